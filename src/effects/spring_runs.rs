//! The springs' force pass laid out for speed.
//!
//! On a lattice, springs of one direction come in runs: from one spring to the next both
//! endpoints step by one vertex (a row of warp edges, all weft edges, each diagonal family).
//! A run reads its positions and writes its forces as two contiguous slices each, in loops the
//! compiler vectorises, with no index lookups. Springs that belong to no long run (free meshes,
//! seams) go through a gather/scatter loop over blocks of four.
//!
//! Per spring the arithmetic is exactly that of the plain loop (`d = xi - xj`, `L = |d|`,
//! `f = -k (L - l) / L d`), so each spring's force is bitwise the same; only the order in which
//! forces reach a vertex, and the energy's summation order, differ (rounding level).

use super::part_range;
use crate::cloth::topology::Spring;
use crate::Vec3;

/// Shortest run worth its per-chunk overhead; shorter ones go to the block loop.
const MIN_RUN: usize = 8;
/// Springs per chunk of a run (the chunk's scratch arrays live on the stack).
const CHUNK: usize = 64;
/// Springs per block of the gather/scatter loop (one AVX register of f64).
const LANES: usize = 4;

/// A run: springs `(i0 + r, j0 + r)` for `r < len`, with rest lengths and stiffnesses at
/// `first..first + len` of [`SpringLayout`]'s arrays.
#[derive(Debug, Clone, PartialEq)]
struct Run {
    i0: usize,
    j0: usize,
    first: usize,
    len: usize,
}

/// Springs regrouped for the force pass (the effect keeps its own list for Jacobians).
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct SpringLayout {
    runs: Vec<Run>,
    rest: Vec<f64>,
    k: Vec<f64>,
    /// Springs in no long run, with their stiffness.
    loose: Vec<Spring>,
    loose_k: Vec<f64>,
    /// One past the largest vertex index (checked once per pass before unchecked indexing).
    bound: usize,
}

impl SpringLayout {
    pub(super) fn new(springs: &[Spring], k: &[f64]) -> Self {
        // Group by endpoint offset, then by first endpoint: runs become consecutive.
        let mut order: Vec<usize> = (0..springs.len()).collect();
        order.sort_by_key(|&s| (springs[s].j as i64 - springs[s].i as i64, springs[s].i));
        let mut layout = SpringLayout {
            bound: springs
                .iter()
                .map(|s| s.i.max(s.j) as usize + 1)
                .max()
                .unwrap_or(0),
            ..Default::default()
        };
        let mut start = 0;
        while start < order.len() {
            let first = springs[order[start]];
            let mut end = start + 1;
            while end < order.len() {
                let s = springs[order[end]];
                let step = end - start;
                if s.i as usize != first.i as usize + step
                    || s.j as usize != first.j as usize + step
                {
                    break;
                }
                end += 1;
            }
            let group = &order[start..end];
            if group.len() >= MIN_RUN {
                layout.runs.push(Run {
                    i0: first.i as usize,
                    j0: first.j as usize,
                    first: layout.rest.len(),
                    len: group.len(),
                });
                layout.rest.extend(group.iter().map(|&s| springs[s].rest));
                layout.k.extend(group.iter().map(|&s| k[s]));
            } else {
                layout.loose.extend(group.iter().map(|&s| springs[s]));
                layout.loose_k.extend(group.iter().map(|&s| k[s]));
            }
            start = end;
        }
        layout
    }

