//! Classic fourth-order Runge-Kutta on the first-order system `(x, v)' = (v, a(x, v, t))`.

use super::dynamics::Dynamics;
use super::explicit::{InverseMass, StartState};
use super::integrator::{Capabilities, Integrator, StepReport};
use crate::effects::State;
use crate::linalg::scratch;
use crate::Vec3;

#[derive(Default)]
pub struct Rk4 {
    f: Vec<Vec3>,
    xs: Vec<Vec3>,
    /// Stage velocities `k_x` of stages 1 to 3 (stage 0's is the start velocity itself); each is
    /// also the velocity the stage's acceleration is evaluated at.
    kx: [Vec<Vec3>; 3],
    kv: [Vec<Vec3>; 4],
    inv_mass: InverseMass,
    start: StartState,
}

impl Integrator for Rk4 {
    fn name(&self) -> &'static str {
        "rk4"
    }

    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    ) {
        let start = self.start.take(x, v);
        self.step_into(d, t, h, (&start.x, &start.v), x, v, report);
        self.start = start;
    }

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
        let n = x0.len();
        scratch(&mut self.xs, n);
        for k in 0..3 {
            scratch(&mut self.kx[k], n);
        }
        for k in 0..4 {
            scratch(&mut self.kv[k], n);
        }
        let inv_mass = self.inv_mass.of(d.mass);
        let c = [0.0, 0.5, 0.5, 1.0];
        for stage in 0..4 {
            let (xs, vs): (&[Vec3], &[Vec3]) = if stage == 0 {
                (x0, v0)
            } else {
                let (done, rest) = self.kx.split_at_mut(stage - 1);
                let kx_prev: &[Vec3] = if stage == 1 { v0 } else { &done[stage - 2] };
                let kv_prev = &self.kv[stage - 1][..n];
                let (xs, vs) = (&mut self.xs[..n], &mut rest[0][..n]);
                let ch = c[stage] * h;
                for i in 0..n {
                    xs[i] = x0[i] + kx_prev[i] * ch;
                    vs[i] = v0[i] + kv_prev[i] * ch;
                }
                (&self.xs, &self.kx[stage - 1])
            };
            let state = State {
                t: t + c[stage] * h,
                x: xs,
                v: vs,
            };
            // The first stage is at the start state, whose position forces the guard cached.
            if stage == 0 {
                d.effects.take_forces(&state, &mut self.f);
            } else {
                scratch(&mut self.f, n);
                d.effects.forces(&state, &mut self.f);
            }
            let filter = &d.constraints.filter[..n];
            let (f, inv_mass, kv) = (&self.f[..n], &inv_mass[..n], &mut self.kv[stage][..n]);
            for i in 0..n {
                kv[i] = filter[i].apply(f[i] * inv_mass[i]);
            }
        }
        let [kx1, kx2, kx3] = &self.kx;
        let [kv0, kv1, kv2, kv3] = &self.kv;
        for i in 0..n {
            x[i] = x0[i] + (v0[i] + kx1[i] * 2.0 + kx2[i] * 2.0 + kx3[i]) * (h / 6.0);
            v[i] = v0[i] + (kv0[i] + kv1[i] * 2.0 + kv2[i] * 2.0 + kv3[i]) * (h / 6.0);
        }
        report.explicit(4);
    }

    fn capabilities(&self) -> Capabilities {
        // |R(i h omega)| <= 1 on the imaginary axis up to h omega = 2 sqrt(2).
        Capabilities::explicit(2.0 * std::f64::consts::SQRT_2)
    }
}
