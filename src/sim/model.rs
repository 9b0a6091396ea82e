//! What the scene fixes for a run (the model) and the scratch buffers of a step (work), kept
//! apart from what evolves (the cloth's state, frames, clock, guard and coupling state), as
//! MuJoCo keeps `mjModel` apart from `mjData`.

use super::guard::GuardSettings;
use super::limit::StrainLimit;
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
/// masses alone.
pub(super) struct Model {
    pub effects: EffectSet,
    /// What the integrator is (asked once, at construction).
    pub caps: Capabilities,
    /// Upper bound of the cloth's highest angular frequency (rad/s), computed on first use.
    omega_bound: Option<f64>,
    /// The materials' strain limit (`None` when no material sets one).
    pub limit: Option<StrainLimit>,
}

impl Model {
    pub fn new(effects: EffectSet, caps: Capabilities, cloth: &Cloth) -> Self {
        Self {
            effects,
            caps,
            omega_bound: None,
            limit: StrainLimit::of(cloth),
        }
    }

    /// Bound on the cloth's highest angular frequency (rad/s): the square root of the sum over
    /// elastic effects of their Gershgorin bounds on `omega^2`, for the masses `mass`.
    pub fn omega_bound(&mut self, mass: &[f64]) -> f64 {
        let effects = &self.effects;
        *self.omega_bound.get_or_insert_with(|| {
            let sum: f64 = effects.stiffness(mass).iter().map(|b| b.omega_sq).sum();
            sum.sqrt()
        })
    }
}

/// Scratch buffers of a substep (any content is overwritten before it is read).
#[derive(Debug, Default)]
pub(super) struct Work {
    /// The substep's start state, kept for the guard's rollback (swapped, not copied).
    pub x_save: Vec<Vec3>,
    pub v_save: Vec<Vec3>,
    /// Forces at some state (start, end), for the coupling and the guard.
    pub scratch_f: Vec<Vec3>,
    /// Forces from outside the cloth (wind, driven vertices) at the start of the substep.
    pub fext: Vec<Vec3>,
    /// Inverse masses for the collision stage (0 for kinematic vertices).
    pub inv_mass: Vec<f64>,
    /// The integrator's report of the last solve (its buffers reused across steps).
    pub report: StepReport,
    /// The vertices near a moving obstacle, for fast contact's test (see `fast::outruns`).
    pub near: Vec<(usize, f64, f64)>,
}
