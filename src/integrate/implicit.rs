//! Implicit backward Euler after Baraff and Witkin (1998): one linearised solve per step,
//!
//! `(M - h df/dv - h^2 df/dx) dv = h (f0 + h df/dx v0)`,   `v1 = v0 + dv`,   `x1 = x0 + h v1`,
//!
//! with the modified preconditioned conjugate gradient that keeps every iterate inside the
//! constraint set: the filter `S_i = I - p p^T` removes constrained directions and the constrained
//! components of `dv` are fixed to `z` (the velocity change that meets the target).

use super::{scratch, BlockCsr, Dynamics, Integrator, IntegratorStats, PatternBuilder};
use crate::effects::{EffectSet, State};
use crate::{Mat3, Vec3};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImplicitSettings {
    /// Relative residual at which conjugate gradients stop.
    pub cg_tolerance: f64,
    pub cg_max_iterations: u32,
}

impl Default for ImplicitSettings {
    fn default() -> Self {
        Self {
            cg_tolerance: 1e-5,
            cg_max_iterations: 200,
        }
    }
}

pub struct Implicit {
    settings: ImplicitSettings,
    /// df/dx, then reused in place as the system matrix A.
    a: Option<BlockCsr>,
    dfdv: Option<BlockCsr>,
    pinv: Vec<Mat3>,
    f0: Vec<Vec3>,
    b: Vec<Vec3>,
    dv: Vec<Vec3>,
    r: Vec<Vec3>,
    c: Vec<Vec3>,
    q: Vec<Vec3>,
    s: Vec<Vec3>,
    z: Vec<Vec3>,
}

impl Implicit {
    pub fn new(settings: ImplicitSettings) -> Self {
        Self {
            settings,
            a: None,
            dfdv: None,
            pinv: Vec::new(),
            f0: Vec::new(),
            b: Vec::new(),
            dv: Vec::new(),
            r: Vec::new(),
            c: Vec::new(),
            q: Vec::new(),
            s: Vec::new(),
            z: Vec::new(),
        }
    }
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum()
}

impl Integrator for Implicit {
    fn name(&self) -> &'static str {
        "implicit"
    }

    fn prepare(&mut self, effects: &EffectSet, n: usize) {
        let mut p = PatternBuilder::new();
        effects.declare(&mut p);
        let m = p.build(n);
        self.dfdv = Some(m.clone());
        self.a = Some(m);
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
        if self.a.as_ref().is_none_or(|a| a.rows() != n) {
            self.prepare(d.effects, n);
        }
        for buf in [
            &mut self.f0,
            &mut self.b,
            &mut self.dv,
            &mut self.r,
            &mut self.c,
            &mut self.q,
            &mut self.s,
            &mut self.z,
        ] {
            scratch(buf, n);
        }
        self.pinv.resize(n, Mat3::IDENTITY);
        let (Some(a), Some(dfdv)) = (self.a.as_mut(), self.dfdv.as_mut()) else {
            unreachable!("prepared above");
        };
        let filt = &d.constraints.filter;
        let state = State { t, x, v };
        d.effects.forces(&state, &mut self.f0);
        d.effects.jacobians(&state, a, dfdv);

        // b = h (f0 + h dfdx v0), then A = M - h dfdv - h^2 dfdx.
        a.mul(v, &mut self.q);
        for i in 0..n {
            self.b[i] = (self.f0[i] + self.q[i] * h) * h;
        }
        a.axpby(-h * h, -h, dfdv);
        a.add_diagonal(d.mass);

        // Constrained components of dv are fixed: z = (I - S)(v_target - v).
        for i in 0..n {
            self.z[i] = filt[i].constrained(d.constraints.target_velocity[i] - v[i]);
            let di = a.diagonal(i);
            self.pinv[i] = if di.determinant().abs() > 0.0 {
                di.inverse()
            } else {
                Mat3::IDENTITY / d.mass[i]
            };
            // Warm start the free components from the previous step's solution.
            self.dv[i] = filt[i].apply(self.dv[i]) + self.z[i];
        }

        // Modified PCG (Baraff-Witkin, section 5.3), with a block-Jacobi preconditioner.
        a.mul(&self.dv, &mut self.q);
        for i in 0..n {
            self.r[i] = filt[i].apply(self.b[i] - self.q[i]);
            self.c[i] = filt[i].apply(self.pinv[i] * self.r[i]);
            self.s[i] = filt[i].apply(self.b[i]);
            self.q[i] = self.pinv[i] * self.s[i];
        }
        let delta0 = dot(&self.s, &self.q).max(f64::MIN_POSITIVE);
        let mut delta = dot(&self.r, &self.c);
        let tol2 = self.settings.cg_tolerance * self.settings.cg_tolerance;
        let mut iterations = 0;
        while delta > tol2 * delta0 && iterations < self.settings.cg_max_iterations {
            a.mul(&self.c, &mut self.q);
            for i in 0..n {
                self.q[i] = filt[i].apply(self.q[i]);
            }
            let cq = dot(&self.c, &self.q);
            if cq <= 0.0 || !cq.is_finite() {
                // Not positive definite along c (only possible with degenerate input): stop with
                // the best iterate so far rather than divide by zero.
                break;
            }
            let alpha = delta / cq;
            for i in 0..n {
                self.dv[i] += self.c[i] * alpha;
                self.r[i] -= self.q[i] * alpha;
                self.s[i] = self.pinv[i] * self.r[i];
            }
            let delta_old = delta;
            delta = dot(&self.r, &self.s);
            let beta = delta / delta_old;
            for i in 0..n {
                self.c[i] = filt[i].apply(self.s[i] + self.c[i] * beta);
            }
            iterations += 1;
        }

        for i in 0..n {
            v[i] += self.dv[i];
            x[i] += v[i] * h;
        }
        IntegratorStats {
            force_evaluations: 1,
            cg_iterations: iterations,
            cg_residual: (delta.max(0.0) / delta0).sqrt(),
        }
    }
}
