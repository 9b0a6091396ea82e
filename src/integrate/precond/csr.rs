//! The multigrid's own block CSR in single precision (`Mat3A` blocks): the filtered fine
//! operator `S A S + c (I - S)` with negligible positive couplings lumped, products, transposes
//! and Galerkin products `P^T A P`.

use super::error::MultigridError;
use crate::linalg::{BlockCsr, Filter};
use crate::Mat3;
use glam::{Mat3A as M3, Vec3A as V3};

/// Matrices with this many rows or more are filtered in two parallel halves.
const PAR_FILTER_ROWS: usize = 512;
/// Products with this many blocks or more are split in two parallel halves (a 64x64 cloth's
/// prolongator has ~15.7k).
const PAR_BLOCKS: usize = 8 * 1024;
/// Positive couplings below this fraction of the geometric mean of their two diagonal blocks
/// (Frobenius norms) are lumped onto the diagonal in the preconditioner (see [`Csr::filtered`]).
const DROP: f64 = 1e-3;

/// Block CSR with 3x3 blocks and its own storage (the multigrid levels and the filtered copy of
/// the fine matrix).
#[derive(Debug, Clone, Default)]
pub struct Csr {
    pub(super) row_start: Vec<usize>,
    pub(super) cols: Vec<u32>,
    pub(super) vals: Vec<M3>,
    /// Scratch of [`Csr::filtered`]: `|A_ii|_F^1/2` per row.
    pub(super) dnorm: Vec<f64>,
    /// Block columns: every entry of `cols` is below it (the products index `x` unchecked).
    pub(super) ncols: usize,
    /// Scratch of [`Csr::filtered`]: the second half's rows.
    pub(super) spill: Spill,
    /// What the last [`Csr::filtered`] pass read: the filter and the source's pattern, so that
    /// [`Csr::refiltered`] can redo only the rows that changed since.
    pub(super) seen: Vec<Filter>,
    pub(super) source: Option<u64>,
    /// Scratch of [`Csr::refiltered`]: where each row is in its list of rewritten rows, and
    /// the arrays a splice writes into.
    pub(super) listed: Vec<u32>,
    pub(super) spare: Spill,
}

/// One half of a product's rows ([`Csr::matmul_rows`]) and the column marker it used.
#[derive(Debug, Clone, Default)]
pub(super) struct Part {
    pub(super) lens: Vec<usize>,
    pub(super) cols: Vec<u32>,
    pub(super) vals: Vec<M3>,
    marker: Vec<usize>,
}

/// Rows filtered in parallel before they are appended.
#[derive(Debug, Clone, Default)]
pub(super) struct Spill {
    pub(super) cols: Vec<u32>,
    pub(super) vals: Vec<M3>,
    pub(super) ends: Vec<usize>,
}

impl Csr {
    /// `S A S + c (I - S)` per vertex, `c` = trace(A_ii)/3, reusing this matrix's storage.
    ///
    /// Negligible couplings (`|A_ij|_F <= DROP |A_ii|_F^1/2 |A_jj|_F^1/2`) that are symmetric
    /// positive semidefinite blocks `B`, e.g. bending's distance-2 blocks `h^2 c I` next to
    /// stretch springs, are lumped onto the diagonal: the change `[B, -B; -B, B]` is positive
    /// semidefinite (the result stays SPD) and leaves rigid translations, the near-null space
    /// the coarse levels are built on, untouched; the smoother and every coarse level get
    /// sparser. (Spring-like negative blocks are kept: lumping them would remove stiffness.)
    pub fn filtered(&mut self, a: &BlockCsr, filter: &[Filter]) {
        let n = a.rows();
        assert_eq!(filter.len(), n, "one filter per row");
        self.seen.clear();
        self.seen.extend_from_slice(filter);
        self.source = Some(a.pattern_id());
        self.ncols = n;
        self.row_start.clear();
        self.cols.clear();
        self.vals.clear();
        self.row_start.push(0);
        self.dnorm.clear();
        self.dnorm
            .extend((0..n).map(|i| frob2_f64(&a.diagonal(i)).sqrt().sqrt()));
        let dnorm = &self.dnorm;
        if n < PAR_FILTER_ROWS {
            filter_rows(
                a,
                filter,
                dnorm,
                0..n,
                &mut self.cols,
                &mut self.vals,
                &mut self.row_start,
            );
            return;
        }
        // Two halves in parallel (the second into scratch, appended after), row by row the
        // same numbers as the serial pass.
        let mid = n / 2;
        let spill = &mut self.spill;
        spill.cols.clear();
        spill.vals.clear();
        spill.ends.clear();
        spill.ends.push(0);
        crate::par::join(
            || {
                filter_rows(
                    a,
                    filter,
                    dnorm,
                    0..mid,
                    &mut self.cols,
                    &mut self.vals,
                    &mut self.row_start,
                )
            },
            || {
                filter_rows(
                    a,
                    filter,
                    dnorm,
                    mid..n,
                    &mut spill.cols,
                    &mut spill.vals,
                    &mut spill.ends,
                )
            },
        );
        let base = self.cols.len();
        self.cols.extend_from_slice(&spill.cols);
        self.vals.extend_from_slice(&spill.vals);
        self.row_start
            .extend(spill.ends[1..].iter().map(|e| base + e));
    }