    /// Adds the forces of the `part`-th of `parts` slices of the springs (of the runs and of the
    /// loose springs each) to `f` and returns their energy.
    pub(super) fn forces_energy(
        &self,
        x: &[Vec3],
        f: &mut [Vec3],
        part: usize,
        parts: usize,
    ) -> f64 {
        assert!(
            x.len() >= self.bound && f.len() >= self.bound,
            "springs reach vertex {} but the state has {} positions and {} forces",
            self.bound.saturating_sub(1),
            x.len(),
            f.len()
        );
        let runs = part_range(self.rest.len(), part, parts);
        let loose = part_range(self.loose.len(), part, parts);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above); indices were checked above.
            return unsafe { self.forces_energy_avx2(x, f, runs, loose) };
        }
        // SAFETY: every index is below `bound`, checked above against both slices.
        unsafe { self.forces_energy_generic(x, f, runs, loose) }
    }

    /// [`SpringLayout::forces_energy_generic`] compiled for AVX2 (4 f64 lanes; no fused
    /// multiply-adds, so lanes round exactly as the baseline build).
    ///
    /// Safety: AVX2 is available, and the contract of `forces_energy_generic`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn forces_energy_avx2(
        &self,
        x: &[Vec3],
        f: &mut [Vec3],
        runs: std::ops::Range<usize>,
        loose: std::ops::Range<usize>,
    ) -> f64 {
        // SAFETY: forwarded from the caller.
        unsafe { self.forces_energy_generic(x, f, runs, loose) }
    }

    /// Safety: every spring index is below `x.len()` and `f.len()`.
    #[inline(always)]
    unsafe fn forces_energy_generic(
        &self,
        x: &[Vec3],
        f: &mut [Vec3],
        runs: std::ops::Range<usize>,
        loose: std::ops::Range<usize>,
    ) -> f64 {
        let mut energy = 0.0;
        let (xf, ff) = (super::flat(x), super::flat_mut(f));
        for run in &self.runs {
            // The part of this run inside the range of run springs.
            let lo = runs.start.max(run.first);
            let hi = runs.end.min(run.first + run.len);
            let mut s = lo;
            while s < hi {
                let m = CHUNK.min(hi - s);
                let r = s - run.first;
                let (a, b) = (3 * (run.i0 + r), 3 * (run.j0 + r));
                energy += run_chunk(xf, ff, (a, b), &self.rest[s..s + m], &self.k[s..s + m]);
                s += m;
            }
        }
        let (springs, k) = (&self.loose[loose.clone()], &self.loose_k[loose]);
        // SAFETY: forwarded from the caller.
        energy + unsafe { blocks(x, f, springs, k) }
    }
}

/// One chunk of a run: springs from flat offsets `a` (first endpoints) and `b` (second
/// endpoints) onwards, `rest.len()` of them. Returns their energy.
#[inline(always)]
fn run_chunk(x: &[f64], f: &mut [f64], (a, b): (usize, usize), rest: &[f64], k: &[f64]) -> f64 {
    let m = rest.len();
    let mut d = [0.0; 3 * CHUNK];
    let d = &mut d[..3 * m];
    for ((dj, &p), &q) in d.iter_mut().zip(&x[a..a + 3 * m]).zip(&x[b..b + 3 * m]) {
        *dj = p - q;
    }
    let mut len2 = [0.0; CHUNK];
    for (l, v) in len2.iter_mut().zip(d.chunks_exact(3)) {
        *l = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    }
    let mut scale = [0.0; CHUNK];
    let energy = scale_energy(&len2[..m], rest, k, &mut scale[..m]);
    let mut fi = [0.0; 3 * CHUNK];
    let fi = &mut fi[..3 * m];
    for ((o, v), &s) in fi.chunks_exact_mut(3).zip(d.chunks_exact(3)).zip(&scale) {
        o[0] = v[0] * s;
        o[1] = v[1] * s;
        o[2] = v[2] * s;
    }
    for (fj, &v) in f[a..a + 3 * m].iter_mut().zip(fi.iter()) {
        *fj += v;
    }
    for (fj, &v) in f[b..b + 3 * m].iter_mut().zip(fi.iter()) {
        *fj -= v;
    }
    energy
}

