//! A symmetric-pattern sparse matrix of 3x3 blocks (block CSR), the implicit solver's system matrix.
//!
//! The pattern is fixed when the simulation is built (from the pairs every effect couples), so
//! assembling a step only overwrites values; no allocation happens per step.

use crate::par::{in_halves, PAR_VERTICES};
use crate::{Mat3, Vec3};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

/// Source of [`BlockCsr::pattern_id`]s.
static NEXT_PATTERN: AtomicU64 = AtomicU64::new(1);

/// Rows this large or larger are multiplied in two parallel halves (a 32x32 cloth's ~20k blocks
/// outweigh the fork on the spinning helper, `crate::par`).
const PAR_ROWS: usize = 512;

/// Blocks from which an element-wise pass over a matrix's values (`assign`, `axpby`) runs in two
/// halves on the pool: a 64x64 cloth's ~40k blocks are 2.8 MB a pass.
const PAR_BLOCKS: usize = 8 * 1024;

/// Collects the vertex pairs a set of effects couples.
#[derive(Debug, Default, Clone)]
pub struct PatternBuilder {
    pairs: Vec<(u32, u32)>,
}

impl PatternBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Declares that vertices `i` and `j` interact (both orders are added).
    pub fn couple(&mut self, i: u32, j: u32) {
        if i != j {
            self.pairs.push((i, j));
            self.pairs.push((j, i));
        }
    }

    /// Declares a clique of mutually interacting vertices.
    pub fn couple_all(&mut self, idx: &[u32]) {
        for (a, &i) in idx.iter().enumerate() {
            for &j in &idx[a + 1..] {
                self.couple(i, j);
            }
        }
    }

    /// Builds the pattern for `n` vertices; the diagonal is always present.
    pub fn build(mut self, n: usize) -> BlockCsr {
        self.pairs.extend((0..n as u32).map(|i| (i, i)));
        self.pairs.sort_unstable();
        self.pairs.dedup();
        let mut row_start = vec![0usize; n + 1];
        for &(i, _) in &self.pairs {
            row_start[i as usize + 1] += 1;
        }
        for r in 0..n {
            row_start[r + 1] += row_start[r];
        }
        let cols: Vec<u32> = self.pairs.iter().map(|&(_, j)| j).collect();
        let diag = (0..n)
            .map(|r| {
                let row = &cols[row_start[r]..row_start[r + 1]];
                row_start[r] + row.binary_search(&(r as u32)).unwrap_or(0)
            })
            .collect();
        BlockCsr {
            vals: vec![Mat3::ZERO; cols.len()],
            row_start,
            cols,
            diag,
            zero: true,
            pattern: NEXT_PATTERN.fetch_add(1, Ordering::Relaxed),
            edits: Edits::default(),
            version: 0,
        }
    }
}

/// Block CSR matrix.
#[derive(Debug, Clone)]
pub struct BlockCsr {
    row_start: Vec<usize>,
    cols: Vec<u32>,
    diag: Vec<usize>,
    vals: Vec<Mat3>,
    /// No value was added since the last clear, so every block is zero: lets the solver skip
    /// clearing, copying and combining empty matrices (df/dv of a scene without damping).
    zero: bool,
    /// Identifies the pattern (shared by clones): cached slot indices are valid for it.
    pattern: u64,
    /// Which rows changed since [`BlockCsr::clear_edits`]: lets a copy derived from the matrix
    /// row by row (the multigrid's filtered finest level) redo only those rows.
    edits: Edits,
    /// Counts the writes to the values: what was computed from them (a Cholesky factor) is
    /// current while the count is the one it was computed at.
    version: u64,
}

/// The rows a [`BlockCsr`]'s values changed in: a list while only [`BlockCsr::add`] touched
/// them (an active-set round's few refits), every row after any other write.
#[derive(Debug, Clone)]
struct Edits {
    all: bool,
    rows: Vec<u32>,
}

impl Default for Edits {
    fn default() -> Self {
        Edits {
            all: true,
            rows: Vec::new(),
        }
    }
}

impl Edits {
    fn everything(&mut self) {
        self.all = true;
        self.rows.clear();
    }
}

impl BlockCsr {
    pub fn rows(&self) -> usize {
        self.row_start.len() - 1
    }

