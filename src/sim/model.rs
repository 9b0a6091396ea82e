//! What the scene fixes for a run (the model) and the scratch buffers of a step (work), kept
//! apart from what evolves (the cloth's state, frames, clock, guard and coupling state), as
//! MuJoCo keeps `mjModel` apart from `mjData`.

use super::guard::{GuardSettings, OutsideForces, Saved};
use super::limit::{ResponseBound, StrainLimit, Tethers};
use crate::cloth::Cloth;
use crate::effects::EffectSet;
use crate::integrate::{Capabilities, StepReport};
use crate::Vec3;

/// Time stepping settings of a simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSettings {
    /// Frame step (s): one call to [`super::Simulation::step`].
    pub dt: f64,
    pub substeps: u32,
    pub guard: GuardSettings,
}

impl StepSettings {
    /// The scene's substep `dt / substeps` (the guard may split it further).
    pub fn substep(&self) -> f64 {
        self.dt / f64::from(self.substeps.max(1))
    }
}

/// The forces a scene named, what the integrator is, and what follows from them and the
/// masses alone; stepping never changes it.
pub(super) struct Model {
    pub effects: EffectSet,
    /// What the integrator is (asked once, at construction).
    pub caps: Capabilities,
    /// Upper bound of the cloth's highest angular frequency (rad/s): the square root of the sum
    /// over elastic effects of their Gershgorin bounds on `omega^2`. Only for an integrator with
    /// a stability limit (the guard splits a substep over it up front), so an implicit scene
    /// does not pay for it.
    pub omega_bound: Option<f64>,
    /// The materials' strain limit (`None` when no material sets one).
    pub limit: Option<StrainLimit>,
    /// The bound the collision pass's answers are held to (`None` when no material sets a
    /// strain limit or a knee).
    pub response_bound: Option<ResponseBound>,
}

impl Model {
    pub fn new(effects: EffectSet, caps: Capabilities, cloth: &Cloth) -> Self {
        let omega_bound = (caps.stability_limit.is_some_and(|l| l > 0.0)).then(|| {
            let sum: f64 = effects
                .stiffness(&cloth.mass)
                .iter()
                .map(|b| b.omega_sq)
                .sum();
            sum.sqrt()
        });
        Self {
            effects,
            caps,
            omega_bound,
            limit: StrainLimit::of(cloth),
            response_bound: ResponseBound::of(cloth),
        }
    }

    /// The integrator's stability limit on `h omega` with the cloth's frequency bound, where
    /// it has one.
    pub fn stability(&self) -> Option<(f64, f64)> {
        self.caps.stability_limit.zip(self.omega_bound)
    }
}

/// What a substep keeps beside the state: its start state, the guard's saves for a rollback,
/// caches that depend on the state (rebuilt when what they depend on changes) and scratch
/// buffers (overwritten before they are read).
#[derive(Debug, Default)]
pub(super) struct Work {
    /// The substep's start state: the integrator starts from it, the collision pass sweeps from
    /// it, the guard rolls back to it (swapped out of the cloth, not copied).
    pub x_start: Vec<Vec3>,
    pub v_start: Vec<Vec3>,
    /// What a rollback after the collision pass needs (saved where the strain check applies).
    pub saved: Saved,
    /// The strain limit's tethers for the current set of kinematic vertices (a cache).
    pub tethers: Tethers,
    /// Scratch: forces at some state (start, end), for the coupling and the guard.
    pub scratch_f: Vec<Vec3>,
    /// Forces from outside the cloth over the substep (wind, driven vertices, moving contacts),
    /// for the guard's energy check.
    pub outside: OutsideForces,
    /// Scratch: inverse masses for the strain limit and the collision stage (0 for kinematic
    /// vertices).
    pub inv_mass: Vec<f64>,
    /// The integrator's report of the last solve (its buffers reused across steps).
    pub report: StepReport,
    /// Scratch: the vertices near a moving obstacle, for fast contact's test (see
    /// `fast::outruns`).
    pub near: Vec<(usize, f64, f64)>,
    /// Scratch: the positions the collision pass started from, where its answers are held to
    /// a bound (see `ResponseBound::hold_response`).
    pub pre_collision: Vec<Vec3>,
    /// The obstacles' inside tests, for held vertices driven into a solid (a cache, built at
    /// the first step with kinematic vertices and a collision stage).
    pub solids: Option<crate::collide::Solids>,
}