/// Per spring, from the squared length: the force scale `-k (L - l) / L` (zero when `L = 0`:
/// coincident endpoints have no direction and, by symmetry, no net force) and the energy
/// `k/2 (L - l)^2`, summed in four lanes.
#[inline(always)]
fn scale_energy(len2: &[f64], rest: &[f64], k: &[f64], scale: &mut [f64]) -> f64 {
    let mut energy = [0.0; LANES];
    let n = len2.len() / LANES * LANES;
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        use std::arch::x86_64::*;
        // SAFETY: AVX is available (checked above); every load and store covers
        // `[q, q + 4)` with `q + 4 <= n <=` the length of each slice, or a local array.
        unsafe {
            let zero = _mm256_setzero_pd();
            let half = _mm256_set1_pd(0.5);
            let mut acc = zero;
            for q in (0..n).step_by(LANES) {
                let len = _mm256_sqrt_pd(_mm256_loadu_pd(len2.as_ptr().add(q)));
                let kv = _mm256_loadu_pd(k.as_ptr().add(q));
                let e = _mm256_sub_pd(len, _mm256_loadu_pd(rest.as_ptr().add(q)));
                let s = _mm256_div_pd(_mm256_mul_pd(_mm256_sub_pd(zero, kv), e), len);
                let positive = _mm256_cmp_pd::<_CMP_GT_OQ>(len, zero);
                _mm256_storeu_pd(scale.as_mut_ptr().add(q), _mm256_and_pd(s, positive));
                let el = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(half, kv), e), e);
                acc = _mm256_add_pd(acc, el);
            }
            _mm256_storeu_pd(energy.as_mut_ptr(), acc);
        }
        return lanes_and_tail(energy, len2, rest, k, scale, n);
    }
    for q in (0..n).step_by(LANES) {
        for l in 0..LANES {
            let e = spring_scalar(len2[q + l], rest[q + l], k[q + l], &mut scale[q + l]);
            energy[l] += 0.5 * k[q + l] * e * e;
        }
    }
    lanes_and_tail(energy, len2, rest, k, scale, n)
}

/// Sums the lane energies and handles the springs from `from` on one by one.
#[inline(always)]
fn lanes_and_tail(
    energy: [f64; LANES],
    len2: &[f64],
    rest: &[f64],
    k: &[f64],
    scale: &mut [f64],
    from: usize,
) -> f64 {
    let mut tail = 0.0;
    for q in from..len2.len() {
        let e = spring_scalar(len2[q], rest[q], k[q], &mut scale[q]);
        tail += 0.5 * k[q] * e * e;
    }
    (energy[0] + energy[1]) + (energy[2] + energy[3]) + tail
}

/// One spring's extension `L - l` from its squared length, and its force scale (to `scale`).
#[inline(always)]
fn spring_scalar(len2: f64, rest: f64, k: f64, scale: &mut f64) -> f64 {
    let len = len2.sqrt();
    let e = len - rest;
    *scale = if len > 0.0 { -k * e / len } else { 0.0 };
    e
}

