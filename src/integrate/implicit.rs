//! Implicit backward Euler after Baraff and Witkin (1998): one linearised solve per step,
//!
//! `(M - h df/dv - h^2 df/dx) dv = h (f0 + h df/dx v0)`,   `v1 = v0 + dv`,   `x1 = x0 + h v1`,
//!
//! with the modified preconditioned conjugate gradient that keeps every iterate inside the
//! constraint set: the filter `S_i = I - p p^T` removes constrained directions and the constrained
//! components of `dv` are fixed to `z` (the velocity change that meets the target).
//!
//! The preconditioner is smoothed-aggregation multigrid on the filtered operator (see
//! [`super::precond`]); its hierarchy is rebuilt only when the iteration count drifts up, and
//! block Jacobi takes over whenever the hierarchy cannot be built.

use super::precond::{Csr, Multigrid};
use super::{scratch, BlockCsr, Dynamics, Filter, Integrator, IntegratorStats, PatternBuilder};
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

/// Which `M^-1` the conjugate gradient uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preconditioner {
    BlockJacobi,
    /// Smoothed-aggregation multigrid, falling back to block Jacobi when its setup fails.
    Multigrid,
}

/// Rebuild the hierarchy at least this often (steps).
const REBUILD_EVERY: u32 = 20;

/// The multigrid state kept across steps.
struct Hierarchy {
    mg: Multigrid,
    steps: u32,
    iterations_at_build: u32,
}

/// What one conjugate-gradient solve did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SolveStats {
    pub iterations: u32,
    /// `|S (b - A dv)| / |S b|` at exit.
    pub residual: f64,
}

/// Scratch vectors of the modified PCG.
#[derive(Default)]
pub(crate) struct Pcg {
    pinv: Vec<Mat3>,
    r: Vec<Vec3>,
    c: Vec<Vec3>,
    q: Vec<Vec3>,
    s: Vec<Vec3>,
}

impl Pcg {
    /// Solves `S A S dv = S b` with `(I - S) dv = z` by the modified PCG (Baraff-Witkin, section
    /// 5.3). `dv` holds the initial guess (its free components are used), `mg` the preconditioner
    /// (block Jacobi when `None`). Stops at `|S r| <= tol |S b|`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve(
        &mut self,
        a: &BlockCsr,
        filt: &[Filter],
        b: &[Vec3],
        z: &[Vec3],
        mut mg: Option<&mut Multigrid>,
        tol: f64,
        max_iterations: u32,
        dv: &mut [Vec3],
    ) -> SolveStats {
        let n = b.len();
        for buf in [&mut self.r, &mut self.c, &mut self.q, &mut self.s] {
            scratch(buf, n);
        }
        self.pinv.resize(n, Mat3::IDENTITY);
        for i in 0..n {
            let di = a.diagonal(i);
            let inv = di.inverse();
            self.pinv[i] = if di.determinant().abs() > 0.0 && inv.is_finite() {
                inv
            } else {
                Mat3::IDENTITY
            };
            dv[i] = filt[i].apply(dv[i]) + z[i];
        }
        a.mul(dv, &mut self.q);
        let mut bnorm2 = 0.0;
        let mut rnorm2 = 0.0;
        for i in 0..n {
            self.r[i] = filt[i].apply(b[i] - self.q[i]);
            bnorm2 += filt[i].apply(b[i]).length_squared();
            rnorm2 += self.r[i].length_squared();
        }
        let bnorm2 = bnorm2.max(f64::MIN_POSITIVE);
        let tol2 = tol * tol;
        let precondition =
            |pinv: &[Mat3], mg: &mut Option<&mut Multigrid>, r: &[Vec3], out: &mut [Vec3]| {
                match mg {
                    Some(mg) => mg.apply(r, out),
                    None => out
                        .iter_mut()
                        .zip(r)
                        .zip(pinv)
                        .for_each(|((o, r), p)| *o = *p * *r),
                }
                out.iter_mut().zip(filt).for_each(|(o, f)| *o = f.apply(*o));
            };
        precondition(&self.pinv, &mut mg, &self.r, &mut self.c);
        let mut delta = dot(&self.r, &self.c);
        let mut iterations = 0;
        while rnorm2 > tol2 * bnorm2 && iterations < max_iterations {
            a.mul(&self.c, &mut self.q);
            let mut cq = 0.0;
            for i in 0..n {
                self.q[i] = filt[i].apply(self.q[i]);
                cq += self.c[i].dot(self.q[i]);
            }
            if cq <= 0.0 || !cq.is_finite() || !(delta > 0.0) {
                // Not positive definite along c (only possible with degenerate input): stop with
                // the best iterate so far rather than divide by zero.
                break;
            }
            let alpha = delta / cq;
            rnorm2 = 0.0;
            for i in 0..n {
                dv[i] += self.c[i] * alpha;
                self.r[i] -= self.q[i] * alpha;
                rnorm2 += self.r[i].length_squared();
            }
            iterations += 1;
            if rnorm2 <= tol2 * bnorm2 {
                break;
            }
            precondition(&self.pinv, &mut mg, &self.r, &mut self.s);
            let delta_old = delta;
            delta = dot(&self.r, &self.s);
            let beta = delta / delta_old;
            for i in 0..n {
                self.c[i] = self.s[i] + self.c[i] * beta;
            }
        }
        SolveStats {
            iterations,
            residual: (rnorm2 / bnorm2).sqrt(),
        }
    }
}

