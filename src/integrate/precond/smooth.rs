//! One level of the hierarchy and its smoother: symmetric block Gauss-Seidel (forward before
//! the coarse correction, backward after), in two parallel halves on large levels (Jacobi across
//! the cut).

use super::csr::{row_dot, row_dot_at, Csr};
use super::error::MultigridError;
use glam::{Mat3A as M3, Vec3A as V3};

/// Levels with this many rows or more smooth their two halves in parallel (hybrid Gauss-Seidel:
/// Gauss-Seidel within each half, Jacobi across the cut). The split depends on the size only, so
/// results do not depend on the number of threads. A 64x64 cloth's first coarse level (~700
/// rows, ~13k blocks) is above it: split, it takes a few more iterations, each enough cheaper
/// to gain overall (`cargo bench --bench contact`, S1 64x64).
const PAR_SWEEP_ROWS: usize = 512;

/// Rows `..mid` and `mid..` of a level, smoothed independently: the pre-smoother is forward
/// Gauss-Seidel on each half's diagonal block (`L_blk`), the post-smoother backward (`L_blk^T`),
/// so the V-cycle stays symmetric.
#[derive(Debug, Clone)]
pub(super) struct Halves {
    pub(super) mid: usize,
    /// Value index of the first block of each row whose column is `>= mid`.
    pub(super) split: Vec<usize>,
    /// `x` before the backward sweep: what each half reads across the cut.
    pub(super) x_old: Vec<V3>,
}

impl Halves {
    pub(super) fn new(a: &Csr) -> Option<Halves> {
        let n = a.rows();
        if n < PAR_SWEEP_ROWS {
            return None;
        }
        let mut h = Halves {
            mid: n / 2,
            split: Vec::with_capacity(n),
            x_old: vec![V3::ZERO; n],
        };
        h.find_split(a);
        Some(h)
    }

    /// The halves for `a`: `old`'s storage with its cuts recomputed when it has `a`'s size,
    /// else new ones (or none for a small level).
    pub(super) fn refit(old: Option<Halves>, a: &Csr) -> Option<Halves> {
        match old {
            Some(mut h) if h.x_old.len() == a.rows() => {
                h.find_split(a);
                Some(h)
            }
            _ => Halves::new(a),
        }
    }

    /// Recomputes the cut positions for a matrix of the same size.
    pub(super) fn find_split(&mut self, a: &Csr) {
        let mid = self.mid;
        self.split.clear();
        self.split.extend((0..a.rows()).map(|r| {
            let (s, e) = (a.row_start[r], a.row_start[r + 1]);
            s + a.cols[s..e].partition_point(|&c| (c as usize) < mid)
        }));
    }
}

#[derive(Debug, Clone, Default)]
pub(super) struct Level {
    /// The level's matrix, rows sorted by column.
    pub(super) a: Csr,
    /// Value index of each row's diagonal block in `a`.
    pub(super) diag: Vec<usize>,
    pub(super) dinv: Vec<M3>,
    /// The two halves of a large level, smoothed in parallel.
    pub(super) halves: Option<Halves>,
    /// Prolongator to this level from the next coarser one and its transpose (empty on the
    /// coarsest level).
    pub(super) p: Csr,
    pub(super) pt: Csr,
    pub(super) x: Vec<V3>,
    pub(super) b: Vec<V3>,
    pub(super) r: Vec<V3>,
}

impl Level {
    /// A level for `a`, its vectors in `old`'s storage (a rebuild's levels replace ones of
    /// about the same size; `Level::default()` for none).
    pub(super) fn reusing(mut a: Csr, level: usize, old: Level) -> Result<Level, MultigridError> {
        let n = a.rows();
        // The sweeps index `x` (n rows) by column unchecked.
        assert_eq!(a.ncols, n, "multigrid level {level} is not square");
        a.sort_rows();
        let Level {
            mut diag,
            mut dinv,
            halves,
            mut x,
            mut b,
            mut r,
            ..
        } = old;
        a.diagonal_slots_into(level, &mut diag)?;
        invert_diagonal(&a, &diag, level, &mut dinv)?;
        let halves = Halves::refit(halves, &a);
        for v in [&mut x, &mut b, &mut r] {
            v.clear();
            v.resize(n, V3::ZERO);
        }
        Ok(Level {
            a,
            diag,
            dinv,
            halves,
            p: Csr::default(),
            pt: Csr::default(),
            x,
            b,
            r,
        })
    }

    /// One forward (`reverse == false`) or backward block Gauss-Seidel sweep on `A x = b`.
    pub(super) fn gauss_seidel(&mut self, reverse: bool) {
        let n = self.a.rows();
        let (a, x, b, dinv) = (&self.a, &mut self.x, &self.b, &self.dinv);
        let mut sweep = |i: usize| {
            let (cols, vals) = a.row(i);
            // SAFETY: the level is square (`Level::reusing`) and `x` has its rows.
            let s = b[i] - unsafe { row_dot(cols, vals, x) };
            x[i] += dinv[i] * s;
        };
        if reverse {
            (0..n).rev().for_each(&mut sweep);
        } else {
            (0..n).for_each(&mut sweep);
        }
    }