    /// [`Csr::filtered`] redone only in the rows that can differ from the last pass over a
    /// matrix of `a`'s pattern: the `edited` rows of `a` (see [`BlockCsr::edited_rows`]) and
    /// those whose filter changed since, and their neighbours (a row reads its neighbours'
    /// filters and diagonal norms). The result is the full pass's, bit for bit. Lists the rows
    /// it rewrote in `rows`. Returns `None` when it cannot (no pass over this pattern yet; the
    /// caller then makes the full pass), else whether a rewritten row's columns changed (a
    /// coupling lumped or unlumped: later rows moved in the arrays).
    ///
    /// An active-set round (friction drags refitted, holds released) changes some tens of rows
    /// of a 64x64 cloth's 4096, where the full pass would rewrite all of them each time.
    pub fn refiltered(
        &mut self,
        a: &BlockCsr,
        filter: &[Filter],
        edited: &[u32],
        rows: &mut Vec<u32>,
    ) -> Option<bool> {
        let n = a.rows();
        rows.clear();
        if self.source != Some(a.pattern_id())
            || self.seen.len() != n
            || self.dnorm.len() != n
            || self.rows() != n
            || filter.len() != n
        {
            return None;
        }
        // `listed[r]`: the index of row `r` in `rows`, or `u32::MAX`.
        self.listed.clear();
        self.listed.resize(n, u32::MAX);
        let mut list = |r: usize, rows: &mut Vec<u32>| {
            let fresh = self.listed[r] == u32::MAX;
            if fresh {
                self.listed[r] = rows.len() as u32;
                rows.push(r as u32);
            }
            fresh
        };
        // The rows that changed themselves; their diagonal norms are read by their neighbours.
        let changed = (edited.iter().map(|&i| i as usize))
            .chain((0..n).filter(|&i| filter[i] != self.seen[i]));
        for i in changed {
            if list(i, rows) {
                self.dnorm[i] = frob2_f64(&a.diagonal(i)).sqrt().sqrt();
            }
        }
        let seeds = rows.len();
        for k in 0..seeds {
            for &j in a.row(rows[k] as usize).0 {
                list(j as usize, rows);
            }
        }
        let spill = &mut self.spill;
        spill.cols.clear();
        spill.vals.clear();
        spill.ends.clear();
        spill.ends.push(0);
        for &r in rows.iter() {
            let r = r as usize;
            filter_rows(
                a,
                filter,
                &self.dnorm,
                r..r + 1,
                &mut spill.cols,
                &mut spill.vals,
                &mut spill.ends,
            );
        }
        for &r in &rows[..seeds] {
            self.seen[r as usize] = filter[r as usize];
        }
        let same = rows.iter().zip(spill.ends.windows(2)).all(|(&r, e)| {
            let (s, t) = (self.row_start[r as usize], self.row_start[r as usize + 1]);
            self.cols[s..t] == spill.cols[e[0]..e[1]]
        });
        if same {
            for (&r, e) in rows.iter().zip(spill.ends.windows(2)) {
                let s = self.row_start[r as usize];
                self.vals[s..s + (e[1] - e[0])].copy_from_slice(&spill.vals[e[0]..e[1]]);
            }
            return Some(false);
        }
        // Splice: every row copied over in order, the rewritten ones from the spill.
        let out = &mut self.spare;
        out.cols.clear();
        out.vals.clear();
        out.ends.clear();
        out.ends.push(0);
        for r in 0..n {
            let (c, v) = match self.listed[r] {
                u32::MAX => {
                    let (s, t) = (self.row_start[r], self.row_start[r + 1]);
                    (&self.cols[s..t], &self.vals[s..t])
                }
                k => {
                    let (s, t) = (spill.ends[k as usize], spill.ends[k as usize + 1]);
                    (&spill.cols[s..t], &spill.vals[s..t])
                }
            };
            out.cols.extend_from_slice(c);
            out.vals.extend_from_slice(v);
            out.ends.push(out.cols.len());
        }
        std::mem::swap(&mut self.cols, &mut out.cols);
        std::mem::swap(&mut self.vals, &mut out.vals);
        std::mem::swap(&mut self.row_start, &mut out.ends);
        Some(true)
    }