    /// Identifier of this matrix's sparsity pattern, equal for clones and unique per
    /// [`PatternBuilder::build`]: slot indices computed for one matrix serve every matrix with
    /// the same id.
    pub fn pattern_id(&self) -> u64 {
        self.pattern
    }

    /// Changes whenever a value may have changed (see [`BlockCsr::version`]'s field).
    pub fn version(&self) -> u64 {
        self.version
    }

    pub fn nnz_blocks(&self) -> usize {
        self.cols.len()
    }

    /// Index of block (i, j) in the value array. Panics if the pair was not declared: that is a bug
    /// in an effect (it must declare every pair it adds to), not a user error.
    #[inline]
    pub fn slot(&self, i: u32, j: u32) -> usize {
        if i == j {
            return self.diag[i as usize];
        }
        let (s, e) = (self.row_start[i as usize], self.row_start[i as usize + 1]);
        match self.cols[s..e].binary_search(&j) {
            Ok(k) => s + k,
            Err(_) => panic!("block ({i}, {j}) missing from the sparsity pattern"),
        }
    }

    /// Index of block (i, j) in the value array, `None` when the pair is not in the pattern.
    #[inline]
    pub fn try_slot(&self, i: u32, j: u32) -> Option<usize> {
        if i == j {
            return self.diag.get(i as usize).copied();
        }
        let (s, e) = (
            *self.row_start.get(i as usize)?,
            *self.row_start.get(i as usize + 1)?,
        );
        self.cols[s..e].binary_search(&j).ok().map(|k| s + k)
    }

    /// Adds `m` to block (i, j); the edit log records row `i`.
    #[inline]
    pub fn add(&mut self, i: u32, j: u32, m: Mat3) {
        self.version = self.version.wrapping_add(1);
        let s = self.slot(i, j);
        self.vals[s] += m;
        self.zero = false;
        if !self.edits.all {
            self.edits.rows.push(i);
        }
    }

    /// Adds `m` at a cached slot (assembly); the edit log then counts every row as changed.
    #[inline]
    pub fn add_at(&mut self, slot: usize, m: Mat3) {
        self.version = self.version.wrapping_add(1);
        self.vals[slot] += m;
        self.zero = false;
        if !self.edits.all {
            self.edits.everything();
        }
    }

    /// The rows whose values changed since the last [`BlockCsr::clear_edits`] (with repeats, in
    /// no order), or `None` when any row may have (a new matrix, assembly, a bulk write).
    pub fn edited_rows(&self) -> Option<&[u32]> {
        (!self.edits.all).then_some(self.edits.rows.as_slice())
    }

    /// Starts a new edit log: what derives from the matrix is up to date with it now.
    pub fn clear_edits(&mut self) {
        self.edits.all = false;
        self.edits.rows.clear();
    }

    /// Bytes one `mul` streams at the least: every block (f64 3x3) with its column index, the
    /// row starts, `x` read once and `y` written once (gathered reads of `x` assumed cached).
    pub fn mul_bytes(&self) -> f64 {
        let n = self.rows() as f64;
        let blocks = self.cols.len() as f64;
        blocks * (72.0 + 4.0) + (n + 1.0) * 8.0 + 2.0 * 24.0 * n
    }

    /// Floating-point operations of one `mul`: a multiply and an add per block entry.
    pub fn mul_flops(&self) -> f64 {
        18.0 * self.cols.len() as f64
    }

    /// True when every block is zero (nothing added since the last clear).
    pub fn is_zero(&self) -> bool {
        self.zero
    }

    /// Copies the values of `other`, which has the same pattern.
    pub fn assign(&mut self, other: &BlockCsr) {
        self.version = self.version.wrapping_add(1);
        debug_assert_eq!(self.cols.len(), other.cols.len());
        if !(self.zero && other.zero) {
            let n = self.vals.len();
            let data = (&mut self.vals[..], &other.vals[..n]);
            in_halves(n, PAR_BLOCKS, data, |(s, o)| s.copy_from_slice(o));
        }
        self.zero = other.zero;
        self.edits.everything();
    }

    /// Column indices and blocks of row `r` (read-only view for preconditioners).
    #[inline]
    pub fn row(&self, r: usize) -> (&[u32], &[Mat3]) {
        let (s, e) = (self.row_start[r], self.row_start[r + 1]);
        (&self.cols[s..e], &self.vals[s..e])
    }

    pub fn diagonal(&self, i: usize) -> Mat3 {
        self.vals[self.diag[i]]
    }

