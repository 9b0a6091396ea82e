//! The scene file: the single description of a run, used alike by `drape record`, the live node,
//! the benchmarks and the study. YAML, parsed with serde; unknown keys are errors.
//!
//! ```yaml
//! effects: [gravity, stretch, shear, bending, damping]   # only these are built
//! solver: { integrator: implicit, dt: 0.0166667 }
//! cloths:
//!   - name: towel
//!     grid: { size: [1.0, 1.0], resolution: [32, 32], pose: { xyz: [0, 0, 1] } }
//!     pins: [ { region: top_left }, { region: top_right } ]
//! ```

mod build;
mod error;
pub mod lint;
mod problem;
mod textile;
mod validate;

pub use error::{NameKind, SceneError};
pub use problem::{Problem, MAX_VERTICES, MIN_EDGE_LENGTH};

pub use build::{build, build_with_robot};
pub use lint::{lint, Warning, WarningKind};

use crate::cloth::{GridRegion, Material};
use crate::collide::{CollisionSpec, ObstacleSpec};
/// An effect a scene can ask for (the effect plan's term, see [`crate::effects::EffectKind`]).
pub use crate::effects::EffectKind;
use crate::effects::{Gust, WindKey};
use crate::integrate::{ImplicitSettings, IntegratorKind, LinearSolver};
use crate::sim::GuardSettings;
use crate::{Pose, Vec3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use crate::collide::PoseSpec;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    pub integrator: IntegratorKind,
    /// Frame step (s).
    pub dt: f64,
    #[serde(default = "one")]
    pub substeps: u32,
    #[serde(default = "ImplicitSettings::default_tolerance")]
    pub cg_tolerance: f64,
    #[serde(default = "ImplicitSettings::default_iterations")]
    pub cg_max_iterations: u32,
    /// Implicit: a spring's stretch beyond its linearisation's prediction, over its rest length,
    /// above which Newton iterations follow the solve.
    #[serde(default = "ImplicitSettings::default_linearisation")]
    pub linearisation_tolerance: f64,
    /// Implicit: how the linear systems are solved (`auto`, `pcg` or `direct`).
    #[serde(default)]
    pub linear: LinearSolver,
    #[serde(default)]
    pub guard: GuardSettings,
}

fn one() -> u32 {
    1
}

impl ImplicitSettings {
    fn default_tolerance() -> f64 {
        ImplicitSettings::default().cg_tolerance
    }
    fn default_iterations() -> u32 {
        ImplicitSettings::default().cg_max_iterations
    }
    fn default_linearisation() -> f64 {
        ImplicitSettings::default().linearisation_tolerance
    }
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            integrator: IntegratorKind::Implicit,
            dt: 1.0 / 60.0,
            substeps: 1,
            cg_tolerance: ImplicitSettings::default().cg_tolerance,
            cg_max_iterations: ImplicitSettings::default().cg_max_iterations,
            linearisation_tolerance: ImplicitSettings::default().linearisation_tolerance,
            linear: LinearSolver::Pcg,
            guard: GuardSettings::default(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindSpec {
    /// Constant wind velocity (m/s).
    #[serde(default)]
    pub velocity: Vec3,
    /// Scripted offsets over time, interpolated linearly.
    #[serde(default)]
    pub keys: Vec<WindKey>,
    #[serde(default)]
    pub gusts: Vec<Gust>,
    #[serde(default = "air_density")]
    pub air_density: f64,
    #[serde(default = "one_f")]
    pub drag_coefficient: f64,
}

fn air_density() -> f64 {
    1.2
}
fn one_f() -> f64 {
    1.0
}

/// A rectangular grid of cloth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Extent along warp (u) and weft (v), metres.
    pub size: [f64; 2],
    /// Vertices along u and v.
    pub resolution: [usize; 2],
    /// Where the grid's centre sits; the grid spans the local x (u) - y (v) plane.
    #[serde(default)]
    pub pose: PoseSpec,
}

/// A set of vertices of one cloth. Exactly one of the fields is given, e.g. `{ region: top_left }`,
/// `{ vertices: [0, 5] }` or `{ near: { point: [0, 0, 1], radius: 0.05 } }`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Selection {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<GridRegion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<Near>,
}

