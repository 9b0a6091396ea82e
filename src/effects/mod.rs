//! Force terms, each its own unit. A scene names the effects it wants; only those are built,
//! so an effect a scene does not name costs nothing in the step (there is no `if enabled` anywhere).
//!
//! Every effect gives forces and, where the implicit solver needs them, analytic force Jacobians
//! `df/dx` and `df/dv` over the sparsity pattern it declares.

mod damping;
mod gravity;
mod springs;
mod stencils;
mod wind;

pub use damping::{AirDrag, SpringDamping, VelocityDiffusion};
pub use gravity::Gravity;
pub use springs::Springs;
pub use stencils::{Bending, StencilSet, Twist};
pub use wind::{Gust, Wind, WindKey};

use crate::integrate::{BlockCsr, PatternBuilder};
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

    /// Adds this effect's forces at `s` to `f`.
    fn add_forces(&self, s: &State, f: &mut [Vec3]);

    /// Adds `df/dx` and `df/dv` at `s`. Default: the force does not depend on state.
    fn add_jacobians(&self, _s: &State, _dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {}

    /// Potential energy at `x` (conservative effects only; 0 otherwise).
    fn energy(&self, _x: &[Vec3]) -> f64 {
        0.0
    }

    /// True for effects that can add energy from outside the cloth (wind); the divergence guard
    /// accounts for their work so that a gust is not mistaken for an instability.
    fn injects_energy(&self) -> bool {
        false
    }

    /// Stiffness bound, for the elastic effects.
    fn stiffness(&self, _mass: &[f64]) -> Option<StiffnessBound> {
        None
    }
}

/// The built effects of a simulation, in scene order, with evaluation counts.
#[derive(Default)]
pub struct EffectSet {
    effects: Vec<Box<dyn Effect>>,
    evaluations: Vec<std::sync::atomic::AtomicU64>,
    gravity: Vec3,
}

impl EffectSet {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds gravity (kept as a vector too, for the divergence guard's error bound).
    pub fn push_gravity(&mut self, g: Gravity) {
        self.gravity += g.g;
        self.push(Box::new(g));
    }

    pub fn push(&mut self, e: Box<dyn Effect>) {
        self.effects.push(e);
        self.evaluations.push(Default::default());
    }

    pub fn iter(&self) -> impl Iterator<Item = &dyn Effect> {
        self.effects.iter().map(|e| e.as_ref())
    }

    pub fn names(&self) -> Vec<&'static str> {
        self.effects.iter().map(|e| e.name()).collect()
    }

    pub fn is_empty(&self) -> bool {
        self.effects.is_empty()
    }

    /// How many times each effect's forces were evaluated, by name.
    pub fn evaluation_counts(&self) -> Vec<(&'static str, u64)> {
        self.effects
            .iter()
            .zip(&self.evaluations)
            .map(|(e, c)| (e.name(), c.load(std::sync::atomic::Ordering::Relaxed)))
            .collect()
    }

    pub fn declare(&self, p: &mut PatternBuilder) {
        for e in &self.effects {
            e.declare(p);
        }
    }

    /// Sum of all forces at `s` (overwrites `f`).
    pub fn forces(&self, s: &State, f: &mut [Vec3]) {
        f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        for (e, c) in self.effects.iter().zip(&self.evaluations) {
            c.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            e.add_forces(s, f);
        }
    }

    /// Forces of the effects that inject energy only (overwrites `f`); false if there are none.
    pub fn injecting_forces(&self, s: &State, f: &mut [Vec3]) -> bool {
        let mut any = false;
        f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        for e in self.effects.iter().filter(|e| e.injects_energy()) {
            e.add_forces(s, f);
            any = true;
        }
        any
    }

    pub fn jacobians(&self, s: &State, dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        dfdx.clear();
        dfdv.clear();
        for e in &self.effects {
            e.add_jacobians(s, dfdx, dfdv);
        }
    }

    pub fn energy(&self, x: &[Vec3]) -> f64 {
        self.effects.iter().map(|e| e.energy(x)).sum()
    }

    /// (elastic, gravity) potential energies.
    pub fn energy_split(&self, x: &[Vec3]) -> (f64, f64) {
        let (mut el, mut gr) = (0.0, 0.0);
        for e in &self.effects {
            if e.name() == "gravity" {
                gr += e.energy(x);
            } else {
                el += e.energy(x);
            }
        }
        (el, gr)
    }

    /// The gravity vector if a gravity effect is present (zero otherwise).
    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// Stiffness bounds of every elastic effect, stiffest first.
    pub fn stiffness(&self, mass: &[f64]) -> Vec<StiffnessBound> {
        let mut b: Vec<StiffnessBound> = self
            .effects
            .iter()
            .filter_map(|e| e.stiffness(mass))
            .collect();
        b.sort_by(|a, b| b.omega_sq.total_cmp(&a.omega_sq));
        b
    }
}

/// Outer product `a b^T`.
#[inline]
pub(crate) fn outer_pub(a: Vec3, b: Vec3) -> crate::Mat3 {
    outer(a, b)
}

/// Outer product `a b^T`.
#[inline]
pub(crate) fn outer(a: Vec3, b: Vec3) -> crate::Mat3 {
    crate::Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}
