//! Garments: flat 2D patterns meshed with their grain, placed around the body, sewn along seams
//! without gravity, welded into one mesh and then simulated like any cloth.
//!
//! Stages: [`pattern`] validates outlines and seams, [`mesh`] resamples seams and meshes each
//! panel, [`placement`] puts panels in the world, [`seam`] pairs seam vertices and holds the
//! sewing springs, [`sew`] runs the sewing schedule, welds, attaches to links and hands the
//! simulation back at t = 0, [`weld`] merges seam pairs and rebuilds springs and bending across
//! the seams; [`spec`] is the `garments:` section of a scene file.
//!
//! Dressing happens while a scene is built, with the robot in its t = 0 pose, so a recording or
//! the live node only ever sees the welded garments.

mod crossing;
pub mod error;
pub mod mesh;
pub mod pattern;
pub mod placement;
pub mod seam;
pub mod sew;
pub mod spec;
pub mod weld;

pub use error::{GarmentError, MeshProblem, OutlineProblem, SharedStageError};
pub use mesh::{mesh_garment, GarmentMesh, PanelMesh, MIN_ANGLE_DEG};
pub use sew::{dress, sew, SewReport};
pub use spec::{
    GarmentAttachSpec, GarmentSpec, PanelSpec, PlacementSpec, SeamSide, SeamSpec, SewingSpec,
    WrapSpec,
};
pub use weld::{weld, Welded};
