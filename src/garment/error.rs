//! What can go wrong with a garment, from its pattern to its sewing: [`GarmentError`], each
//! variant naming the garment, panel or seam at fault and carrying the values, with the cause
//! (a divergence, a collision-stage error) as its `source()`.

use super::spec::{GarmentSpec, SeamSide};
use crate::collide::StageError;
use crate::sim::DivergenceError;
use std::sync::Arc;

/// A pattern, seam or sewing problem, naming the garment, panel or seam at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GarmentError {
    #[error("garment '{garment}': has no panels")]
    NoPanels { garment: String },
    #[error(
        "garment '{garment}': edge_length {edge_length:e} m must be finite and at least {min:e} m"
    )]
    EdgeLength {
        garment: String,
        edge_length: f64,
        min: f64,
    },
    /// The material's density gives a vertex mass that is zero or subnormal.
    #[error("garment '{garment}': material.density gives each vertex a mass of {mass:.3e} kg, too small to simulate")]
    MassTooSmall { garment: String, mass: f64 },
    #[error("garment '{garment}': two panels are named '{panel}'")]
    DuplicatePanel { garment: String, panel: String },
    #[error("garment '{garment}': two seams are named '{seam}'")]
    DuplicateSeam { garment: String, seam: String },
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
    #[error("garment '{garment}': sewn through itself: {pairs} pairs of triangles cross after welding, the first (triangles {triangles:?}, at {at:?} m) {}", crossing_place(.seam))]
    WeldedCrossing {
        garment: String,
        /// The seam nearest the first crossing, if within a few edge lengths of it.
        seam: Option<String>,
        pairs: usize,
        triangles: (u32, u32),
        at: [f32; 3],
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
    #[error("seam '{seam}': sides are {} and {} long, more than {}% apart", Length(*a), Length(*b), max_mismatch * 100.0)]
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
    #[error("garment '{garment}': seam '{seam}': a side was not resampled")]
    NotResampled { garment: String, seam: String },
    #[error("garment '{garment}': panel '{panel}': meshing failed: {problem}")]
    Mesh {
        garment: String,
        panel: String,
        problem: MeshProblem,
    },
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
    #[error("garment '{garment}': seam '{seam}' still has a {} gap after {time:.2} s (tolerance {})", Length(*gap), Length(*tolerance))]
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

/// A length in metres printed with three decimals in the unit that keeps it readable (m, mm or
/// µm; scientific below a micrometre), so a small gap never prints as zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Length(pub f64);

impl std::fmt::Display for Length {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        let a = v.abs();
        if !v.is_finite() || a == 0.0 {
            write!(f, "{v} m")
        } else if a >= 1.0 {
            write!(f, "{v:.3} m")
        } else if a >= 1e-3 {
            write!(f, "{:.3} mm", v * 1e3)
        } else if a >= 1e-6 {
            write!(f, "{:.3} µm", v * 1e6)
        } else {
            write!(f, "{v:.3e} m")
        }
    }
}

impl GarmentError {
    /// The garment at fault, for errors that concern one garment (not a sewing of several).
    /// Pattern errors name only their panel or seam: [`GarmentError::key_in`] takes the garment.
    pub fn garment(&self) -> Option<&str> {
        use GarmentError::*;
        match self {
            NoPanels { garment }
            | EdgeLength { garment, .. }
            | MassTooSmall { garment, .. }
            | DuplicatePanel { garment, .. }
            | DuplicateSeam { garment, .. }
            | Value { garment, .. }
            | MaxTime { garment, .. }
            | AttachShape { garment, .. }
            | AttachNeedsRobot { garment, .. }
            | AttachLink { garment, .. }
            | AttachSelectsNothing { garment, .. }
            | WeldCollapse { garment, .. }
            | WeldedCrossing { garment, .. }
            | NotResampled { garment, .. }
            | Mesh { garment, .. }
            | SeamOpen { garment, .. } => Some(garment),
            _ => None,
        }
    }

