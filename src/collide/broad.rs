//! Uniform spatial hash for cloth-cloth broad phase: cost about linear in the number of boxes
//! when the cell size matches the typical box size. Buffers are kept across steps.

use crate::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Aabb {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        lo: Vec3::splat(f64::INFINITY),
        hi: Vec3::splat(f64::NEG_INFINITY),
    };

    pub fn from_points(pts: &[Vec3], margin: f64) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in pts {
            b.lo = b.lo.min(*p);
            b.hi = b.hi.max(*p);
        }
        b.lo -= Vec3::splat(margin);
        b.hi += Vec3::splat(margin);
        b
    }

    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.lo.cmple(o.hi).all() && o.lo.cmple(self.hi).all()
    }
}

/// Items are hashed into every cell their box overlaps (counting sort into `entries`).
#[derive(Debug, Default)]
pub(crate) struct SpatialHash {
    inv_cell: f64,
    cell_start: Vec<u32>,
    entries: Vec<u32>,
    keyed: Vec<(u32, u32)>,
    cursor: Vec<u32>,
    /// Items spanning more than `MAX_SPAN` cells on an axis: tested against every query.
    big: Vec<u32>,
}

/// Boxes covering more cells than this per axis are kept in a side list instead of the table
/// (fast-moving vertices), so the table cost stays linear.
const MAX_SPAN: i64 = 8;

fn cell_range(lo: f64, hi: f64, inv: f64) -> (i64, i64) {
    ((lo * inv).floor() as i64, (hi * inv).floor() as i64)
}

fn too_big(r: (i64, i64)) -> bool {
    r.1 - r.0 > MAX_SPAN
}

fn hash(x: i64, y: i64, z: i64, n: usize) -> usize {
    let h =
        (x.wrapping_mul(73_856_093)) ^ (y.wrapping_mul(19_349_663)) ^ (z.wrapping_mul(83_492_791));
    (h as u64 % n as u64) as usize
}

impl SpatialHash {
    fn table_len(&self) -> usize {
        self.cell_start.len().saturating_sub(1)
    }

    /// Rebuilds over `boxes` with cubic cells of edge `cell`.
    pub fn build(&mut self, cell: f64, boxes: &[Aabb]) {
        self.inv_cell = 1.0 / cell.max(1e-9);
        let n = (2 * boxes.len()).max(64);
        self.keyed.clear();
        self.big.clear();
        for (i, b) in boxes.iter().enumerate() {
            if !(b.lo.is_finite() && b.hi.is_finite()) {
                self.big.push(i as u32);
                continue;
            }
            let rx = cell_range(b.lo.x, b.hi.x, self.inv_cell);
            let ry = cell_range(b.lo.y, b.hi.y, self.inv_cell);
            let rz = cell_range(b.lo.z, b.hi.z, self.inv_cell);
            if too_big(rx) || too_big(ry) || too_big(rz) {
                self.big.push(i as u32);
                continue;
            }
            let ((x0, x1), (y0, y1), (z0, z1)) = (rx, ry, rz);
            for x in x0..=x1 {
                for y in y0..=y1 {
                    for z in z0..=z1 {
                        self.keyed.push((hash(x, y, z, n) as u32, i as u32));
                    }
                }
            }
        }
        self.cell_start.clear();
        self.cell_start.resize(n + 1, 0);
        for &(h, _) in &self.keyed {
            self.cell_start[h as usize + 1] += 1;
        }
        for k in 0..n {
            self.cell_start[k + 1] += self.cell_start[k];
        }
        self.entries.clear();
        self.entries.resize(self.keyed.len(), 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.cell_start);
        for &(h, i) in &self.keyed {
            let c = &mut self.cursor[h as usize];
            self.entries[*c as usize] = i;
            *c += 1;
        }
    }

    /// Calls `f` for every item sharing a hash bucket with `b` (may repeat items).
    pub fn query(&self, b: &Aabb, mut f: impl FnMut(u32)) {
        for &i in &self.big {
            f(i);
        }
        let n = self.table_len();
        if n == 0 || !(b.lo.is_finite() && b.hi.is_finite()) {
            return;
        }
        let rx = cell_range(b.lo.x, b.hi.x, self.inv_cell);
        let ry = cell_range(b.lo.y, b.hi.y, self.inv_cell);
        let rz = cell_range(b.lo.z, b.hi.z, self.inv_cell);
        if too_big(rx) || too_big(ry) || too_big(rz) {
            // A huge query box: scan every entry once instead of every cell it covers.
            for &i in &self.entries {
                f(i);
            }
            return;
        }
        let ((x0, x1), (y0, y1), (z0, z1)) = (rx, ry, rz);
        for x in x0..=x1 {
            for y in y0..=y1 {
                for z in z0..=z1 {
                    let h = hash(x, y, z, n);
                    let (s, e) = (self.cell_start[h] as usize, self.cell_start[h + 1] as usize);
                    for &i in &self.entries[s..e] {
                        f(i);
                    }
                }
            }
        }
    }
}

