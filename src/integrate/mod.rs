//! Time integrators behind one trait: explicit (forward) Euler, symplectic Euler, classic RK4 and
//! implicit backward Euler after Baraff and Witkin ("Large Steps in Cloth Simulation", 1998).
//!
//! Constraints reach every integrator the same way: a per-vertex [`Filter`] (free, one direction
//! constrained, or fixed) and a target velocity for the constrained directions. Explicit methods
//! filter accelerations; the implicit method filters its conjugate-gradient iterates, which is the
//! survey's "mass modification" `(I - p p^T)/m`.

mod contact;
mod explicit;
mod friction;
mod implicit;
mod precond;
mod rk4;
mod sparse;

pub use contact::ContactSpring;
pub use explicit::{Euler, ExplicitEuler, SymplecticEuler};
pub use friction::{Friction, STICK_SPEED};
pub use implicit::{Implicit, ImplicitSettings};
pub use rk4::Rk4;
pub use sparse::{BlockCsr, PairSlots, PatternBuilder};

use crate::effects::{EffectSet, State};
use crate::{Mat3, Vec3};
use serde::{Deserialize, Serialize};

/// How a vertex's velocity is constrained during a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Filter {
    Free,
    /// The component along this unit direction is prescribed (a contact normal); the vertex
    /// moves freely in the plane orthogonal to it.
    Direction(Vec3),
    /// Only the component along this unit direction is free (a vertex held by two contact
    /// surfaces at once slides along their common edge line; both normals are prescribed).
    Line(Vec3),
    /// Fully prescribed (pinned or attached vertices).
    Fixed,
}

impl Filter {
    /// `S a`: removes the constrained components of `a`.
    #[inline]
    pub fn apply(&self, a: Vec3) -> Vec3 {
        match *self {
            Filter::Free => a,
            Filter::Direction(n) => a - n * n.dot(a),
            Filter::Line(e) => e * e.dot(a),
            Filter::Fixed => Vec3::ZERO,
        }
    }

    /// The constrained part `(I - S) a`.
    #[inline]
    pub fn constrained(&self, a: Vec3) -> Vec3 {
        a - self.apply(a)
    }

    pub fn matrix(&self) -> Mat3 {
        match *self {
            Filter::Free => Mat3::IDENTITY,
            Filter::Direction(n) => Mat3::IDENTITY - crate::effects::outer_pub(n, n),
            Filter::Line(e) => crate::effects::outer_pub(e, e),
            Filter::Fixed => Mat3::ZERO,
        }
    }
}

/// Per-vertex constraints of one step.
#[derive(Debug, Clone, Default)]
pub struct Constraints {
    pub filter: Vec<Filter>,
    /// Velocity the constrained components must have at the end of the step.
    pub target_velocity: Vec<Vec3>,
    /// Coulomb friction of held vertices, for integrators that solve it (see
    /// [`Integrator::solves_friction`]); the others leave friction to the collision stage.
    pub friction: Vec<Friction>,
    /// Static obstacle edges and corners against the cloth, for integrators that solve them
    /// (see [`Integrator::solves_contacts`]); the others leave them to the collision stage.
    pub contacts: Vec<ContactSpring>,
}

impl Constraints {
    pub fn free(n: usize) -> Self {
        Self {
            filter: vec![Filter::Free; n],
            target_velocity: vec![Vec3::ZERO; n],
            friction: Vec::new(),
            contacts: Vec::new(),
        }
    }
}

/// Everything an integrator needs to evaluate the dynamics.
pub struct Dynamics<'a> {
    pub effects: &'a EffectSet,
    pub mass: &'a [f64],
    pub constraints: &'a Constraints,
}

impl Dynamics<'_> {
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Filtered accelerations at `(t, x, v)` into `a`, using `f` as scratch for forces.
    pub fn accelerations(&self, t: f64, x: &[Vec3], v: &[Vec3], f: &mut [Vec3], a: &mut [Vec3]) {
        self.effects.forces(&State { t, x, v }, f);
        for i in 0..a.len() {
            a[i] = self.acceleration(i, f[i]);
        }
    }

    /// Filtered acceleration of vertex `i` under force `f`.
    #[inline]
    pub fn acceleration(&self, i: usize, f: Vec3) -> Vec3 {
        self.constraints.filter[i].apply(f / self.mass[i])
    }
}

