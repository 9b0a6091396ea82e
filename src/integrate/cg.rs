//! The modified preconditioned conjugate gradient of Baraff and Witkin (section 5.3): solves
//! `S A S dv = S b` with the constrained components of `dv` fixed, every iterate kept inside the
//! constraint set by the per-vertex filter `S`, started from the best combination of up to two
//! guesses in the energy norm.

use super::contact::OffPattern;
use super::precond::Multigrid;
use crate::linalg::{scratch, BlockCsr, Filter, FilteredCholesky};
use crate::par::sum_in_halves;
use crate::{Mat3, Vec3};

/// What one conjugate-gradient solve did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SolveStats {
    pub iterations: u32,
    /// `|S (b - A dv)| / |S b|` at exit.
    pub residual: f64,
    /// Wall time of the iterations (the set-up before the first is not counted).
    pub seconds: f64,
    /// Floating-point operations and least bytes streamed by one iteration (see
    /// [`iteration_cost`]).
    pub flops: f64,
    pub bytes: f64,
    /// Wall time preparing the preconditioner (multigrid update or Cholesky factorisation),
    /// and the factorisations and symbolic analyses done for the solve.
    pub setup_seconds: f64,
    pub factorisations: u32,
    pub analyses: u32,
}

/// The `M^-1` of one PCG solve.
pub(crate) enum Precond<'a> {
    /// The inverse of each vertex's diagonal block.
    BlockJacobi,
    /// A V-cycle of the smoothed-aggregation hierarchy.
    Multigrid(&'a mut Multigrid),
    /// The sparse Cholesky factor of the filtered matrix: exact for `A` itself (one iteration),
    /// an approximate inverse when the system adds couplings outside `A`'s pattern
    /// ([`OffPattern`]) or the factor is of a nearby matrix.
    Cholesky(&'a mut FilteredCholesky),
}

impl<'a> From<Option<&'a mut Multigrid>> for Precond<'a> {
    fn from(mg: Option<&'a mut Multigrid>) -> Self {
        mg.map_or(Precond::BlockJacobi, Precond::Multigrid)
    }
}

/// Floating-point operations and the least bytes one PCG iteration below streams: the product
/// `A c` ([`BlockCsr::mul_bytes`]), the preconditioner (the V-cycle's
/// [`Multigrid::apply_cost`], two triangular solves with the Cholesky factor, or block Jacobi's
/// 3x3 inverse per vertex), and the vector passes of the loop (filter and dot of `q`; `dv`, `r`
/// and `|r|^2`; the filter of `M^-1 r` and `r . s`; `c = s + beta c`: 15 reads or writes of
/// `Vec3` and two of the filter per vertex).
pub(crate) fn iteration_cost(a: &BlockCsr, pre: &Precond) -> (f64, f64) {
    let n = a.rows() as f64;
    let filter = std::mem::size_of::<Filter>() as f64;
    let (pf, pb) = match pre {
        Precond::Multigrid(mg) => mg.apply_cost(),
        Precond::Cholesky(c) => {
            let l = c.factor_len() as f64;
            (4.0 * l, 2.0 * l * 16.0)
        }
        Precond::BlockJacobi => (15.0 * n, n * (72.0 + 2.0 * 24.0)),
    };
    (
        a.mul_flops() + pf + 60.0 * n,
        a.mul_bytes() + pb + n * (15.0 * 24.0 + 2.0 * filter),
    )
}