pub struct Implicit {
    settings: ImplicitSettings,
    preconditioner: Preconditioner,
    /// df/dx, then reused in place as the system matrix A.
    a: Option<BlockCsr>,
    dfdv: Option<BlockCsr>,
    hierarchy: Option<Hierarchy>,
    /// Storage for the filtered fine matrix handed to the multigrid.
    filtered: Csr,
    pcg: Pcg,
    f0: Vec<Vec3>,
    b: Vec<Vec3>,
    dv: Vec<Vec3>,
    z: Vec<Vec3>,
}

impl Implicit {
    pub fn new(settings: ImplicitSettings) -> Self {
        Self::with_preconditioner(settings, Preconditioner::Multigrid)
    }

    pub fn with_preconditioner(settings: ImplicitSettings, preconditioner: Preconditioner) -> Self {
        Self {
            settings,
            preconditioner,
            a: None,
            dfdv: None,
            hierarchy: None,
            filtered: Csr::default(),
            pcg: Pcg::default(),
            f0: Vec::new(),
            b: Vec::new(),
            dv: Vec::new(),
            z: Vec::new(),
        }
    }

    /// Gives the multigrid the current filtered matrix: a fresh hierarchy when none exists or the
    /// last one has aged (iterations drifting up or `REBUILD_EVERY` steps), else only the finest
    /// level. `None` means block Jacobi (multigrid disabled or its setup failed).
    fn update_hierarchy(&mut self, filt: &[Filter]) -> Option<&mut Multigrid> {
        if self.preconditioner != Preconditioner::Multigrid {
            return None;
        }
        let a = self.a.as_ref()?;
        let n = a.rows();
        let mut fine = match self.hierarchy.as_mut() {
            Some(h) => h.mg.take_finest(),
            None => std::mem::take(&mut self.filtered),
        };
        fine.filtered(a, filt);
        let reuse = self
            .hierarchy
            .as_ref()
            .is_some_and(|h| h.mg.rows() == n && h.steps < REBUILD_EVERY);
        if reuse {
            if let Some(h) = self.hierarchy.as_mut() {
                match h.mg.refresh_finest(fine) {
                    Ok(()) => {
                        h.steps += 1;
                        return self.hierarchy.as_mut().map(|h| &mut h.mg);
                    }
                    Err(e) => {
                        log::debug!("multigrid refresh failed ({e}); rebuilding");
                        self.hierarchy = None;
                        return None;
                    }
                }
            }
        }
        match Multigrid::build(fine) {
            Ok(mg) => {
                self.hierarchy = Some(Hierarchy {
                    mg,
                    steps: 0,
                    iterations_at_build: 0,
                });
                self.hierarchy.as_mut().map(|h| &mut h.mg)
            }
            Err(e) => {
                log::debug!("multigrid setup failed ({e}); using block Jacobi");
                self.hierarchy = None;
                None
            }
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
        self.hierarchy = None;
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
        for buf in [&mut self.f0, &mut self.b, &mut self.dv, &mut self.z] {
            scratch(buf, n);
        }
        let filt = &d.constraints.filter;
        let t_0 = std::time::Instant::now();
        {
            let (Some(a), Some(dfdv)) = (self.a.as_mut(), self.dfdv.as_mut()) else {
                unreachable!("prepared above");
            };
            let state = State { t, x, v };
            d.effects.forces(&state, &mut self.f0);
            d.effects.jacobians(&state, a, dfdv);

            // b = h (f0 + h dfdx v0), then A = M - h dfdv - h^2 dfdx.
            a.mul(v, &mut self.b);
            for i in 0..n {
                self.b[i] = (self.f0[i] + self.b[i] * h) * h;
            }
            a.axpby(-h * h, -h, dfdv);
            a.add_diagonal(d.mass);
        }
        // Constrained components of dv are fixed: z = (I - S)(v_target - v). The free components
        // are warm-started from the previous step's solution.
        for i in 0..n {
            self.z[i] = filt[i].constrained(d.constraints.target_velocity[i] - v[i]);
        }

        let (tol, max_it) = (self.settings.cg_tolerance, self.settings.cg_max_iterations);
        let t_1 = std::time::Instant::now();
        let use_mg = self.update_hierarchy(filt).is_some();
        let t_2 = std::time::Instant::now();
        let Some(a) = self.a.as_ref() else {
            unreachable!("prepared above");
        };
        let mgref = match self.hierarchy.as_mut() {
            Some(h) if use_mg => Some(&mut h.mg),
            _ => None,
        };
        let stats = self
            .pcg
            .solve(a, filt, &self.b, &self.z, mgref, tol, max_it, &mut self.dv);
        if std::env::var_os("DRAPE_MG_DEBUG").is_some() {
            eprintln!(
                "assemble {:?} setup {:?} solve {:?} its {}",
                t_1 - t_0,
                t_2 - t_1,
                t_2.elapsed(),
                stats.iterations
            );
        }
        if let Some(h) = self.hierarchy.as_mut() {
            if h.steps == 0 {
                h.iterations_at_build = stats.iterations;
            } else if stats.iterations > h.iterations_at_build + h.iterations_at_build / 2 + 2 {
                h.steps = REBUILD_EVERY; // drifted: rebuild next step
            }
        }

        for i in 0..n {
            v[i] += self.dv[i];
            x[i] += v[i] * h;
        }
        IntegratorStats {
            force_evaluations: 1,
            cg_iterations: stats.iterations,
            cg_residual: stats.residual,
        }
    }
}