    /// The forward sweep from `x = 0`: the rows after `i` are still zero, so only the strictly
    /// lower part contributes, `x_i = D_i^-1 (b_i - sum_{j < i} A_ij x_j)` (half the work).
    /// With halves, the second half starts its lower part at the cut.
    pub(super) fn forward_sweep_from_zero(&mut self) {
        let Level {
            a,
            diag,
            dinv,
            b,
            x,
            halves,
            ..
        } = self;
        let n = a.rows();
        // The lower part starts at the row start, or at the cut for the second half.
        let sweep = |rows: std::ops::Range<usize>, cut: Option<&[usize]>, x: &mut [V3]| {
            let offset = rows.start;
            for i in rows {
                let lower = cut.map_or(a.row_start[i], |c| c[i])..diag[i];
                // SAFETY: the lower part of row `i` (from the cut in the second half) has columns
                // in `offset..i`, and `x` holds this half's rows.
                let s =
                    b[i] - unsafe { row_dot_at(&a.cols[lower.clone()], &a.vals[lower], x, offset) };
                x[i - offset] = dinv[i] * s;
            }
        };
        match halves {
            None => sweep(0..n, None, x),
            Some(h) => {
                let (xa, xb) = x.split_at_mut(h.mid);
                crate::par::join(
                    || sweep(0..h.mid, None, xa),
                    || sweep(h.mid..n, Some(&h.split), xb),
                );
            }
        }
    }

    /// The post-smoother: a backward sweep, on each half separately when there are halves (the
    /// other half's values taken from before the sweep).
    pub(super) fn backward_sweep(&mut self) {
        let Level {
            a,
            dinv,
            b,
            x,
            halves,
            ..
        } = self;
        let Some(h) = halves else {
            return self.gauss_seidel(true);
        };
        let n = a.rows();
        h.x_old.copy_from_slice(x);
        let (mid, split, x_old) = (h.mid, &h.split, &h.x_old);
        let (xa, xb) = x.split_at_mut(mid);
        // Row `i`'s own-half columns are `own(i)`, the rest read `x_old`.
        let sweep = |rows: std::ops::Range<usize>, x: &mut [V3]| {
            let offset = rows.start;
            for i in rows.rev() {
                let (s, e) = (a.row_start[i], a.row_start[i + 1]);
                let (own, cross) = if offset == 0 {
                    (s..split[i], split[i]..e)
                } else {
                    (split[i]..e, s..split[i])
                };
                // SAFETY: `own` holds the columns of this half (rows sorted, cut at `mid`), which
                // `x` holds from `offset` on; `x_old` has every row of the square level.
                let r = b[i]
                    - unsafe { row_dot_at(&a.cols[own.clone()], &a.vals[own], x, offset) }
                    - unsafe { row_dot(&a.cols[cross.clone()], &a.vals[cross], x_old) };
                x[i - offset] += dinv[i] * r;
            }
        };
        crate::par::join(|| sweep(0..mid, xa), || sweep(mid..n, xb));
    }
}

impl Level {
    /// `r = b - A x` right after one forward sweep from `x = 0`: row `i` was solved exactly with
    /// the rows after it still zero, so only the strictly upper part contributes,
    /// `r_i = -sum_{j > i} A_ij x_j` (half the multiplications of a full residual).
    /// With halves, the second half's rows were solved without the columns before the cut,
    /// which therefore join the residual.
    pub(super) fn residual_after_forward_sweep(&mut self) {
        let Level {
            a,
            diag,
            x,
            r,
            halves,
            ..
        } = self;
        let rows = |start: usize, r: &mut [V3], split: Option<&[usize]>| {
            for (k, ri) in r.iter_mut().enumerate() {
                let i = start + k;
                let upper = diag[i] + 1..a.row_start[i + 1];
                // SAFETY: the level is square and `x` has all its rows.
                let mut acc = unsafe { row_dot(&a.cols[upper.clone()], &a.vals[upper], x) };
                if let Some(split) = split {
                    let cross = a.row_start[i]..split[i];
                    // SAFETY: as above.
                    acc += unsafe { row_dot(&a.cols[cross.clone()], &a.vals[cross], x) };
                }
                *ri = -acc;
            }
        };
        match halves {
            None => rows(0, r, None),
            Some(h) => {
                let (ra, rb) = r.split_at_mut(h.mid);
                crate::par::join(|| rows(0, ra, None), || rows(h.mid, rb, Some(&h.split)));
            }
        }
    }
}

/// The inverses of `a`'s diagonal blocks (at `diag`) into `out`.
pub(super) fn invert_diagonal(
    a: &Csr,
    diag: &[usize],
    level: usize,
    out: &mut Vec<M3>,
) -> Result<(), MultigridError> {
    out.clear();
    for (row, &slot) in diag.iter().enumerate() {
        out.push(
            invert_block(a.vals[slot]).ok_or(MultigridError::SingularDiagonal { level, row })?,
        );
    }
    Ok(())
}

/// The inverse of a diagonal block, `None` unless it is positive definite enough to invert.
pub(super) fn invert_block(d: M3) -> Option<M3> {
    let inv = d.inverse();
    (d.determinant() > 0.0 && inv.is_finite()).then_some(inv)
}
