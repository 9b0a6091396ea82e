//! The hard-case catalogue: scenes at the edges of what the simulator promises (stiff, tiny, huge,
//! fast, pinched, crumpled, degenerate, windy, long), each with explicit pass criteria, and a runner
//! that records the worst values every step. `tests/hard_cases.rs` and `drape dev hard-cases` share it,
//! so the committed summary (`docs/hard_cases.md`) is what the tests check.

mod cases;
mod edge;
mod fast_links;
mod hanging;
mod motion;
mod real_robots;
mod report;
mod runner;
mod self_contact;
mod setup;

pub use cases::{catalogue, CaseFn};
pub use report::markdown;
pub use runner::{run_case, Outcome, Worst};

use crate::robot::RobotDriver;
use crate::sim::Simulation;

/// How fine a case is run: `Ci` keeps the whole catalogue to well under a minute of wall time;
/// `Full` is the resolution and duration the case is named for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resolution {
    Ci,
    Full,
}

/// How the energy of a case is judged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EnergyCheck {
    /// `E(t) <= E(0) + W_ext(t) + margin * scale`, with `W_ext` the work of wind and of driven
    /// (pinned/attached) vertices, integrated by the trapezoid rule per frame; `scale` is the
    /// larger of the peak dynamic energy (kinetic + elastic) over the run and the gravity scale
    /// `M g L` (cloth mass, gravity, initial cloth size).
    Bounded { margin: f64 },
    /// Obstacles push the cloth and their work is not observable from outside the collision
    /// stage: the excess is reported but the bound is on speed instead (see
    /// [`Criteria::max_speed`]).
    NotMeasured,
}

/// Explicit pass criteria of a case; `None` means "not judged" (the value is still reported).
#[derive(Debug, Clone, PartialEq)]
pub struct Criteria {
    /// Largest |x| any vertex may reach (m).
    pub max_abs_x: f64,
    /// Largest vertex speed (m/s).
    pub max_speed: f64,
    pub energy: EnergyCheck,
    /// Deepest penetration into an obstacle's thickness layer (m).
    pub max_penetration: Option<f64>,
    /// Largest edge length over its rest length at any frame end (a bound the case derives
    /// from its material and speeds, e.g. `1 + v / c` for an impact at `v`).
    pub max_stretch: Option<f64>,
    /// Depth of the deepest free cloth vertex inside an obstacle at a frame end (m), judged
    /// independently of the contact stage (which has no inside test for mesh links): parry's
    /// projection for primitives, the generalised winding number for meshes.
    pub max_inside_solid: Option<f64>,
    /// Intersecting non-adjacent triangle pairs at the end of any step.
    pub max_self_intersections: Option<usize>,
    /// Distance of a pinned/attached vertex from its target after a step (m).
    pub max_attached_drift: f64,
    /// Energy creep of a long periodic run: relative change of the mean energy between the
    /// second and the last tenth of the run.
    pub max_energy_creep: Option<f64>,
    /// Frames after which the energy reference `E(0)` is taken (0: the initial state). A case that
    /// starts infeasible (cloth inside an obstacle) pays the lead-out of it once: the reference
    /// is then the first frame from this one on that ends with no vertex on its way out.
    pub energy_from_frame: usize,
    /// Whether the guard must subdivide at least once (the case is built to need it).
    pub expect_subdivisions: bool,
}

impl Criteria {
    /// Defaults every case starts from: finite, no drift, energy bounded with a 5 % margin.
    pub fn base(max_abs_x: f64, max_speed: f64) -> Self {
        Self {
            max_abs_x,
            max_speed,
            energy: EnergyCheck::Bounded { margin: 0.05 },
            max_penetration: None,
            max_stretch: None,
            max_inside_solid: None,
            max_self_intersections: None,
            // Kinematic vertices are reset onto their targets every substep: only round-off remains.
            max_attached_drift: 1e-9,
            max_energy_creep: None,
            energy_from_frame: 0,
            expect_subdivisions: false,
        }
    }
}

/// One runnable hard case.
pub struct Case {
    pub name: &'static str,
    /// What the case does, one sentence.
    pub description: String,
    pub sim: Simulation,
    pub driver: Option<RobotDriver>,
    /// Simulated seconds.
    pub duration: f64,
    pub criteria: Criteria,
}

/// A case that could not be built (a bundled file missing, a scene the parser rejects).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HardError {
    #[error("hard case {case}")]
    Scene {
        case: &'static str,
        #[source]
        source: crate::scene::SceneError,
    },
    /// The case's hand-made panel was rejected by the cloth (its message).
    #[error("hard case {case}: panel rejected: {message}")]
    Panel { case: &'static str, message: String },
    /// Data the case needs is not on this machine (pybullet_data's robots).
    #[error("hard case {case}: {message}")]
    MissingData { case: &'static str, message: String },
    #[error("hard case {case}: no elastic effect to take the stability limit from")]
    NoElasticEffect { case: &'static str },
}