/// The gather/scatter loop over blocks of four springs, for springs in no long run.
///
/// Safety: every spring index is below `x.len()` and `f.len()`.
#[inline(always)]
unsafe fn blocks(x: &[Vec3], f: &mut [Vec3], springs: &[Spring], k: &[f64]) -> f64 {
    let mut energy = 0.0;
    for (sb, kb) in springs.chunks_exact(LANES).zip(k.chunks_exact(LANES)) {
        let mut d = [Vec3::ZERO; LANES];
        let (mut len2, mut rest) = ([0.0; LANES], [0.0; LANES]);
        for l in 0..LANES {
            let s = &sb[l];
            // SAFETY: indices below x.len() (function contract).
            d[l] = unsafe { *x.get_unchecked(s.i as usize) - *x.get_unchecked(s.j as usize) };
            len2[l] = d[l].x * d[l].x + d[l].y * d[l].y + d[l].z * d[l].z;
            rest[l] = s.rest;
        }
        let mut scale = [0.0; LANES];
        energy += scale_energy(&len2, &rest, kb, &mut scale);
        for l in 0..LANES {
            let s = &sb[l];
            let fi = d[l] * scale[l];
            // SAFETY: indices below f.len() (function contract).
            unsafe {
                *f.get_unchecked_mut(s.i as usize) += fi;
                *f.get_unchecked_mut(s.j as usize) -= fi;
            }
        }
    }
    let tail = springs.len() / LANES * LANES;
    for (s, &kl) in springs[tail..].iter().zip(&k[tail..]) {
        let d = x[s.i as usize] - x[s.j as usize];
        let mut scale = 0.0;
        let e = spring_scalar(d.length_squared(), s.rest, kl, &mut scale);
        f[s.i as usize] += d * scale;
        f[s.j as usize] -= d * scale;
        energy += 0.5 * kl * e * e;
    }
    energy
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Springs of a 7x5 lattice (rows, columns, both diagonals, skip-one) in lattice order, plus
    /// a few irregular ones, at a deformed state: the layout's forces and energy match a plain
    /// loop over the springs to rounding, for one and two parts.
    #[test]
    fn layout_matches_a_plain_loop() {
        let (nu, nv) = (7usize, 5usize);
        let id = |i: usize, j: usize| (j * nu + i) as u32;
        let mut springs = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                for (di, dj) in [(1isize, 0isize), (0, 1), (1, 1), (-1, 1), (2, 0)] {
                    let (a, b) = (i as isize + di, j as isize + dj);
                    if (0..nu as isize).contains(&a) && (0..nv as isize).contains(&b) {
                        let rest = 0.1 * ((di * di + dj * dj) as f64).sqrt();
                        springs.push(Spring {
                            i: id(i, j),
                            j: id(a as usize, b as usize),
                            rest,
                        });
                    }
                }
            }
        }
        springs.push(Spring {
            i: 3,
            j: 30,
            rest: 0.4,
        });
        springs.push(Spring {
            i: 30,
            j: 3,
            rest: 0.4,
        });
        // Coincident endpoints (below) must give no force.
        springs.push(Spring {
            i: 8,
            j: 9,
            rest: 0.1,
        });
        let k: Vec<f64> = (0..springs.len()).map(|s| 100.0 + s as f64).collect();
        let mut x: Vec<Vec3> = (0..nu * nv)
            .map(|v| {
                let (i, j) = ((v % nu) as f64, (v / nu) as f64);
                Vec3::new(0.1 * i + 0.01 * j.sin(), 0.1 * j, 0.02 * (i * j).cos())
            })
            .collect();
        x[9] = x[8];
        let layout = SpringLayout::new(&springs, &k);
        assert!(!layout.runs.is_empty() && !layout.loose.is_empty());
        assert_eq!(layout.rest.len() + layout.loose.len(), springs.len());

        let mut reference = vec![Vec3::ZERO; x.len()];
        let mut e_ref = 0.0;
        for (s, &kl) in springs.iter().zip(&k) {
            let d = x[s.i as usize] - x[s.j as usize];
            let len = d.length();
            let e = len - s.rest;
            let fi = if len > 0.0 {
                d * (-kl * e / len)
            } else {
                Vec3::ZERO
            };
            reference[s.i as usize] += fi;
            reference[s.j as usize] -= fi;
            e_ref += 0.5 * kl * e * e;
        }
        for parts in [1, 2] {
            let mut f = vec![Vec3::ZERO; x.len()];
            let energy: f64 = (0..parts)
                .map(|p| layout.forces_energy(&x, &mut f, p, parts))
                .sum();
            // Same terms in another order: a few ulps of the largest force (about k * 0.1).
            let scale = reference.iter().map(|v| v.length()).fold(0.0, f64::max);
            for (a, b) in f.iter().zip(&reference) {
                assert!((*a - *b).length() <= 1e-13 * scale, "{a} vs {b}");
            }
            assert!(
                (energy - e_ref).abs() <= 1e-13 * e_ref,
                "{energy} vs {e_ref}"
            );
        }
    }
}