    pub fn clear(&mut self) {
        self.version = self.version.wrapping_add(1);
        if !self.zero {
            self.vals.iter_mut().for_each(|v| *v = Mat3::ZERO);
        }
        self.zero = true;
        self.edits.everything();
    }

    /// Sets `self = a * self + b * other` (same pattern).
    pub fn axpby(&mut self, a: f64, b: f64, other: &BlockCsr) {
        self.version = self.version.wrapping_add(1);
        debug_assert_eq!(self.cols.len(), other.cols.len());
        let n = self.vals.len();
        if other.zero {
            in_halves(n, PAR_BLOCKS, &mut self.vals[..], |s| {
                s.iter_mut().for_each(|s| *s *= a)
            });
        } else {
            let data = (&mut self.vals[..], &other.vals[..n]);
            in_halves(n, PAR_BLOCKS, data, |(s, o)| {
                for (s, o) in s.iter_mut().zip(o) {
                    *s = *s * a + *o * b;
                }
            });
            self.zero = false;
        }
        self.edits.everything();
    }

    /// For each pair `k` with slots `slots[k]` (its blocks (i, i), (j, j), (i, j), (j, i), as
    /// [`PairSlots`] lists them), adds `m = block(k)` to its two diagonal blocks and `-m` to its
    /// two couplings: the pattern of every spring-like Jacobian. From [`PAR_VERTICES`] rows on
    /// the rows are split in two halves filled on two threads, each going through every pair in
    /// order and adding only into its own rows (a pair across the split is evaluated by both):
    /// every block gets its terms in pair order, so the sum is the one pass's, bit for bit.
    pub fn add_pairs(&mut self, slots: &[[usize; 4]], block: impl Fn(usize) -> Mat3 + Sync) {
        self.version = self.version.wrapping_add(1);
        self.zero = false;
        self.edits.everything();
        let n = self.rows();
        let split = if n < PAR_VERTICES {
            self.vals.len()
        } else {
            self.row_start[n / 2]
        };
        let (lo, hi) = self.vals.split_at_mut(split);
        // Slots `from..from + vals.len()`: the pairs touching them, in order.
        let fill = |vals: &mut [Mat3], from: usize| {
            let len = vals.len();
            let own = |s: usize| s.wrapping_sub(from) < len;
            for (k, sl) in slots.iter().enumerate() {
                // A pair's couplings lie in its diagonals' rows.
                if !own(sl[0]) && !own(sl[1]) {
                    continue;
                }
                let m = block(k);
                for (q, &s) in sl.iter().enumerate() {
                    if own(s) {
                        vals[s - from] += if q < 2 { m } else { -m };
                    }
                }
            }
        };
        if hi.is_empty() {
            fill(lo, 0);
        } else {
            crate::par::join(|| fill(lo, 0), || fill(hi, split));
        }
    }

    /// Adds `d[i] * I` to each diagonal block.
    pub fn add_diagonal(&mut self, d: &[f64]) {
        self.version = self.version.wrapping_add(1);
        for (i, &di) in d.iter().enumerate() {
            self.vals[self.diag[i]] += Mat3::from_diagonal(Vec3::splat(di));
        }
        self.zero = false;
        self.edits.everything();
    }

    #[inline(always)]
    fn row_times(&self, r: usize, x: &[Vec3]) -> Vec3 {
        let (cols, vals) = self.row(r);
        let mut acc = Vec3::ZERO;
        for (&j, m) in cols.iter().zip(vals) {
            acc += *m * x[j as usize];
        }
        acc
    }

    /// `y = A x`.
    pub fn mul(&self, x: &[Vec3], y: &mut [Vec3]) {
        assert!(
            x.len() >= self.rows() && y.len() == self.rows(),
            "mul: size mismatch"
        );
        let simd = avx2();
        let rows = |start: usize, y: &mut [Vec3]| {
            if simd {
                // SAFETY: AVX2 is available; every column index is below `rows() <= x.len()`
                // (the pattern is built for `rows()` vertices) and `start + y.len() <= rows()`.
                #[cfg(target_arch = "x86_64")]
                unsafe {
                    self.rows_times_avx2(start, x, y)
                }
            } else {
                for (k, yr) in y.iter_mut().enumerate() {
                    *yr = self.row_times(start + k, x);
                }
            }
        };
        if y.len() >= PAR_ROWS {
            let mid = y.len() / 2;
            let (ya, yb) = y.split_at_mut(mid);
            crate::par::join(|| rows(0, ya), || rows(mid, yb));
        } else {
            rows(0, y);
        }
    }

