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

pub mod mesh;
pub mod pattern;
pub mod placement;
pub mod seam;
pub mod sew;
pub mod spec;
pub mod weld;

pub use mesh::{mesh_garment, GarmentMesh, PanelMesh, MIN_ANGLE_DEG};
pub use sew::{dress, sew, SewReport};
pub use spec::{
    GarmentAttachSpec, GarmentSpec, PanelSpec, PlacementSpec, SeamSide, SeamSpec, SewingSpec,
    WrapSpec,
};
pub use weld::{weld, Welded};

/// A pattern, seam or sewing problem, naming the garment, panel or seam at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GarmentError {
    #[error("garment '{garment}': {reason}")]
    Invalid { garment: String, reason: String },
    #[error("panel '{panel}': outline {reason}")]
    Outline { panel: String, reason: String },
    #[error("panel '{panel}': outline intersects itself (edges {edge_a} and {edge_b})")]
    SelfIntersecting {
        panel: String,
        edge_a: usize,
        edge_b: usize,
    },
    #[error("seam '{seam}': names panel '{panel}', which does not exist")]
    MissingPanel { seam: String, panel: String },
    #[error("seam '{seam}': outline index {index} of panel '{panel}' is out of range (outline has {len} points)")]
    SeamIndex {
        seam: String,
        panel: String,
        index: usize,
        len: usize,
    },
    #[error("seam '{seam}': sides are {a:.3} m and {b:.3} m long, more than {pct}% apart", pct = pattern::MAX_SEAM_MISMATCH * 100.0)]
    SeamLength { seam: String, a: f64, b: f64 },
    #[error("seam '{seam}': {reason}")]
    Seam { seam: String, reason: String },
    #[error("panel '{panel}': meshing failed: {reason}")]
    Mesh { panel: String, reason: String },
    #[error("garment '{garment}': sewing failed: {reason}")]
    Sewing { garment: String, reason: String },
}