/// Scratch vectors of the modified PCG.
#[derive(Default)]
pub(crate) struct Pcg {
    pinv: Vec<Mat3>,
    r: Vec<Vec3>,
    c: Vec<Vec3>,
    q: Vec<Vec3>,
    s: Vec<Vec3>,
    /// The second start direction and its product.
    h: Vec<Vec3>,
    ah: Vec<Vec3>,
    /// `|S r|^2` and `|S b|^2` of the start (see [`Pcg::start`]).
    rnorm2: f64,
    bnorm2: f64,
    /// Couplings of the system outside `A`'s pattern, added to every product with `A`.
    pub extra: OffPattern,
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
        mg: Option<&mut Multigrid>,
        tol: f64,
        max_iterations: u32,
        dv: &mut [Vec3],
        second: Option<&[Vec3]>,
    ) -> SolveStats {
        match self.start(a, filt, b, z, tol, dv, second) {
            Some(done) => done,
            None => self.iterate(a, filt, mg.into(), tol, max_iterations, dv),
        }
    }

    /// The start of [`Pcg::solve`]: `dv` set to the best start and the residual computed.
    /// Returns the solve's outcome when that start already meets the tolerance, so that a
    /// caller can leave the preconditioner alone (its update can cost more than the solve).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn start(
        &mut self,
        a: &BlockCsr,
        filt: &[Filter],
        b: &[Vec3],
        z: &[Vec3],
        tol: f64,
        dv: &mut [Vec3],
        second: Option<&[Vec3]>,
    ) -> Option<SolveStats> {
        let n = b.len();
        for buf in [&mut self.r, &mut self.c, &mut self.q, &mut self.s] {
            scratch(buf, n);
        }
        let (mut guess, mut target) = (false, false);
        for i in 0..n {
            // The free part of the guess in `c`, the constrained part (`z`) in `dv`.
            self.c[i] = filt[i].apply(dv[i]);
            dv[i] = z[i];
            guess |= self.c[i] != Vec3::ZERO;
            target |= z[i] != Vec3::ZERO;
        }
        // r = S (b - A z): the residual of the start without the guess.
        if target {
            self.extra.system_product(a, dv, &mut self.q);
        } else {
            self.q.fill(Vec3::ZERO);
        }
        let mut bnorm2 = 0.0;
        for i in 0..n {
            let sb = filt[i].apply(b[i]);
            self.r[i] = sb - filt[i].apply(self.q[i]);
            bnorm2 += sb.length_squared();
        }
        // The guess enters as the combination of its directions (`g`, and `h` when given) that
        // minimises the error's energy norm over their span (a Galerkin step on `S A S`): never
        // worse than starting from zero, exact when the solution lies in the span.
        if guess {
            self.extra.system_product(a, &self.c, &mut self.q);
            let (mut gr, mut gag) = (0.0, 0.0);
            for i in 0..n {
                self.q[i] = filt[i].apply(self.q[i]);
                gr += self.c[i].dot(self.r[i]);
                gag += self.c[i].dot(self.q[i]);
            }
            let mut two = None;
            if let Some(second) = second.filter(|h| h.len() == n) {
                scratch(&mut self.h, n);
                scratch(&mut self.ah, n);
                for i in 0..n {
                    self.h[i] = filt[i].apply(second[i]);
                }
                self.extra.system_product(a, &self.h, &mut self.ah);
                let (mut hr, mut hah, mut gah) = (0.0, 0.0, 0.0);
                for i in 0..n {
                    self.ah[i] = filt[i].apply(self.ah[i]);
                    hr += self.h[i].dot(self.r[i]);
                    hah += self.h[i].dot(self.ah[i]);
                    gah += self.c[i].dot(self.ah[i]);
                }
                // 2x2 Gram system; skipped when `h` is (nearly) parallel to `g`.
                let det = gag * hah - gah * gah;
                if det > 1e-8 * gag * hah {
                    let (ag, ah) = ((gr * hah - hr * gah) / det, (hr * gag - gr * gah) / det);
                    if ag.is_finite() && ah.is_finite() {
                        two = Some((ag, ah));
                    }
                }
            }
            // With one direction, `h` is `g` with coefficient zero.
            let (ag, ah, h, ahv) = match two {
                Some((ag, ah)) => (ag, ah, &self.h, &self.ah),
                None if gag > 0.0 && (gr / gag).is_finite() => (gr / gag, 0.0, &self.c, &self.q),
                None => (0.0, 0.0, &self.c, &self.q),
            };
            // Taken only when it also lowers the residual PCG stops on: the energy-norm optimum
            // can leave a larger residual than the zero start (at loose tolerances, e.g. the
            // node's real-time preview at 1e-2, that costs iterations).
            let (mut before, mut after) = (0.0, 0.0);
            for i in 0..n {
                before += self.r[i].length_squared();
                after += (self.r[i] - self.q[i] * ag - ahv[i] * ah).length_squared();
            }
            if (ag != 0.0 || ah != 0.0) && after < before {
                for i in 0..n {
                    dv[i] += self.c[i] * ag + h[i] * ah;
                    self.r[i] -= self.q[i] * ag + ahv[i] * ah;
                }
            }
        }
        self.rnorm2 = self.r.iter().map(|r| r.length_squared()).sum();
        self.bnorm2 = bnorm2.max(f64::MIN_POSITIVE);
        (self.rnorm2 <= tol * tol * self.bnorm2).then(|| SolveStats {
            iterations: 0,
            residual: (self.rnorm2 / self.bnorm2).sqrt(),
            seconds: 0.0,
            flops: 0.0,
            bytes: 0.0,
            setup_seconds: 0.0,
            factorisations: 0,
            analyses: 0,
        })
    }

    /// The iterations of [`Pcg::solve`] from the start [`Pcg::start`] left in `dv`.
    pub(crate) fn iterate(
        &mut self,
        a: &BlockCsr,
        filt: &[Filter],
        mut pre: Precond,
        tol: f64,
        max_iterations: u32,
        dv: &mut [Vec3],
    ) -> SolveStats {
        let n = dv.len();
        let (mut rnorm2, bnorm2) = (self.rnorm2, self.bnorm2);
        let tol2 = tol * tol;
        if matches!(pre, Precond::BlockJacobi) {
            // Block Jacobi's inverses (only then: computing them for every solve at 64x64
            // would cost the multigrid solves a noticeable share of their time).
            self.pinv.clear();
            self.pinv.extend((0..n).map(|i| {
                let di = a.diagonal(i);
                let inv = di.inverse();
                if di.determinant().abs() > 0.0 && inv.is_finite() {
                    inv
                } else {
                    Mat3::IDENTITY
                }
            }));
        }
        // `out = S M^-1 r`, returning `r . out`.
        let precondition = |pinv: &[Mat3], pre: &mut Precond, r: &[Vec3], out: &mut [Vec3]| {
            let applied = match pre {
                Precond::Multigrid(mg) => {
                    mg.apply(r, out);
                    true
                }
                // The caller factorised before choosing this preconditioner; without a factor
                // the iteration runs unpreconditioned rather than stopping.
                Precond::Cholesky(c) => {
                    if c.solve(r, out).is_err() {
                        out.copy_from_slice(r);
                    }
                    true
                }
                Precond::BlockJacobi => false,
            };
            if applied {
                sum_in_halves(n, (out, r, filt), |(out, r, filt)| {
                    let mut d = 0.0;
                    for ((o, r), f) in out.iter_mut().zip(r).zip(filt) {
                        *o = f.apply(*o);
                        d += r.dot(*o);
                    }
                    d
                })
            } else {
                sum_in_halves(n, (out, r, filt, pinv), |(out, r, filt, pinv)| {
                    let mut d = 0.0;
                    for (((o, r), f), p) in out.iter_mut().zip(r).zip(filt).zip(pinv) {
                        *o = f.apply(*p * *r);
                        d += r.dot(*o);
                    }
                    d
                })
            }
        };
        // The clock includes the first `M^-1 r`: with the Cholesky factor that is most of a
        // solve.
        let clock = std::time::Instant::now();
        let mut delta = precondition(&self.pinv, &mut pre, &self.r, &mut self.c);
        let mut iterations = 0;
        let (flops, bytes) = iteration_cost(a, &pre);
        // The vector passes run in halves on two threads for large cloths (`sum_in_halves`).
        while rnorm2 > tol2 * bnorm2 && iterations < max_iterations {
            self.extra.system_product(a, &self.c, &mut self.q);
            let cq = sum_in_halves(n, (&mut self.q[..], &self.c[..], filt), |(q, c, filt)| {
                let mut cq = 0.0;
                for ((q, c), f) in q.iter_mut().zip(c).zip(filt) {
                    *q = f.apply(*q);
                    cq += c.dot(*q);
                }
                cq
            });
            if cq <= 0.0 || !cq.is_finite() || delta <= 0.0 || !delta.is_finite() {
                // Not positive definite along c (only possible with degenerate input): stop with
                // the best iterate so far rather than divide by zero.
                break;
            }
            let alpha = delta / cq;
            let data = (&mut dv[..], &mut self.r[..], &self.c[..], &self.q[..]);
            rnorm2 = sum_in_halves(n, data, |(dv, r, c, q)| {
                let mut rr = 0.0;
                for (((x, r), c), q) in dv.iter_mut().zip(r).zip(c).zip(q) {
                    *x += *c * alpha;
                    *r -= *q * alpha;
                    rr += r.length_squared();
                }
                rr
            });
            iterations += 1;
            if rnorm2 <= tol2 * bnorm2 {
                break;
            }
            let delta_old = delta;
            delta = precondition(&self.pinv, &mut pre, &self.r, &mut self.s);
            let beta = delta / delta_old;
            sum_in_halves(n, (&mut self.c[..], &self.s[..]), |(c, s)| {
                for (c, s) in c.iter_mut().zip(s) {
                    *c = *s + *c * beta;
                }
                0.0
            });
        }
        SolveStats {
            iterations,
            residual: (rnorm2 / bnorm2).sqrt(),
            seconds: clock.elapsed().as_secs_f64(),
            flops,
            bytes,
            setup_seconds: 0.0,
            factorisations: 0,
            analyses: 0,
        }
    }
}

#[cfg(test)]
mod tests;