/// One parallel chunk's dedup stamps and found pairs.
type ChunkBuffers = (Vec<u32>, Vec<(u32, u32)>);

/// Per-chunk buffers for `collect_pairs`, kept across steps.
#[derive(Debug, Default)]
pub(crate) struct PairScratch {
    chunks: Vec<ChunkBuffers>,
}

/// Queries per parallel chunk: small enough to balance, large enough to amortise the per-chunk
/// stamp reset.
const CHUNK: usize = 1024;

/// Collects deduplicated pairs `(query index, item index)` whose boxes overlap and that `accept`
/// keeps, in query order. Runs the queries in parallel chunks (rayon), each with its own stamp
/// array for deduplication.
pub(crate) fn collect_pairs(
    hash: &SpatialHash,
    queries: &[Aabb],
    items: &[Aabb],
    scratch: &mut PairScratch,
    accept: impl Fn(u32, u32) -> bool + Sync,
    out: &mut Vec<(u32, u32)>,
) {
    use rayon::prelude::*;
    out.clear();
    let n_chunks = queries.len().div_ceil(CHUNK);
    if scratch.chunks.len() < n_chunks {
        scratch.chunks.resize_with(n_chunks, Default::default);
    }
    scratch.chunks[..n_chunks]
        .par_iter_mut()
        .enumerate()
        .for_each(|(c, (stamp, found))| {
            found.clear();
            stamp.clear();
            stamp.resize(items.len(), u32::MAX);
            let start = c * CHUNK;
            for (k, qb) in queries[start..(start + CHUNK).min(queries.len())]
                .iter()
                .enumerate()
            {
                let q = (start + k) as u32;
                hash.query(qb, |i| {
                    let s = &mut stamp[i as usize];
                    if *s == q {
                        return;
                    }
                    *s = q;
                    if items[i as usize].overlaps(qb) && accept(q, i) {
                        found.push((q, i));
                    }
                });
            }
        });
    for (_, found) in &scratch.chunks[..n_chunks] {
        out.extend_from_slice(found);
    }
}

/// A cell edge suited to `boxes`: their mean largest extent (at least `min_cell`).
pub(crate) fn cell_size(boxes: &[Aabb], min_cell: f64) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for b in boxes {
        let e = (b.hi - b.lo).max_element();
        if e.is_finite() {
            sum += e;
            n += 1;
        }
    }
    if n == 0 {
        return min_cell.max(1e-6);
    }
    (sum / n as f64).max(min_cell).max(1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pairs from the hash equal brute-force overlapping pairs on random boxes.
    #[test]
    fn hash_pairs_match_brute_force() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64) / ((1u64 << 53) as f64)
        };
        let mk = |c: Vec3, e: f64| Aabb {
            lo: c - Vec3::splat(e),
            hi: c + Vec3::splat(e),
        };
        let items: Vec<Aabb> = (0..400)
            .map(|_| {
                mk(
                    Vec3::new(rnd(), rnd(), rnd()) * 2.0 - 1.0,
                    0.02 + 0.05 * rnd(),
                )
            })
            .collect();
        let queries: Vec<Aabb> = (0..300)
            .map(|_| {
                mk(
                    Vec3::new(rnd(), rnd(), rnd()) * 2.0 - 1.0,
                    0.01 + 0.08 * rnd(),
                )
            })
            .collect();
        let mut h = SpatialHash::default();
        h.build(cell_size(&items, 0.0), &items);
        let mut scratch = PairScratch::default();
        let mut got = Vec::new();
        collect_pairs(&h, &queries, &items, &mut scratch, |_, _| true, &mut got);
        got.sort_unstable();
        let mut want = Vec::new();
        for (q, qb) in queries.iter().enumerate() {
            for (i, ib) in items.iter().enumerate() {
                if qb.overlaps(ib) {
                    want.push((q as u32, i as u32));
                }
            }
        }
        assert!(!want.is_empty());
        assert_eq!(got, want);
    }
}