    /// The key, within garment `g`'s section of a scene file, of the value at fault
    /// (`panels[1].outline`, `seams[0].b.to`, `sewing.max_time`); empty when the error concerns
    /// the garment as a whole. Panels and seams are found by name (unique in a valid garment).
    pub fn key_in(&self, g: &GarmentSpec) -> String {
        use GarmentError::*;
        let panel = |name: &str| {
            g.panels
                .iter()
                .rposition(|p| p.name == name)
                .map_or_else(|| "panels".to_string(), |k| format!("panels[{k}]"))
        };
        let seam = |name: &str| g.seams.iter().rposition(|s| s.name == name);
        // The side of seam `name` that names `panel` (and `index`, if given): `seams[s].a`.
        let side = |name: &str, panel: &str, index: Option<usize>| {
            let Some(k) = seam(name) else {
                return "seams".to_string();
            };
            let s = &g.seams[k];
            let fits =
                |x: &SeamSide| x.panel == panel && index.is_none_or(|i| x.from == i || x.to == i);
            let (letter, x) = if fits(&s.a) || !fits(&s.b) {
                ("a", &s.a)
            } else {
                ("b", &s.b)
            };
            match index {
                Some(i) if x.from == i => format!("seams[{k}].{letter}.from"),
                Some(_) => format!("seams[{k}].{letter}.to"),
                None => format!("seams[{k}].{letter}"),
            }
        };
        let whole_seam =
            |name: &str| seam(name).map_or_else(|| "seams".to_string(), |k| format!("seams[{k}]"));
        match self {
            NoPanels { .. } => "panels".into(),
            EdgeLength { .. } | WeldCollapse { .. } => "edge_length".into(),
            MassTooSmall { .. } => "material.density".into(),
            DuplicatePanel { panel: p, .. } => format!("{}.name", panel(p)),
            DuplicateSeam { seam: s, .. } => format!("{}.name", whole_seam(s)),
            Value { key, .. } => (*key).into(),
            MaxTime { .. } => "sewing.max_time".into(),
            AttachShape { index, .. }
            | AttachNeedsRobot { index, .. }
            | AttachSelectsNothing { index, .. } => format!("attach[{index}]"),
            AttachLink { index, .. } => format!("attach[{index}].link"),
            Outline { panel: p, problem } => match problem {
                OutlineProblem::NonFinitePlacement => format!("{}.placement", panel(p)),
                OutlineProblem::WrapRadius { .. } => {
                    format!("{}.placement.wrap.radius", panel(p))
                }
                _ => format!("{}.outline", panel(p)),
            },
            SelfIntersecting { panel: p, .. } => format!("{}.outline", panel(p)),
            Mesh { panel: p, .. } => panel(p),
            MissingPanel { seam: s, panel: p } => format!("{}.panel", side(s, p, None)),
            SeamIndex {
                seam: s,
                panel: p,
                index,
                ..
            } => side(s, p, Some(*index)),
            EmptySeamSide { seam: s, panel: p }
            | SeamOverlap {
                seam: s, panel: p, ..
            } => side(s, p, None),
            SeamLength { seam: s, .. }
            | NotResampled { seam: s, .. }
            | SeamOpen { seam: s, .. } => whole_seam(s),
            WeldedCrossing { seam: Some(s), .. } => whole_seam(s),
            WeldedCrossing { seam: None, .. } => "panels".into(),
            SewingDiverged { .. } | Cancelled { .. } | Stage { .. } => String::new(),
        }
    }
}

/// What is wrong with a panel's outline or placement.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OutlineProblem {
    #[error("needs at least 3 points, has {count}")]
    TooFewPoints { count: usize },
    #[error("has {count} points, more than the {max} an outline may have")]
    TooManyPoints { count: usize, max: usize },
    #[error("point {point} is not finite")]
    NotFinite { point: usize },
    #[error("points {a} and {b} coincide")]
    Coincident { a: usize, b: usize },
    #[error("encloses no area")]
    ZeroArea,
    /// The estimated vertices of all cloths of the scene up to this panel (meshed at
    /// `edge_length`) pass `limit`.
    #[error(
        "meshed at edge_length {edge_length:e} m, brings the scene's cloth to about {vertices:.0} vertices, more than the {limit} a scene may have (all cloths and garments together)"
    )]
    TooManyVertices {
        vertices: f64,
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

/// Where a welded garment's first crossing is, in words, for [`GarmentError::WeldedCrossing`].
fn crossing_place(seam: &Option<String>) -> String {
    match seam {
        Some(s) => format!(
            "is at seam '{s}': check its sides' order (`reversed`) and the panels' placement"
        ),
        None => "is away from every seam: the panels are placed crossing each other".into(),
    }
}