    pub fn rows(&self) -> usize {
        self.row_start.len().saturating_sub(1)
    }

    #[inline]
    pub(super) fn row(&self, r: usize) -> (&[u32], &[M3]) {
        let (s, e) = (self.row_start[r], self.row_start[r + 1]);
        (&self.cols[s..e], &self.vals[s..e])
    }

    /// Row `r` times `x`. Safety: `x.len() >= self.ncols`.
    #[inline(always)]
    pub(super) unsafe fn row_times(&self, r: usize, x: &[V3]) -> V3 {
        let (cols, vals) = self.row(r);
        // SAFETY: every column is below `ncols <= x.len()`.
        unsafe { row_dot(cols, vals, x) }
    }

    /// `y = A x`.
    pub fn mul(&self, x: &[V3], y: &mut [V3]) {
        assert!(
            x.len() >= self.ncols && y.len() == self.rows(),
            "mul: size mismatch"
        );
        let rows = |start: usize, y: &mut [V3]| {
            for (k, yr) in y.iter_mut().enumerate() {
                // SAFETY: `x.len() >= ncols` (asserted above).
                *yr = unsafe { self.row_times(start + k, x) };
            }
        };
        // Parallel by work, not rows: the restriction `P^T` has few rows but the fine level's
        // blocks.
        if self.cols.len() >= PAR_BLOCKS && y.len() >= 64 {
            let mid = self.work_split();
            let (ya, yb) = y.split_at_mut(mid);
            crate::par::join(|| rows(0, ya), || rows(mid, yb));
        } else {
            rows(0, y);
        }
    }

    /// Sorts every row by column (Galerkin products leave them in first-touch order), so that
    /// the strictly lower and upper parts of a row are contiguous.
    pub(super) fn sort_rows(&mut self) {
        let mut row: Vec<(u32, M3)> = Vec::new();
        for r in 0..self.rows() {
            let (s, e) = (self.row_start[r], self.row_start[r + 1]);
            if self.cols[s..e].is_sorted() {
                continue;
            }
            row.clear();
            row.extend(
                self.cols[s..e]
                    .iter()
                    .copied()
                    .zip(self.vals[s..e].iter().copied()),
            );
            row.sort_unstable_by_key(|&(c, _)| c);
            for (k, (c, m)) in row.iter().enumerate() {
                self.cols[s + k] = *c;
                self.vals[s + k] = *m;
            }
        }
    }

    /// Value index of each row's diagonal block (rows sorted by column), into `out`.
    pub(super) fn diagonal_slots_into(
        &self,
        level: usize,
        out: &mut Vec<usize>,
    ) -> Result<(), MultigridError> {
        out.clear();
        for r in 0..self.rows() {
            let s = self.row_start[r];
            let k = self.cols[s..self.row_start[r + 1]]
                .binary_search(&(r as u32))
                .map_err(|_| MultigridError::MissingDiagonal { level, row: r })?;
            out.push(s + k);
        }
        Ok(())
    }

    pub(super) fn diagonal_blocks(&self, level: usize) -> Result<Vec<M3>, MultigridError> {
        (0..self.rows())
            .map(|r| {
                let (cols, vals) = self.row(r);
                cols.iter()
                    .position(|&c| c as usize == r)
                    .map(|k| vals[k])
                    .ok_or(MultigridError::MissingDiagonal { level, row: r })
            })
            .collect()
    }

