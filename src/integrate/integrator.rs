//! The [`Integrator`] trait: what a time integrator tells the simulation once
//! ([`Capabilities`]) and what each step reports back ([`StepReport`]).
//!
//! The simulation does not ask a method which contact terms it implements through hooks; it
//! reads the capabilities once, hands the step its constraints, and takes the step's feedback
//! (constraint impulses, contact spring forces) from the report, whose buffers it keeps across
//! steps so that no step allocates.

use super::dynamics::Dynamics;
use crate::effects::EffectSet;
use crate::Vec3;

/// What an integrator is, as the simulation needs to know before stepping with it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capabilities {
    /// Largest stable `h * omega` for an undamped oscillator (`None`: unconditionally stable,
    /// e.g. implicit Euler; `Some(0.0)`: stable for no step, forward Euler).
    pub stability_limit: Option<f64>,
    /// The step applies [`super::Constraints::friction`] itself (implicit: as a drag inside the
    /// solve, see [`super::Friction`]); otherwise friction stays with the collision stage.
    pub solves_friction: bool,
    /// The step applies [`super::Constraints::contacts`] itself (implicit: as one-sided springs
    /// inside the solve, see [`super::ContactSpring`]); otherwise they stay with the collision
    /// stage.
    pub solves_contacts: bool,
}

impl Capabilities {
    /// An explicit method with stability limit `h omega <= limit` and no contact terms.
    pub fn explicit(limit: f64) -> Self {
        Self {
            stability_limit: Some(limit),
            solves_friction: false,
            solves_contacts: false,
        }
    }
}

/// What one integrator step did. The caller owns it and passes the same report to every step:
/// the step overwrites every field, and the vectors keep their capacity across steps.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepReport {
    pub force_evaluations: u32,
    pub cg_iterations: u32,
    /// Relative residual the conjugate gradient reached (implicit only; 0 otherwise).
    pub cg_residual: f64,
    /// Wall time of the conjugate-gradient iterations (s), and their floating-point operations
    /// and least bytes streamed (summed over the iterations; see the solver's cost model), so
    /// that time per iteration can be set against the memory-bandwidth bound.
    pub cg_time_s: f64,
    pub cg_flops: f64,
    pub cg_bytes: f64,
    /// The linear path the implicit step ran (`None` for a method without linear solves).
    pub linear_path: Option<super::LinearPath>,
    /// Wall time (s) preparing the linear solves' `M^-1`: the Cholesky factorisations on the
    /// direct path, the multigrid hierarchy's builds and updates on PCG.
    pub setup_time_s: f64,
    /// Wall time (s) assembling the linearised systems (Jacobians, drags, contact springs).
    pub assembly_time_s: f64,
    /// Numeric Cholesky factorisations and symbolic analyses (the direct path).
    pub factorisations: u32,
    pub analyses: u32,
    /// The impulse (N s) each vertex received from its constraint filter during the step,
    /// `(I - S)(M dv - h f)`, when the method knows it (implicit: from the system it solved, so
    /// it holds no linearisation error); empty otherwise. Entries of free vertices are zero.
    pub constraint_impulses: Vec<Vec3>,
    /// The normal force (N) each of [`super::Constraints::contacts`] exerted at the end of the
    /// step, in their order (empty when the method does not solve them).
    pub contact_forces: Vec<f64>,
    /// The force (N) each in-solve friction drag rubbing on a moving surface exerted at the end
    /// of the step, `(vertex, force)`: the surface's work on the cloth, from outside like a held
    /// vertex's constraint impulse at a moving surface (empty when none).
    pub moving_friction: Vec<(u32, Vec3)>,
}

impl StepReport {
    /// Reports a step that evaluated the forces `force_evaluations` times and knows neither
    /// constraint impulses nor contact forces (the explicit methods).
    pub fn explicit(&mut self, force_evaluations: u32) {
        self.force_evaluations = force_evaluations;
        self.cg_iterations = 0;
        self.cg_residual = 0.0;
        self.cg_time_s = 0.0;
        self.cg_flops = 0.0;
        self.cg_bytes = 0.0;
        self.linear_path = None;
        self.setup_time_s = 0.0;
        self.assembly_time_s = 0.0;
        self.factorisations = 0;
        self.analyses = 0;
        self.constraint_impulses.clear();
        self.contact_forces.clear();
        self.moving_friction.clear();
    }

    /// [`StepReport::constraint_impulses`], `None` when the method did not report them.
    pub fn impulses(&self) -> Option<&[Vec3]> {
        (!self.constraint_impulses.is_empty()).then_some(self.constraint_impulses.as_slice())
    }
}

/// Advances `(x, v)` from `t` to `t + h`. Kinematic vertices arrive with their velocity already
/// set to the constant velocity that carries them to their end-of-step target.
pub trait Integrator: Send {
    fn name(&self) -> &'static str;

    /// What the method is (asked once, when the simulation is built).
    fn capabilities(&self) -> Capabilities;

    /// Called once when the simulation is built (and again if the effects change).
    fn prepare(&mut self, _effects: &EffectSet, _n: usize) {}

    /// Changes the linear solver's settings from the next step on (the node's adaptive
    /// quality). Returns false, changing nothing, for a method without a linear solver.
    fn set_solver_settings(&mut self, _settings: super::ImplicitSettings) -> bool {
        false
    }

    /// Advances `(x, v)` in place and fills `report`.
    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    );

    /// [`Integrator::step`] out of place: advances `(x0, v0)` and writes the result to `(x, v)`
    /// (same lengths; every entry is overwritten). The simulation keeps the start state for the
    /// divergence guard's rollback this way without copying it. Default: copy, then step in place.
    #[allow(clippy::too_many_arguments)]
    fn step_into(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        (x0, v0): (&[Vec3], &[Vec3]),
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    ) {
        x.copy_from_slice(x0);
        v.copy_from_slice(v0);
        self.step(d, t, h, x, v, report)
    }
}