/// Vertices within `radius` of `point` (world frame, at the initial placement).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Near {
    pub point: [f64; 3],
    pub radius: f64,
}

/// Vertices attached to a moving frame: `{ frame: handle, region: top_left }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttachSpec {
    /// Name of a frame in the scene's `frames`.
    pub frame: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<GridRegion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<Near>,
}

impl AttachSpec {
    pub fn selection(&self) -> Selection {
        Selection {
            vertex: self.vertex,
            vertices: self.vertices.clone(),
            region: self.region,
            near: self.near,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothSpec {
    pub name: String,
    pub grid: GridSpec,
    #[serde(default)]
    pub material: Material,
    #[serde(default)]
    pub pins: Vec<Selection>,
    #[serde(default)]
    pub attach: Vec<AttachSpec>,
}

/// A named moving frame that cloth can attach to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameSpec {
    pub name: String,
    #[serde(default)]
    pub pose: PoseSpec,
    /// Constant linear velocity (m/s) of the frame's origin.
    #[serde(default)]
    pub linear_velocity: [f64; 3],
    /// Constant angular velocity (rad/s) about the frame's origin, world axes.
    #[serde(default)]
    pub angular_velocity: [f64; 3],
}

impl FrameSpec {
    pub fn pose_at(&self, t: f64) -> Pose {
        let p0 = self.pose.to_pose();
        let w = Vec3::from(self.angular_velocity) * t;
        let rot = glam::DQuat::from_scaled_axis(w) * p0.rotation;
        Pose::new(
            p0.translation + Vec3::from(self.linear_velocity) * t,
            rot.normalize(),
        )
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    #[serde(default)]
    pub name: String,
    /// Default run length for `drape record` (s).
    #[serde(default = "duration")]
    pub duration: f64,
    /// Output rate of meshes (Hz).
    #[serde(default = "publish_rate")]
    pub publish_rate: f64,
    #[serde(default = "gravity")]
    pub gravity: [f64; 3],
    pub effects: Vec<EffectKind>,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub wind: Option<WindSpec>,
    #[serde(default)]
    pub frames: Vec<FrameSpec>,
    #[serde(default)]
    pub cloths: Vec<ClothSpec>,
    /// Garments sewn from flat patterns around the body before the run (see `crate::garment`).
    #[serde(default)]
    pub garments: Vec<crate::garment::GarmentSpec>,
    /// Rigid obstacles (scripted or robot-driven).
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// A robot from URDF: its links become external obstacles, cloth can attach to links.
    #[serde(default)]
    pub robot: Option<RobotSpec>,
    /// Collision detection and response; without obstacles and self-collision no collision
    /// structure is built at all.
    #[serde(default)]
    pub collision: CollisionSpec,
    /// Folder relative mesh paths are resolved against (the scene file's folder).
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
    /// URDF text to use instead of reading `robot.urdf` (e.g. from `/robot_description`);
    /// meshes are still resolved against `robot.urdf`'s folder.
    #[serde(skip)]
    pub robot_urdf_text: Option<String>,
    /// Where the scene came from (its file), for errors; set by [`Scene::from_yaml`].
    #[serde(skip)]
    pub origin: String,
    /// Extra folders (relative to the scene's folder, or absolute) mesh files may be read from,
    /// besides the scene's folder and the URDF's package. Every mesh reference (`package://`,
    /// `file://`, relative, through symlinks) must resolve inside one of them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mesh_paths: Vec<PathBuf>,
    /// Folders searched for the URDF's `package://` meshes besides `ROS_PACKAGE_PATH` and
    /// `AMENT_PREFIX_PATH` (a package, or a folder of packages): the command line's
    /// `--package-path`, not a key of the file.
    #[serde(skip)]
    pub package_paths: Vec<PathBuf>,
}

/// `robot: { urdf: bot.urdf, trajectory: {names, points}, visual_fallback, attach: [..] }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// URDF file, relative to the scene file. Its root link is the world frame of the scene.
    pub urdf: String,
    /// Scripted joint motion; without it the robot holds its zero configuration.
    #[serde(default)]
    pub trajectory: Option<crate::robot::JointTrajectory>,
    /// Use a link's visual geometry when it has no collision element.
    #[serde(default)]
    pub visual_fallback: bool,
    #[serde(default)]
    pub attach: Vec<RobotAttachSpec>,
    /// Grasp rules: cloth between a gripper's pads is held while its fingers are closed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grasps: Vec<RobotGraspSpec>,
}

/// `{ link: right_palm, fingers: [right_finger_a_joint], close_below: 0.012, open_above: 0.02,
/// pads: { xyz: [0, 0, -0.13], half_extents: [0.012, 0.03, 0.015] } }`: when the largest finger
/// joint position drops below `close_below`, the free vertices of `cloth` (all cloths if
/// omitted) inside the pad box (link frame) are attached to `link`; above `open_above` they are
/// released with the link's velocity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotGraspSpec {
    pub link: String,
    pub fingers: Vec<String>,
    pub close_below: f64,
    pub open_above: f64,
    pub pads: PadSpec,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cloth: Option<String>,
}

/// A box in a link frame: centre pose and half extents (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PadSpec {
    #[serde(default)]
    pub xyz: [f64; 3],
    #[serde(default)]
    pub rpy: [f64; 3],
    pub half_extents: [f64; 3],
}