    /// Rows `start..start + y.len()` of `A x` with AVX2: a block times a vector is three
    /// column-times-broadcast products, `(c0 x + c1 y) + c2 z`, added to the row sum in the
    /// scalar code's order without fused multiply-adds, so the result is bitwise that of
    /// [`BlockCsr::row_times`] (and does not depend on the machine).
    ///
    /// Safety: AVX2 is available, every column index is below `x.len()`, and
    /// `start + y.len() <= self.rows()`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn rows_times_avx2(&self, start: usize, x: &[Vec3], y: &mut [Vec3]) {
        use std::arch::x86_64::*;
        // Lanes x, y, z of the last column: the fourth would read past the block (and, for the
        // last block, past the array).
        let xyz = _mm256_set_epi64x(0, -1, -1, -1);
        let vals = self.vals.as_ptr() as *const f64;
        let xs = x.as_ptr() as *const f64;
        for (k, yr) in y.iter_mut().enumerate() {
            let r = start + k;
            // SAFETY: `r < rows()` (contract), so `r + 1` indexes `row_start`.
            let (s, e) = unsafe {
                (
                    *self.row_start.get_unchecked(r),
                    *self.row_start.get_unchecked(r + 1),
                )
            };
            let mut acc = _mm256_setzero_pd();
            for b in s..e {
                // SAFETY: `b < nnz` so the block's 9 values are in bounds (the first two
                // columns' 4-wide loads end inside the block, the third is masked); the column
                // index is below `x.len()` (contract).
                unsafe {
                    let j = *self.cols.get_unchecked(b) as usize;
                    let m = vals.add(9 * b);
                    let xj = xs.add(3 * j);
                    let t = _mm256_add_pd(
                        _mm256_add_pd(
                            _mm256_mul_pd(_mm256_loadu_pd(m), _mm256_broadcast_sd(&*xj)),
                            _mm256_mul_pd(
                                _mm256_loadu_pd(m.add(3)),
                                _mm256_broadcast_sd(&*xj.add(1)),
                            ),
                        ),
                        _mm256_mul_pd(
                            _mm256_maskload_pd(m.add(6), xyz),
                            _mm256_broadcast_sd(&*xj.add(2)),
                        ),
                    );
                    acc = _mm256_add_pd(acc, t);
                }
            }
            let mut out = [0.0; 4];
            // SAFETY: store to a local 4-element array.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), acc) };
            *yr = Vec3::new(out[0], out[1], out[2]);
        }
    }
}

/// Whether the AVX2 kernels can run (checked once; std caches the answer).
#[inline]
fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Value slots `(ii, jj, ij, ji)` of a fixed list of vertex pairs, computed once per pattern, so
/// that assembling a pair's 2x2 blocks every step needs no search.
#[derive(Debug, Default)]
pub struct PairSlots(Mutex<(u64, Vec<[usize; 4]>)>);