    /// The transpose of an `rows x ncols` block matrix (blocks transposed too), into `out`'s
    /// storage.
    pub(super) fn transpose_into(&self, ncols: usize, out: &mut Csr) {
        let count = &mut out.row_start;
        count.clear();
        count.resize(ncols + 1, 0);
        for &c in &self.cols {
            count[c as usize + 1] += 1;
        }
        for k in 0..ncols {
            count[k + 1] += count[k];
        }
        let next = &mut out.spill.ends;
        next.clone_from(count);
        // Every slot is written below: only new ones need a value first.
        out.cols.resize(self.cols.len(), 0);
        out.vals.resize(self.cols.len(), M3::ZERO);
        for r in 0..self.rows() {
            let (rc, rv) = self.row(r);
            for (&c, &m) in rc.iter().zip(rv) {
                let dst = next[c as usize];
                next[c as usize] += 1;
                out.cols[dst] = r as u32;
                out.vals[dst] = m.transpose();
            }
        }
        out.ncols = self.rows();
    }

    /// `self * other` (Gustavson), `other` having `ncols` block columns; large products in two
    /// halves by work (each row's result does not depend on the split).
    #[cfg(test)]
    pub(super) fn matmul(&self, other: &Csr, ncols: usize) -> Csr {
        let mut out = Csr::default();
        self.matmul_into(other, ncols, &mut out, &mut Default::default());
        out
    }

    /// [`Csr::matmul`] into `out`'s storage, the second half's rows first into `parts[1]`
    /// (storage kept across rebuilds, so that the products write into warm memory).
    pub(super) fn matmul_into(
        &self,
        other: &Csr,
        ncols: usize,
        out: &mut Csr,
        parts: &mut [Part; 2],
    ) {
        let rows = self.rows();
        let [first, second] = parts;
        let (cols, vals) = (&mut out.cols, &mut out.vals);
        let mid = if self.cols.len() >= PAR_BLOCKS {
            let mid = self.work_split();
            crate::par::join(
                || self.matmul_rows(other, ncols, 0..mid, first, (cols, vals)),
                || {
                    let Part { cols, vals, .. } = second;
                    let (mut c, mut v) = (std::mem::take(cols), std::mem::take(vals));
                    self.matmul_rows(other, ncols, mid..rows, second, (&mut c, &mut v));
                    (second.cols, second.vals) = (c, v);
                },
            );
            mid
        } else {
            self.matmul_rows(other, ncols, 0..rows, first, (cols, vals));
            rows
        };
        out.row_start.clear();
        out.row_start.push(0);
        let mut push_rows = |lens: &[usize]| {
            for &l in lens {
                let last = *out.row_start.last().unwrap_or(&0);
                out.row_start.push(last + l);
            }
        };
        push_rows(&first.lens);
        if mid < rows {
            push_rows(&second.lens);
            out.cols.extend_from_slice(&second.cols);
            out.vals.extend_from_slice(&second.vals);
        }
        out.ncols = ncols;
    }

    /// Rows `range` of `self * other`: each row's length into `part.lens`, its columns and
    /// blocks appended to `out` (cleared first); `part.marker` is scratch.
    pub(super) fn matmul_rows(
        &self,
        other: &Csr,
        ncols: usize,
        range: std::ops::Range<usize>,
        part: &mut Part,
        out: (&mut Vec<u32>, &mut Vec<M3>),
    ) {
        let (cols, vals) = out;
        let Part { lens, marker, .. } = part;
        marker.clear();
        marker.resize(ncols, usize::MAX);
        lens.clear();
        cols.clear();
        vals.clear();
        for r in range {
            let row_begin = cols.len();
            let (ac, av) = self.row(r);
            for (&k, &a) in ac.iter().zip(av) {
                let (bc, bv) = other.row(k as usize);
                for (&j, &b) in bc.iter().zip(bv) {
                    let slot = marker[j as usize];
                    if slot != usize::MAX && slot >= row_begin {
                        vals[slot] += a * b;
                    } else {
                        marker[j as usize] = cols.len();
                        cols.push(j);
                        vals.push(a * b);
                    }
                }
            }
            lens.push(cols.len() - row_begin);
        }
    }

