//! Classic fourth-order Runge-Kutta on the first-order system `(x, v)' = (v, a(x, v, t))`.

use super::{scratch, Dynamics, Integrator, IntegratorStats};
use crate::Vec3;

#[derive(Default)]
pub struct Rk4 {
    f: Vec<Vec3>,
    xs: Vec<Vec3>,
    vs: Vec<Vec3>,
    kx: [Vec<Vec3>; 4],
    kv: [Vec<Vec3>; 4],
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
    ) -> IntegratorStats {
        let n = x.len();
        scratch(&mut self.f, n);
        scratch(&mut self.xs, n);
        scratch(&mut self.vs, n);
        for k in 0..4 {
            scratch(&mut self.kx[k], n);
            scratch(&mut self.kv[k], n);
        }
        let c = [0.0, 0.5, 0.5, 1.0];
        for stage in 0..4 {
            if stage == 0 {
                self.xs.copy_from_slice(x);
                self.vs.copy_from_slice(v);
            } else {
                let (kx, kv) = (&self.kx[stage - 1], &self.kv[stage - 1]);
                for i in 0..n {
                    self.xs[i] = x[i] + kx[i] * (c[stage] * h);
                    self.vs[i] = v[i] + kv[i] * (c[stage] * h);
                }
            }
            self.kx[stage].copy_from_slice(&self.vs);
            d.accelerations(
                t + c[stage] * h,
                &self.xs,
                &self.vs,
                &mut self.f,
                &mut self.kv[stage],
            );
        }
        for i in 0..n {
            x[i] += (self.kx[0][i] + self.kx[1][i] * 2.0 + self.kx[2][i] * 2.0 + self.kx[3][i])
                * (h / 6.0);
            v[i] += (self.kv[0][i] + self.kv[1][i] * 2.0 + self.kv[2][i] * 2.0 + self.kv[3][i])
                * (h / 6.0);
        }
        IntegratorStats {
            force_evaluations: 4,
            ..Default::default()
        }
    }

    fn stability_limit(&self) -> Option<f64> {
        // |R(i h omega)| <= 1 on the imaginary axis up to h omega = 2 sqrt(2).
        Some(2.0 * std::f64::consts::SQRT_2)
    }
}
