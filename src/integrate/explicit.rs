//! Forward Euler and symplectic (semi-implicit) Euler.
//!
//! Both run out of place ([`Integrator::step_into`]): one pass reads the start state and the
//! forces and writes the end state, so the simulation keeps the start state for its rollback
//! without a copy.

use super::{Dynamics, Integrator, IntegratorStats};
use crate::effects::{State, PAR_VERTICES};
use crate::Vec3;
use std::ops::Range;

/// `x += h v(t); v += h a(t)`. First order; gains energy on any undamped oscillation, so it is here
/// as the survey's baseline and for the accuracy study, not for production.
pub type ExplicitEuler = Euler<false>;

/// `v += h a(x, v); x += h v_new`. First order but symplectic: energy stays bounded on undamped
/// oscillations while `h omega < 2`.
pub type SymplecticEuler = Euler<true>;

/// The two Euler variants share everything but the order of the position and velocity updates.
#[derive(Default)]
pub struct Euler<const SYMPLECTIC: bool> {
    f: Vec<Vec3>,
    inv_mass: InverseMass,
    start: StartState,
}

impl<const SYMPLECTIC: bool> Integrator for Euler<SYMPLECTIC> {
    fn name(&self) -> &'static str {
        if SYMPLECTIC {
            "symplectic_euler"
        } else {
            "explicit_euler"
        }
    }

    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
    ) -> IntegratorStats {
        let start = self.start.take(x, v);
        let stats = self.step_into(d, t, h, (&start.x, &start.v), x, v);
        self.start = start;
        stats
    }

    fn step_into(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        (x0, v0): (&[Vec3], &[Vec3]),
        x: &mut [Vec3],
        v: &mut [Vec3],
    ) -> IntegratorStats {
        d.effects
            .take_forces(&State { t, x: x0, v: v0 }, &mut self.f);
        let inv_mass = self.inv_mass.of(d.mass);
        let (f, filter) = (&self.f[..], &d.constraints.filter[..]);
        split_update(x, v, &|r, x, v| {
            // Equal-length slices let the compiler drop the loop's bounds checks.
            let n = x.len();
            let (f, filter, inv_mass) = (&f[r.clone()], &filter[r.clone()], &inv_mass[r.clone()]);
            let (x0, v0, v) = (&x0[r.clone()], &v0[r], &mut v[..n]);
            let (f, filter, inv_mass, x0, v0) =
                (&f[..n], &filter[..n], &inv_mass[..n], &x0[..n], &v0[..n]);
            for i in 0..n {
                let vi = v0[i] + filter[i].apply(f[i] * inv_mass[i]) * h;
                // Forward Euler moves with the start velocity, symplectic Euler with the new one.
                x[i] = x0[i] + if SYMPLECTIC { vi } else { v0[i] } * h;
                v[i] = vi;
            }
        });
        IntegratorStats {
            force_evaluations: 1,
            ..Default::default()
        }
    }

    fn stability_limit(&self) -> Option<f64> {
        // Forward Euler undamped: unstable for every h > 0 (damping buys a small margin).
        Some(if SYMPLECTIC { 2.0 } else { 0.0 })
    }
}

/// A per-vertex update over a range of vertices and their positions and velocities.
pub(super) type VertexUpdate<'a> = dyn Fn(Range<usize>, &mut [Vec3], &mut [Vec3]) + Sync + 'a;

/// Runs a per-vertex update `body(range, x[range], v[range])` over all vertices: on two threads
/// (two halves) from [`PAR_VERTICES`] vertices on, where the pass outweighs waking a thread.
/// Each vertex's result does not depend on the split.
pub(super) fn split_update(x: &mut [Vec3], v: &mut [Vec3], body: &VertexUpdate) {
    let n = x.len().min(v.len());
    if n >= PAR_VERTICES {
        let mid = n / 2;
        let (xa, xb) = x[..n].split_at_mut(mid);
        let (va, vb) = v[..n].split_at_mut(mid);
        rayon::join(|| body(0..mid, xa, va), || body(mid..n, xb, vb));
    } else {
        body(0..n, &mut x[..n], &mut v[..n]);
    }
}

/// Reciprocal masses, recomputed only when the masses change: one multiply per vertex in the
/// update loops instead of a division per component.
#[derive(Default)]
pub(super) struct InverseMass {
    mass: Vec<f64>,
    inv: Vec<f64>,
}

impl InverseMass {
    /// `1 / m` per vertex for these masses.
    pub(super) fn of(&mut self, mass: &[f64]) -> &[f64] {
        if self.mass.as_slice() != mass {
            self.mass.clear();
            self.mass.extend_from_slice(mass);
            self.inv.clear();
            self.inv.extend(mass.iter().map(|m| 1.0 / m));
        }
        &self.inv
    }
}

/// A copy of the start state, for the in-place [`Integrator::step`] (the simulation itself uses
/// [`Integrator::step_into`] and needs no copy).
#[derive(Default)]
pub(super) struct StartState {
    pub(super) x: Vec<Vec3>,
    pub(super) v: Vec<Vec3>,
}

impl StartState {
    /// Moves the buffers out of `self`, filled with `(x, v)`; put them back after the step.
    pub(super) fn take(&mut self, x: &[Vec3], v: &[Vec3]) -> StartState {
        let mut s = std::mem::take(self);
        s.x.clear();
        s.x.extend_from_slice(x);
        s.v.clear();
        s.v.extend_from_slice(v);
        s
    }
}