    /// The row that splits this matrix's blocks in two near-equal halves.
    fn work_split(&self) -> usize {
        let half = self.cols.len() / 2;
        self.row_start
            .partition_point(|&s| s < half)
            .min(self.rows())
    }
}

/// Rows `rows` of [`Csr::filtered`], appended to `cols` and `vals`, each row's end (relative to
/// `ends`' first entry's storage) pushed to `ends`.
pub(super) fn filter_rows(
    a: &BlockCsr,
    filter: &[Filter],
    dnorm: &[f64],
    rows: std::ops::Range<usize>,
    out_cols: &mut Vec<u32>,
    out_vals: &mut Vec<M3>,
    ends: &mut Vec<usize>,
) {
    let drop2 = DROP * DROP;
    for i in rows {
        let fi = &filter[i];
        let (cols, vals) = a.row(i);
        let si = fi.matrix();
        let mut diag = usize::MAX;
        let mut lumped = Mat3::ZERO;
        for (&j, &blk) in cols.iter().zip(vals) {
            let fj = &filter[j as usize];
            let mut m = match (fi, fj) {
                (Filter::Free, Filter::Free) => blk,
                _ => si * blk * fj.matrix(),
            };
            if j as usize == i {
                if !matches!(fi, Filter::Free) {
                    let c = (blk.x_axis.x + blk.y_axis.y + blk.z_axis.z) / 3.0;
                    m += (Mat3::IDENTITY - si) * c;
                }
                diag = out_cols.len();
            } else {
                let scale = dnorm[i] * dnorm[j as usize];
                if frob2_f64(&m) <= drop2 * scale * scale && symmetric_psd(&m) {
                    lumped += m;
                    continue;
                }
            }
            out_cols.push(j);
            out_vals.push(single(&m));
        }
        if diag != usize::MAX {
            out_vals[diag] += single(&lumped);
        }
        ends.push(out_cols.len());
    }
}

/// `sum_k vals[k] x[cols[k]]`: one (partial) row times a vector.
///
/// Safety: every column in `cols` is below `x.len()`.
#[inline(always)]
pub(super) unsafe fn row_dot(cols: &[u32], vals: &[M3], x: &[V3]) -> V3 {
    // SAFETY: forwarded contract (offset 0).
    unsafe { row_dot_at(cols, vals, x, 0) }
}

/// [`row_dot`] with `x` holding the unknowns from index `offset` on. Unchecked indexing: the
/// bounds checks cost a third of the multigrid cycle's instructions.
///
/// Safety: every column `j` in `cols` satisfies `offset <= j < offset + x.len()`.
#[inline(always)]
pub(super) unsafe fn row_dot_at(cols: &[u32], vals: &[M3], x: &[V3], offset: usize) -> V3 {
    let mut acc = V3::ZERO;
    for (&j, m) in cols.iter().zip(vals) {
        debug_assert!(j as usize >= offset && (j as usize - offset) < x.len());
        // SAFETY: in bounds by the contract.
        acc += *m * unsafe { *x.get_unchecked(j as usize - offset) };
    }
    acc
}

/// Whether a block is exactly symmetric and positive semidefinite (all principal minors `>= 0`).
pub(super) fn symmetric_psd(m: &Mat3) -> bool {
    let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
    // Column-major: m[r][c] = col(c)[r].
    if a.y != b.x || a.z != c.x || b.z != c.y {
        return false;
    }
    let (d0, d1, d2) = (a.x, b.y, c.z);
    d0 >= 0.0
        && d1 >= 0.0
        && d2 >= 0.0
        && d0 * d1 - a.y * a.y >= 0.0
        && d0 * d2 - a.z * a.z >= 0.0
        && d1 * d2 - b.z * b.z >= 0.0
        && m.determinant() >= 0.0
}

/// A 3x3 block in the preconditioner's single precision.
#[inline]
pub(super) fn single(m: &Mat3) -> M3 {
    M3::from(m.as_mat3())
}

pub(super) fn frob2_f64(m: &Mat3) -> f64 {
    m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()
}

pub(super) fn frob2(m: &M3) -> f32 {
    m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()
}

#[cfg(test)]
mod tests;
