//! Robots from URDF: kinematic tree, forward kinematics, joint inputs, and per-link collision
//! geometry for the collision stage.

pub mod driver;
pub mod grasp;
pub mod joint_input;
pub mod kinematics;
pub mod resolve;
pub mod summary;
pub mod urdf;

pub use driver::{joint_stream, JointSource, RobotDriver};
pub use grasp::{Grasp, GraspError, GraspEvent, Hysteresis, PadBox};
pub use joint_input::{
    apply_free_poses, JointInput, JointInputError, JointTrajectory, Overspeed, TrajectoryError,
    TrajectoryPoint,
};
pub use kinematics::{FkReport, Joint, JointKind, JointPositions, Kinematics, Mimic, TreeError};
pub use resolve::SearchPaths;
pub use summary::RobotSummary;
pub use urdf::{RobotError, UrdfOptions};

use crate::mesh::TriMeshData;
use crate::{Pose, Vec3};
use std::sync::Arc;

/// Collision geometry of a link, in its own frame (see the pose it is paired with).
///
/// Cylinders and capsules follow URDF: their axis is the local **z** axis, centred on the
/// origin, `length` excluding the capsule caps. (parry's are along y; the collision layer
/// converts.)
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    Sphere { radius: f64 },
    Box { half_extents: Vec3 },
    Cylinder { radius: f64, length: f64 },
    Capsule { radius: f64, length: f64 },
    Mesh(Arc<TriMeshData>),
}

/// A loaded robot: kinematics plus collision shapes, link-indexed.
#[derive(Debug, Clone)]
pub struct Robot {
    pub name: String,
    kinematics: Kinematics,
    collision: Vec<Vec<(Pose, Geometry)>>,
    /// Per link: where its shapes came from, or why it has none (what `drape check` shows).
    sources: Vec<ShapeSource>,
    /// Mesh URIs left out because no file was found (only with
    /// [`UrdfOptions::skip_missing_meshes`]).
    missing_meshes: Vec<String>,
}

/// Where a link's collision shapes came from, or why the link is not an obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShapeSource {
    /// Its `<collision>` elements.
    Collision,
    /// Its `<visual>` elements, because it has no `<collision>` and `visual_fallback` is on.
    VisualFallback,
    /// No `<collision>`; it has `<visual>` geometry that `visual_fallback: true` would use.
    SkippedVisualOnly,
    /// Neither `<collision>` nor `<visual>` geometry (a frame link).
    SkippedNoGeometry,
}

impl Robot {
    pub fn kinematics(&self) -> &Kinematics {
        &self.kinematics
    }

    /// Per link (indexed like [`Kinematics::links`]): shapes with their pose in the link frame.
    pub fn collision_shapes(&self) -> &[Vec<(Pose, Geometry)>] {
        &self.collision
    }

    /// Per link (indexed like [`Kinematics::links`]): where its shapes came from.
    pub fn shape_sources(&self) -> &[ShapeSource] {
        &self.sources
    }

    /// Mesh URIs left out because no file was found (see [`UrdfOptions::skip_missing_meshes`]).
    pub fn missing_meshes(&self) -> &[String] {
        &self.missing_meshes
    }

    pub fn link_names(&self) -> &[String] {
        self.kinematics.links()
    }

    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.kinematics.link_index(name)
    }

    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.kinematics.joint_index(name)
    }

    pub fn zero_positions(&self) -> JointPositions {
        self.kinematics.zero_positions()
    }

    /// Link poses in the root link frame. See [`Kinematics::link_poses_into`] for the
    /// allocation-free variant that also reports clamping.
    pub fn link_poses(&self, q: &JointPositions) -> Vec<Pose> {
        self.kinematics.link_poses(q)
    }

    pub fn link_poses_into(&self, q: &JointPositions, out: &mut Vec<Pose>) -> FkReport {
        self.kinematics.link_poses_into(q, out)
    }
}
