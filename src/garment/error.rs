//! What can go wrong with a garment, from its pattern to its sewing: [`GarmentError`], each
//! variant naming the garment, panel or seam at fault and carrying the values, with the cause
//! (a divergence, a collision-stage error) as its `source()`.

use crate::collide::StageError;
use crate::sim::DivergenceError;
use std::sync::Arc;

/// A pattern, seam or sewing problem, naming the garment, panel or seam at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GarmentError {
    #[error("garment '{garment}': has no panels")]
    NoPanels { garment: String },
    #[error("garment '{garment}': edge_length {edge_length} must be > 0")]
    EdgeLength { garment: String, edge_length: f64 },
    #[error("garment '{garment}': two panels are named '{panel}'")]
    DuplicatePanel { garment: String, panel: String },
    /// A material or sewing value out of range; `strictly`: it must be > 0, else >= 0.
    #[error("garment '{garment}': {key} = {value} must be finite and {}", if *strictly { "> 0" } else { ">= 0" })]
    Value {
        garment: String,
        key: &'static str,
        value: f64,
        strictly: bool,
    },
    #[error("garment '{garment}': sewing.max_time = {max_time} must be finite and > close_time ({close_time})")]
    MaxTime {
        garment: String,
        max_time: f64,
        close_time: f64,
    },
    #[error("garment '{garment}': attach[{index}]: point must be finite and radius > 0")]
    AttachShape { garment: String, index: usize },
    #[error("garment '{garment}': attach[{index}]: needs a robot")]
    AttachNeedsRobot { garment: String, index: usize },
    #[error("garment '{garment}': attach[{index}]: the robot has no link named '{link}'")]
    AttachLink {
        garment: String,
        index: usize,
        link: String,
    },
    #[error("garment '{garment}': attach[{index}]: no garment vertex within {radius} m of {point:?} in link '{link}'")]
    AttachSelectsNothing {
        garment: String,
        index: usize,
        link: String,
        point: [f64; 3],
        radius: f64,
    },
    #[error("garment '{garment}': welding collapses triangle {triangle}: a seam joins two vertices of one triangle (seam too short for edge_length {edge_length})")]
    WeldCollapse {
        garment: String,
        triangle: usize,
        edge_length: f64,
    },
    #[error("panel '{panel}': outline {problem}")]
    Outline {
        panel: String,
        problem: OutlineProblem,
    },
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
    /// The two sides' lengths differ by more than `max_mismatch` (a fraction of the longer).
    #[error("seam '{seam}': sides are {a:.3} m and {b:.3} m long, more than {}% apart", max_mismatch * 100.0)]
    SeamLength {
        seam: String,
        a: f64,
        b: f64,
        max_mismatch: f64,
    },
    #[error("seam '{seam}': stretch of panel '{panel}' is empty (from == to)")]
    EmptySeamSide { seam: String, panel: String },
    #[error("seam '{seam}': edge {edge} of panel '{panel}' is already sewn by seam '{other}'")]
    SeamOverlap {
        seam: String,
        panel: String,
        edge: usize,
        other: String,
    },
    #[error("seam '{seam}': a side was not resampled")]
    NotResampled { seam: String },
    #[error("panel '{panel}': meshing failed: {problem}")]
    Mesh { panel: String, problem: MeshProblem },
    #[error("garments '{garments}': the simulation diverged while sewing")]
    SewingDiverged {
        /// The garments being sewn, comma separated.
        garments: String,
        #[source]
        source: Box<DivergenceError>,
    },
    #[error("garments '{garments}': sewing stopped by a signal")]
    Cancelled {
        /// The garments being sewn, comma separated.
        garments: String,
    },
    #[error("garment '{garment}': seam '{seam}' still has a {:.2} mm gap after {time:.2} s (tolerance {:.2} mm)", gap * 1e3, tolerance * 1e3)]
    SeamOpen {
        garment: String,
        seam: String,
        gap: f64,
        time: f64,
        tolerance: f64,
    },
    #[error("garments '{garments}': the collision stage rejected the cloth")]
    Stage {
        garments: String,
        #[source]
        source: SharedStageError,
    },
}

/// What is wrong with a panel's outline or placement.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OutlineProblem {
    #[error("needs at least 3 points, has {count}")]
    TooFewPoints { count: usize },
    #[error("point {point} is not finite")]
    NotFinite { point: usize },
    #[error("points {a} and {b} coincide")]
    Coincident { a: usize, b: usize },
    #[error("encloses no area")]
    ZeroArea,
    #[error(
        "would mesh into ~{triangles:.0} triangles at edge_length {edge_length} (limit {limit})"
    )]
    TooManyTriangles {
        triangles: f64,
        edge_length: f64,
        limit: usize,
    },
    #[error("has a non-finite placement pose or grain")]
    NonFinitePlacement,
    #[error("wrap radius {radius} must be > 0")]
    WrapRadius { radius: f64 },
}

/// Why meshing a panel failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshProblem {
    #[error("triangulation failed")]
    Triangulation(#[source] spade::InsertionError),
    #[error("resampled boundary has coincident points")]
    CoincidentBoundary,
    #[error("refinement did not converge (outline too detailed for edge_length?)")]
    NoConvergence,
    #[error(
        "worst triangle angle {worst_deg:.1} deg is below {min_deg} deg (sharp outline corner?)"
    )]
    SharpAngle { worst_deg: f64, min_deg: f64 },
    /// The meshed panel was rejected by the cloth (its message).
    #[error("{0}")]
    Panel(String),
}

/// A collision-stage error, shared so that [`GarmentError`] stays `Clone` (equal when it is the
/// same error).
#[derive(Debug, Clone)]
pub struct SharedStageError(pub Arc<StageError>);

impl PartialEq for SharedStageError {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl std::fmt::Display for SharedStageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for SharedStageError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}
