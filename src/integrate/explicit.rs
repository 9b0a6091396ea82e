//! Forward Euler and symplectic (semi-implicit) Euler.

use super::{scratch, Dynamics, Integrator, IntegratorStats};
use crate::effects::State;
use crate::Vec3;

/// `x += h v(t); v += h a(t)`. First order; gains energy on any undamped oscillation, so it is here
/// as the survey's baseline and for the accuracy study, not for production.
#[derive(Default)]
pub struct ExplicitEuler {
    f: Vec<Vec3>,
}

impl Integrator for ExplicitEuler {
    fn name(&self) -> &'static str {
        "explicit_euler"
    }

    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
    ) -> IntegratorStats {
        scratch(&mut self.f, x.len());
        d.effects.forces(&State { t, x, v }, &mut self.f);
        for i in 0..x.len() {
            x[i] += v[i] * h;
            v[i] += d.acceleration(i, self.f[i]) * h;
        }
        IntegratorStats {
            force_evaluations: 1,
            ..Default::default()
        }
    }

    fn stability_limit(&self) -> Option<f64> {
        // Undamped: unstable for every h > 0; damping buys a small margin.
        Some(0.0)
    }
}

/// `v += h a(x, v); x += h v_new`. First order but symplectic: energy stays bounded on undamped
/// oscillations while `h omega < 2`.
#[derive(Default)]
pub struct SymplecticEuler {
    f: Vec<Vec3>,
}

impl Integrator for SymplecticEuler {
    fn name(&self) -> &'static str {
        "symplectic_euler"
    }

    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
    ) -> IntegratorStats {
        scratch(&mut self.f, x.len());
        d.effects.forces(&State { t, x, v }, &mut self.f);
        for i in 0..x.len() {
            v[i] += d.acceleration(i, self.f[i]) * h;
            x[i] += v[i] * h;
        }
        IntegratorStats {
            force_evaluations: 1,
            ..Default::default()
        }
    }

    fn stability_limit(&self) -> Option<f64> {
        Some(2.0)
    }
}
