//! Test systems shared by the solver's unit tests (conjugate gradient and multigrid): SPD
//! spring systems of cloth-like and random structure, constraint sets and a reference solve.

use super::cg::{Pcg, SolveStats};
use super::precond::{Csr, Multigrid};
use crate::linalg::{BlockCsr, Filter, PatternBuilder};
use crate::{Mat3, Vec3};

/// Deterministic xorshift numbers in [-1, 1).
pub(crate) struct Rng(pub(crate) u64);
impl Rng {
    pub(crate) fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    pub(crate) fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

/// `M + sum_ij k_ij (e_i - e_j)(e_i - e_j)^T (x) D_ij` with `D_ij` symmetric positive
/// semidefinite, so `A` is SPD. `pairs` gives `(i, j, k, d)`: `D = d d^T + 0.02 I`.
pub(crate) fn spring_system(n: usize, mass: f64, pairs: &[(u32, u32, f64, Vec3)]) -> BlockCsr {
    let mut p = PatternBuilder::new();
    for &(i, j, _, _) in pairs {
        p.couple(i, j);
    }
    let mut a = p.build(n);
    for &(i, j, k, d) in pairs {
        let blk = (Mat3::from_cols(d * d.x, d * d.y, d * d.z) + Mat3::IDENTITY * 0.02) * k;
        a.add(i, i, blk);
        a.add(j, j, blk);
        a.add(i, j, -blk);
        a.add(j, i, -blk);
    }
    a.add_diagonal(&vec![mass; n]);
    a
}

/// The hanging cloth's `M + h^2 K` at `res x res`: axial springs (`h^2 k` = 0.56, 1e4 times
/// the vertex mass as at 64x64), shear at a tenth, bending-like distance-2 couplings.
pub(crate) fn cloth_system(res: usize) -> BlockCsr {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let id = |i: usize, j: usize| (i * res + j) as u32;
    let mut pairs = Vec::new();
    for i in 0..res {
        for j in 0..res {
            for (di, dj, k) in [
                (0, 1, 1.0),
                (1, 0, 1.0),
                (1, 1, 0.1),
                (1, -1, 0.1),
                (0, 2, 1e-3),
                (2, 0, 1e-3),
            ] {
                let (a, b) = (i as i64 + di, j as i64 + dj);
                if a < res as i64 && b >= 0 && b < res as i64 {
                    let d = (Vec3::new(di as f64, dj as f64, 0.0) + rng.vec3() * 0.1).normalize();
                    pairs.push((id(i, j), id(a as usize, b as usize), 0.56 * k, d));
                }
            }
        }
    }
    spring_system(res * res, 5e-5, &pairs)
}

/// Random sparse SPD system: each vertex coupled to a few random others.
pub(crate) fn random_system(n: usize, seed: u64) -> BlockCsr {
    let mut rng = Rng(seed);
    let mut pairs = Vec::new();
    for i in 0..n as u32 {
        for _ in 0..3 {
            let j = ((rng.next() * 0.5 + 0.5) * n as f64) as u32 % n as u32;
            if j != i {
                let k = 10f64.powf(3.0 * rng.next());
                pairs.push((i, j, k, rng.vec3().normalize()));
            }
        }
    }
    spring_system(n, 1e-3, &pairs)
}

/// Pinned vertices, contact-like `Direction` filters and free ones, with targets `z`.
pub(crate) fn constraints(n: usize, rng: &mut Rng) -> (Vec<Filter>, Vec<Vec3>) {
    let filt: Vec<Filter> = (0..n)
        .map(|i| match i % 17 {
            0 if i < n / 4 => Filter::Fixed,
            3 | 11 => Filter::Direction(rng.vec3().normalize()),
            _ => Filter::Free,
        })
        .collect();
    let z = filt.iter().map(|f| f.constrained(rng.vec3())).collect();
    (filt, z)
}

/// Every `period`-th row (from `offset`) held along `normal` (a contact's `Direction`), the
/// others free.
pub(crate) fn held_every(n: usize, period: usize, offset: usize, normal: Vec3) -> Vec<Filter> {
    (0..n)
        .map(|i| {
            if i % period == offset {
                Filter::Direction(normal)
            } else {
                Filter::Free
            }
        })
        .collect()
}

/// The 12x12 cloth system with [`constraints`], a random right-hand side and its solution to
/// 1e-13: `(a, filt, z, b, x)`. `rng` goes on for the caller's own draws.
pub(crate) fn solved_cloth(
    rng: &mut Rng,
) -> (BlockCsr, Vec<Filter>, Vec<Vec3>, Vec<Vec3>, Vec<Vec3>) {
    let a = cloth_system(12);
    let n = a.rows();
    let (filt, z) = constraints(n, rng);
    let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let (x, _) = solve(&a, &filt, &b, &z, false, 1e-13);
    (a, filt, z, b, x)
}

pub(crate) fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum()
}

pub(crate) fn solve(
    a: &BlockCsr,
    filt: &[Filter],
    b: &[Vec3],
    z: &[Vec3],
    mg: bool,
    tol: f64,
) -> (Vec<Vec3>, SolveStats) {
    let mut fine = Csr::default();
    fine.filtered(a, filt);
    let mut m = if mg {
        Some(Multigrid::build(fine).expect("hierarchy"))
    } else {
        None
    };
    let mut dv = vec![Vec3::ZERO; b.len()];
    let stats = Pcg::default().solve(a, filt, b, z, m.as_mut(), tol, 100_000, &mut dv, None);
    (dv, stats)
}

/// Multigrid-preconditioned and tight block-Jacobi solves agree, meet `(I - S) dv = z` and
/// the residual bound. Both stop at `|r| <= 1e-12 |b|`, so each is within `kappa * 1e-12` of
/// the exact solution (relative); with `kappa <~ 1e4` they agree to 2e-8.
pub(crate) fn check_agreement(a: &BlockCsr, seed: u64) {
    let n = a.rows();
    let mut rng = Rng(seed);
    let (filt, z) = constraints(n, &mut rng);
    let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let (reference, rs) = solve(a, &filt, &b, &z, false, 1e-12);
    let (dv, ms) = solve(a, &filt, &b, &z, true, 1e-12);
    assert!(
        rs.residual <= 1e-12 && ms.residual <= 1e-12,
        "{rs:?} {ms:?}"
    );
    assert!(
        ms.iterations < rs.iterations,
        "multigrid {ms:?} vs jacobi {rs:?}"
    );
    let scale = reference.iter().map(|v| v.length()).fold(0.0, f64::max);
    for i in 0..n {
        assert!(
            (dv[i] - reference[i]).length() <= 2e-8 * scale,
            "vertex {i}: {} vs {}",
            dv[i],
            reference[i]
        );
        let c = filt[i].constrained(dv[i]) - z[i];
        assert!(
            c.length() <= 1e-14 * scale.max(1.0),
            "vertex {i} constrained part off by {c}"
        );
        assert!(dv[i].is_finite());
    }
    // The filtered residual really is small (not just the solver's bookkeeping).
    let mut q = vec![Vec3::ZERO; n];
    a.mul(&dv, &mut q);
    let r2: f64 = (0..n)
        .map(|i| filt[i].apply(b[i] - q[i]).length_squared())
        .sum();
    let b2: f64 = (0..n).map(|i| filt[i].apply(b[i]).length_squared()).sum();
    assert!(r2.sqrt() <= 1e-11 * b2.sqrt());
}
