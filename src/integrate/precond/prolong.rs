//! The smoothed prolongator `P = (I - omega D^-1 A) T`: the tentative prolongator `T` (one 3x3
//! identity per vertex into its aggregate: the translations) smoothed once by damped block
//! Jacobi, with `omega = 4 / (3 rho(D^-1 A))`.

use super::aggregate::ISOLATED;
use super::csr::Csr;
use glam::{Mat3A as M3, Vec3A as V3};

/// Largest eigenvalue of `D^-1 A` by power iteration (a slight overestimate is harmless).
pub(super) fn spectral_radius(a: &Csr, dinv: &[M3]) -> f32 {
    let n = a.rows();
    // Deterministic, non-smooth start vector.
    let mut x: Vec<V3> = (0..n)
        .map(|i| {
            let t = i as f32;
            V3::new(
                (t * 0.618).fract() - 0.5,
                (t * 0.414).fract() - 0.5,
                (t * 0.732).fract() - 0.5,
            )
        })
        .collect();
    let mut y = vec![V3::ZERO; n];
    let mut rho = 1.0;
    for _ in 0..12 {
        a.mul(&x, &mut y);
        let mut norm = 0.0;
        for (yi, di) in y.iter_mut().zip(dinv) {
            *yi = *di * *yi;
            norm += yi.length_squared();
        }
        let xnorm: f32 = x.iter().map(|v| v.length_squared()).sum();
        if !(norm > 0.0 && xnorm > 0.0) {
            break;
        }
        rho = (norm / xnorm).sqrt();
        let s = 1.0 / norm.sqrt();
        for (xi, yi) in x.iter_mut().zip(&y) {
            *xi = *yi * s;
        }
    }
    rho * 1.05
}

/// `P = (I - omega D^-1 A) P_tent`, `P_tent` = one identity block per row in its aggregate column
/// (none for an [`ISOLATED`] row), into `p`'s storage; `marker` is scratch.
pub(super) fn smoothed_prolongator(
    a: &Csr,
    dinv: &[M3],
    agg: &[u32],
    nc: usize,
    omega: f32,
    p: &mut Csr,
    marker: &mut Vec<usize>,
) {
    let n = a.rows();
    marker.clear();
    marker.resize(nc, usize::MAX);
    p.row_start.clear();
    p.cols.clear();
    p.vals.clear();
    p.ncols = nc;
    p.row_start.push(0);
    for i in 0..n {
        let begin = p.cols.len();
        let (cols, vals) = a.row(i);
        for (&j, &m) in cols.iter().zip(vals) {
            let c = agg[j as usize];
            if c == ISOLATED {
                continue;
            }
            let slot = marker[c as usize];
            if slot != usize::MAX && slot >= begin {
                p.vals[slot] += m;
            } else {
                marker[c as usize] = p.cols.len();
                p.cols.push(c);
                p.vals.push(m);
            }
        }
        let w = dinv[i] * -omega;
        for v in &mut p.vals[begin..] {
            *v = w * *v;
        }
        let own = agg[i];
        if own != ISOLATED {
            let slot = marker[own as usize];
            if slot != usize::MAX && slot >= begin {
                p.vals[slot] += M3::IDENTITY;
            } else {
                p.cols.push(own);
                p.vals.push(M3::IDENTITY);
            }
        }
        p.row_start.push(p.cols.len());
    }
}
