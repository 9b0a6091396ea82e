//! What a step integrates: the effects, the masses and the step's per-vertex constraints.
//!
//! Constraints reach every integrator the same way: a per-vertex [`Filter`] (free, one direction
//! constrained, or fixed) and a target velocity for the constrained directions. Explicit methods
//! filter accelerations; the implicit method filters its conjugate-gradient iterates, which is the
//! survey's "mass modification" `(I - p p^T)/m`. Friction and contact springs are there for the
//! methods that solve them (see [`super::Capabilities`]).

use super::contact::ContactSpring;
use super::friction::Friction;
use crate::effects::{EffectSet, State};
use crate::linalg::Filter;
use crate::Vec3;

/// Per-vertex constraints of one step.
#[derive(Debug, Clone, Default)]
pub struct Constraints {
    pub filter: Vec<Filter>,
    /// Velocity the constrained components must have at the end of the step.
    pub target_velocity: Vec<Vec3>,
    /// Coulomb friction of held vertices, for integrators that solve it (see
    /// [`super::Capabilities::solves_friction`]); the others leave friction to the collision
    /// stage.
    pub friction: Vec<Friction>,
    /// Static obstacle edges and corners against the cloth, for integrators that solve them
    /// (see [`super::Capabilities::solves_contacts`]); the others leave them to the collision
    /// stage.
    pub contacts: Vec<ContactSpring>,
    /// Per vertex, the strain of the impact front a moving link's drag sends through the cloth
    /// around it this substep (0 elsewhere; empty when no link drags cloth): the implicit
    /// solve linearises the springs there at that tension (see
    /// [`crate::effects::Effect::add_front_stiffness`]).
    pub front_strain: Vec<f64>,
    /// Free vertices whose contact the collision stage released at the step's start (the force
    /// on them pulls them off), to be held along the normal after all (at their
    /// `target_velocity`) if the solve drives them into it, for integrators that release holds
    /// within the step. Only cloth on its way out of a solid it started inside: the collision
    /// stage leads it out a sixth of an edge a pass, so a solve that moves it back in is not
    /// undone at once. Released at the start, the patch inside drape_bot's forearm would be
    /// pulled back in by the solve (its springs, stretched by the patch's upward speed).
    pub standby: Vec<(usize, Vec3)>,
}

impl Constraints {
    pub fn free(n: usize) -> Self {
        Self {
            filter: vec![Filter::Free; n],
            target_velocity: vec![Vec3::ZERO; n],
            friction: Vec::new(),
            contacts: Vec::new(),
            front_strain: Vec::new(),
            standby: Vec::new(),
        }
    }
}

/// Everything an integrator needs to evaluate the dynamics.
pub struct Dynamics<'a> {
    pub effects: &'a EffectSet,
    pub mass: &'a [f64],
    pub constraints: &'a Constraints,
    /// The scene's substep (s); a step shorter than it is a split or a subdivision of one (0:
    /// unknown, every step counts as a full one). See `integrate::implicit::solve`.
    pub nominal_step: f64,
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