/// What one integrator step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct IntegratorStats {
    pub force_evaluations: u32,
    pub cg_iterations: u32,
    /// Relative residual the conjugate gradient reached (implicit only).
    pub cg_residual: f64,
}

/// Advances `(x, v)` from `t` to `t + h`. Kinematic vertices arrive with their velocity already
/// set to the constant velocity that carries them to their end-of-step target.
pub trait Integrator: Send {
    fn name(&self) -> &'static str;

    /// Called once when the simulation is built (and again if the effects change).
    fn prepare(&mut self, _effects: &EffectSet, _n: usize) {}

    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
    ) -> IntegratorStats;

    /// [`Integrator::step`] out of place: advances `(x0, v0)` and writes the result to `(x, v)`
    /// (same lengths; every entry is overwritten). The simulation keeps the start state for the
    /// divergence guard's rollback this way without copying it. Default: copy, then step in place.
    fn step_into(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        (x0, v0): (&[Vec3], &[Vec3]),
        x: &mut [Vec3],
        v: &mut [Vec3],
    ) -> IntegratorStats {
        x.copy_from_slice(x0);
        v.copy_from_slice(v0);
        self.step(d, t, h, x, v)
    }

    /// Largest stable `h * omega` for an undamped oscillator, if the method has one.
    fn stability_limit(&self) -> Option<f64> {
        None
    }

    /// Whether the step applies [`Constraints::friction`] itself (implicit: as a drag inside the
    /// solve, see [`Friction`]).
    fn solves_friction(&self) -> bool {
        false
    }

    /// The normal force (N) each of [`Constraints::contacts`] exerted at the end of the last
    /// step, in their order (`None` when the integrator does not solve them).
    fn contact_forces(&self) -> Option<&[f64]> {
        None
    }

    /// Whether the step applies [`Constraints::contacts`] itself (implicit: as one-sided
    /// springs inside the solve, see [`ContactSpring`]).
    fn solves_contacts(&self) -> bool {
        false
    }

    /// The impulse (N s) each vertex received from its constraint filter during the last step,
    /// `(I - S)(M dv - h f)`, when the method knows it (implicit: from the system it solved, so
    /// it holds no linearisation error). Entries of free vertices are zero.
    fn constraint_impulses(&self) -> Option<&[Vec3]> {
        None
    }
}

/// Integrator choice in a scene file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorKind {
    ExplicitEuler,
    SymplecticEuler,
    Rk4,
    Implicit,
}

impl IntegratorKind {
    pub const ALL: [IntegratorKind; 4] = [
        IntegratorKind::ExplicitEuler,
        IntegratorKind::SymplecticEuler,
        IntegratorKind::Rk4,
        IntegratorKind::Implicit,
    ];

    pub fn build(self, implicit: ImplicitSettings) -> Box<dyn Integrator> {
        match self {
            IntegratorKind::ExplicitEuler => Box::new(ExplicitEuler::default()),
            IntegratorKind::SymplecticEuler => Box::new(SymplecticEuler::default()),
            IntegratorKind::Rk4 => Box::new(Rk4::default()),
            IntegratorKind::Implicit => Box::new(Implicit::new(implicit)),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::ExplicitEuler => "explicit_euler",
            IntegratorKind::SymplecticEuler => "symplectic_euler",
            IntegratorKind::Rk4 => "rk4",
            IntegratorKind::Implicit => "implicit",
        }
    }
}

/// Resizes a scratch buffer without reallocating when the size is unchanged.
pub(crate) fn scratch(buf: &mut Vec<Vec3>, n: usize) {
    if buf.len() != n {
        buf.clear();
        buf.resize(n, Vec3::ZERO);
    }
}
