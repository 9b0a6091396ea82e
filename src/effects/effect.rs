//! The [`Effect`] trait, one force term: its forces, its Jacobians over the pattern it declares,
//! its energy and its stiffness bound, and the [`State`] it is evaluated at.

use crate::linalg::{BlockCsr, PatternBuilder};
use crate::Vec3;

/// The state an effect is evaluated at.
#[derive(Clone, Copy)]
pub struct State<'a> {
    pub t: f64,
    pub x: &'a [Vec3],
    pub v: &'a [Vec3],
}

/// Upper bound of an effect's stiffness seen by one vertex, for step-size limits and for naming
/// the likely culprit when a step diverges.
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessBound {
    /// Bound on the largest `omega^2 = lambda_max(M^-1 K)` (1/s^2) the effect contributes.
    pub omega_sq: f64,
    /// The vertex where the bound is attained.
    pub vertex: usize,
    /// The scene parameter responsible, e.g. `cloth[0].material.stretch`.
    pub parameter: String,
}

pub trait Effect: Send + Sync {
    /// Name as written in a scene's effect list.
    fn name(&self) -> &'static str;

    /// Declares the vertex pairs the Jacobians couple (default: none, e.g. gravity).
    fn declare(&self, _pattern: &mut PatternBuilder) {}

    /// Sets the constant part of the air velocity (m/s, scripted keys and gusts still add);
    /// false for effects that are not wind.
    fn set_wind_velocity(&mut self, _velocity: Vec3) -> bool {
        false
    }

    /// Adds this effect's forces at `s` to `f`.
    fn add_forces(&self, s: &State, f: &mut [Vec3]);

    /// Adds `df/dx` and `df/dv` at `s`. Default: the force does not depend on state.
    fn add_jacobians(&self, _s: &State, _dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {}

    /// Adds to `df/dx` the transverse stiffness of the tension an impact front puts in this
    /// effect's springs where a moving link drags the cloth: `front_strain[i]` is the front's
    /// strain at vertex `i` (0: none). The force is unchanged; only the linearisation is taken
    /// at the tension the substep's drag will have built, which at rest length it has not yet
    /// (see `Springs`). Default: no such stiffness.
    fn add_front_stiffness(&self, _s: &State, _front_strain: &[f64], _dfdx: &mut BlockCsr) {}

    /// True when the Jacobians do not depend on the state (quadratic energies, linear damping):
    /// the implicit solver assembles them once, and [`Effect::add_jacobians`] must then not read
    /// its state argument.
    fn constant_jacobians(&self) -> bool {
        false
    }

    /// Potential energy at `x` (conservative effects only; 0 otherwise).
    fn energy(&self, _x: &[Vec3]) -> f64 {
        0.0
    }

    /// True when the force depends on positions only (not on velocity or time): such forces
    /// computed alongside the energy at `x` serve the next force evaluation at the same `x`.
    fn position_only(&self) -> bool {
        false
    }

    /// Adds the forces at `s` to `f` and returns the energy at `s.x`. Elastic effects override
    /// this with one fused pass (the guard needs the energy of every substep's result).
    fn add_forces_energy(&self, s: &State, f: &mut [Vec3]) -> f64 {
        self.add_forces(s, f);
        self.energy(s.x)
    }

    /// [`Effect::add_forces_energy`] over the `part`-th of `parts` slices of the effect's elements,
    /// so that one pass can be split across threads. Default: part 0 does everything.
    fn add_forces_energy_part(&self, s: &State, f: &mut [Vec3], part: usize, _parts: usize) -> f64 {
        if part == 0 {
            self.add_forces_energy(s, f)
        } else {
            0.0
        }
    }

    /// True for effects that can add energy from outside the cloth (wind); the divergence guard
    /// accounts for their work so that a gust is not mistaken for an instability.
    fn injects_energy(&self) -> bool {
        false
    }

    /// The largest stretch, over rest length, that a linearisation of this effect at `x0` does
    /// not see at `x1`: a spring's `|d1| - n0 . d1` (its length beyond the projection on its
    /// direction at `x0`), which a spring turning by `a` gains as `a^2 / 2` of its length.
    /// Default: none (effects without springs).
    fn unseen_stretch(&self, _x0: &[Vec3], _x1: &[Vec3]) -> f64 {
        0.0
    }

    /// Stiffness bound, for the elastic effects.
    fn stiffness(&self, _mass: &[f64]) -> Option<StiffnessBound> {
        None
    }
}