impl PairSlots {
    /// The slots of `pairs` in `m` (recomputed when `m` has another pattern than last time).
    pub fn get(
        &self,
        m: &BlockCsr,
        pairs: impl Iterator<Item = (u32, u32)>,
    ) -> MutexGuard<'_, (u64, Vec<[usize; 4]>)> {
        let mut g = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if g.0 != m.pattern_id() {
            g.1.clear();
            g.1.extend(
                pairs.map(|(i, j)| [m.slot(i, i), m.slot(j, j), m.slot(i, j), m.slot(j, i)]),
            );
            g.0 = m.pattern_id();
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn multiply_matches_dense() {
        let mut p = PatternBuilder::new();
        p.couple(0, 2);
        p.couple(1, 2);
        let mut m = p.build(3);
        let a = Mat3::from_cols_array(&[1., 2., 3., 4., 5., 6., 7., 8., 10.]);
        m.add(0, 2, a);
        m.add(2, 0, a.transpose());
        m.add(1, 1, Mat3::IDENTITY * 3.0);
        let x = [
            Vec3::new(1., 0., 0.),
            Vec3::new(0., 1., 0.),
            Vec3::new(1., 1., 1.),
        ];
        let mut y = [Vec3::ZERO; 3];
        m.mul(&x, &mut y);
        assert_eq!(y[0], a * x[2]);
        assert_eq!(y[1], Vec3::new(0., 3., 0.));
        assert_eq!(y[2], a.transpose() * x[0]);
        assert_eq!(m.nnz_blocks(), 7); // 3 diagonal + 2 symmetric pairs
    }

    /// The (parallel, AVX2 where available) product is bitwise the scalar row-by-row one, on a
    /// matrix large enough to be split into tasks, with values of mixed magnitude and sign.
    #[test]
    fn product_is_bitwise_the_scalar_one() {
        let n = 3 * PAR_ROWS / 2 + 7;
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10f64.powi((seed % 7) as i32 - 3)
        };
        let mut p = PatternBuilder::new();
        for i in 0..n as u32 {
            for d in [1, 2, 64, 65, 127] {
                p.couple(i, (i + d) % n as u32);
            }
        }
        let mut m = p.build(n);
        for v in m.vals.iter_mut() {
            *v = Mat3::from_cols_array(&std::array::from_fn(|_| next()));
        }
        m.zero = false;
        let x: Vec<Vec3> = (0..n).map(|_| Vec3::new(next(), next(), next())).collect();
        let mut y = vec![Vec3::ZERO; n];
        m.mul(&x, &mut y);
        for (r, yr) in y.iter().enumerate() {
            let reference = m.row_times(r, &x);
            assert_eq!(
                yr.to_array().map(f64::to_bits),
                reference.to_array().map(f64::to_bits),
                "row {r}"
            );
        }
    }

    /// Cached pair slots match the searched ones, follow a new pattern, and clones share theirs.
    #[test]
    fn pair_slots_follow_the_pattern() {
        let build = |pairs: &[(u32, u32)]| {
            let mut p = PatternBuilder::new();
            pairs.iter().for_each(|&(i, j)| p.couple(i, j));
            p.build(5)
        };
        let (a, b) = (build(&[(0, 3), (3, 4)]), build(&[(0, 3), (1, 3), (3, 4)]));
        assert_eq!(a.pattern_id(), a.clone().pattern_id());
        assert_ne!(a.pattern_id(), b.pattern_id());
        let cache = PairSlots::default();
        for m in [&a, &b, &a] {
            let pairs = [(0u32, 3u32), (3, 4)];
            let g = cache.get(m, pairs.iter().copied());
            for (&(i, j), s) in pairs.iter().zip(&g.1) {
                assert_eq!(*s, [m.slot(i, i), m.slot(j, j), m.slot(i, j), m.slot(j, i)]);
            }
        }
    }
    /// Pair blocks added in two row halves on two threads are bitwise the ones added pair by
    /// pair in order, with pairs inside either half and across the split, and values of mixed
    /// magnitude (where the order of a sum shows in its last bits).
    #[test]
    fn pair_blocks_in_halves_are_bitwise_the_serial_sum() {
        let n = 2 * PAR_VERTICES + 5;
        let mut p = PatternBuilder::new();
        let mut pairs = Vec::new();
        for i in 0..n as u32 {
            for d in [1, 3, 64, n as u32 / 2 - 1, n as u32 / 2 + 2] {
                let j = (i + d) % n as u32;
                p.couple(i, j);
                pairs.push((i, j));
            }
        }
        let mut split = p.build(n);
        let cache = PairSlots::default();
        let slots = cache.get(&split, pairs.iter().copied());
        let block = |k: usize| {
            let t = k as f64;
            Mat3::from_cols_array(&std::array::from_fn(|e| {
                ((t * 0.618 + e as f64 * 0.37).fract() - 0.5) * 10f64.powi((k + e) as i32 % 9 - 4)
            }))
        };
        let mut serial = split.clone();
        split.add_pairs(&slots.1, block);
        for (k, sl) in slots.1.iter().enumerate() {
            let m = block(k);
            serial.add_at(sl[0], m);
            serial.add_at(sl[1], m);
            serial.add_at(sl[2], -m);
            serial.add_at(sl[3], -m);
        }
        assert!(!split.is_zero());
        for (a, b) in split.vals.iter().zip(&serial.vals) {
            assert_eq!(
                a.to_cols_array().map(f64::to_bits),
                b.to_cols_array().map(f64::to_bits)
            );
        }
    }
}