/// Cloth vertices held by a link, keeping their offset: `{ cloth: towel, link: hand,
/// region: top_left }`. `near.point` is in the **link** frame (at t = 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotAttachSpec {
    pub cloth: String,
    pub link: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<GridRegion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<Near>,
}

impl RobotAttachSpec {
    /// The selection with `near` still in the link frame.
    pub fn selection(&self) -> Selection {
        Selection {
            vertex: self.vertex,
            vertices: self.vertices.clone(),
            region: self.region,
            near: self.near,
        }
    }
}

fn duration() -> f64 {
    5.0
}
fn publish_rate() -> f64 {
    30.0
}
fn gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

impl Scene {
    /// Parses and validates a scene from YAML text; `origin` names it in errors (the file
    /// path when loaded with [`Scene::load`]). A leading byte-order mark is ignored.
    pub fn from_yaml(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let text = crate::input::strip_bom(text);
        crate::input::check_yaml_depth(text).map_err(|line| SceneError::TooDeep {
            origin: origin.to_string(),
            line,
            max: crate::input::MAX_YAML_DEPTH,
        })?;
        let mut scene: Scene =
            serde_yaml_ng::from_str(text).map_err(|source| SceneError::Parse {
                origin: origin.to_string(),
                source,
            })?;
        scene.origin = origin.to_string();
        let value_error = |(key, problem)| SceneError::Value {
            origin: origin.to_string(),
            key,
            problem: Box::new(problem),
        };
        Scene::check_textile_keys(text).map_err(value_error)?;
        scene.resolve_textile().map_err(value_error)?;
        scene.validate().map_err(value_error)?;
        Ok(scene)
    }

    /// Reads a scene file through [`crate::input`] (a regular file, at most
    /// [`crate::input::InputKind::Scene`]'s cap) and validates it.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = crate::input::read_text(path, crate::input::InputKind::Scene)?;
        let mut scene = Self::from_yaml(&text, &path.display().to_string())?;
        scene.base_dir = path.parent().map(|d| {
            if d.as_os_str().is_empty() {
                Path::new(".").to_path_buf()
            } else {
                d.to_path_buf()
            }
        });
        Ok(scene)
    }

    /// Where this scene came from, for errors: its file, or the origin given to `from_yaml`.
    pub fn origin(&self) -> &str {
        if self.origin.is_empty() {
            "<scene>"
        } else {
            &self.origin
        }
    }

    /// Folders mesh files may come from besides the URDF's package: the scene's folder and the
    /// scene's `mesh_paths` (relative to the scene's folder).
    pub fn mesh_roots(&self) -> Vec<PathBuf> {
        let base = self.base_dir.clone().unwrap_or_else(|| PathBuf::from("."));
        let mut roots = vec![base.clone()];
        roots.extend(self.mesh_paths.iter().map(|p| base.join(p)));
        roots
    }

    /// Whether this scene needs a collision stage at all.
    pub fn needs_collision(&self) -> bool {
        !self.obstacles.is_empty() || self.collision.self_collision || self.robot.is_some()
    }

    pub fn has(&self, e: EffectKind) -> bool {
        self.effects.contains(&e)
    }
}
