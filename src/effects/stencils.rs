//! Bending (second derivative along warp or weft) and twist (mixed derivative) as quadratic
//! energies of linear finite-difference stencils: `E = c/2 |sum_k w_k x_k|^2`.
//!
//! Being quadratic, their forces are linear in positions and their Jacobians are constant
//! (`-c w_a w_b I`), which the implicit solver handles exactly. Separate warp and weft rigidities
//! give anisotropic cloth, as in the survey's figure of four materials.

use super::effect::{Effect, State, StiffnessBound};
use crate::cloth::topology::Stencil;
use crate::linalg::{BlockCsr, PatternBuilder};
use crate::{Mat3, Vec3};

/// A set of stencils of one size with one rigidity per stencil: bending (`N = 3`) or twist (`N = 4`).
pub struct StencilSet<const N: usize> {
    name: &'static str,
    stencils: Vec<Stencil<N>>,
    c: Vec<f64>,
    parameter: String,
    /// The stencils grouped into runs for the force pass.
    runs: Vec<Run<N>>,
}

/// Consecutive stencils with the same weights and rigidity whose vertex indices all step by one
/// from a stencil to the next (on a lattice, a row of warp stencils or all weft stencils): the
/// force pass treats a run as contiguous slices of positions and forces, loops the compiler
/// vectorises, with no index lookups.
#[derive(Debug, Clone, PartialEq)]
struct Run<const N: usize> {
    /// Index of the run's first stencil.
    first: usize,
    len: usize,
    /// Vertex indices of the first stencil.
    idx: [usize; N],
    w: [f64; N],
    c: f64,
}

/// Groups `stencils` into maximal runs (see [`Run`]).
fn runs<const N: usize>(stencils: &[Stencil<N>], c: &[f64]) -> Vec<Run<N>> {
    let mut out: Vec<Run<N>> = Vec::new();
    for (k, (s, &ck)) in stencils.iter().zip(c).enumerate() {
        let idx = s.idx.map(|i| i as usize);
        if let Some(r) = out.last_mut() {
            let continues = r.w == s.w
                && r.c.to_bits() == ck.to_bits()
                && (0..N).all(|a| idx[a] == r.idx[a] + r.len);
            if continues {
                r.len += 1;
                continue;
            }
        }
        out.push(Run {
            first: k,
            len: 1,
            idx,
            w: s.w,
            c: ck,
        });
    }
    out
}

/// Second derivative along warp and/or weft.
pub type Bending = StencilSet<3>;
/// The mixed second derivative `d2r/du dv`.
pub type Twist = StencilSet<4>;

impl Bending {
    pub fn new(stencils: Vec<Stencil<3>>, rigidity: Vec<f64>, parameter: String) -> Self {
        StencilSet {
            name: "bending",
            runs: runs(&stencils, &rigidity),
            stencils,
            c: rigidity,
            parameter,
        }
    }
}

impl Twist {
    pub fn new(stencils: Vec<Stencil<4>>, rigidity: Vec<f64>, parameter: String) -> Self {
        StencilSet {
            name: "twist",
            runs: runs(&stencils, &rigidity),
            stencils,
            c: rigidity,
            parameter,
        }
    }
}

impl<const N: usize> StencilSet<N> {
    fn declare(&self, p: &mut PatternBuilder) {
        for s in &self.stencils {
            p.couple_all(&s.idx);
        }
    }

    /// Adds the forces `-c w_k d` and returns the energy `sum c/2 |d|^2`, `d = sum_k w_k x_k`,
    /// of the `part`-th of `parts` slices of the stencils.
    fn add_forces(&self, x: &[Vec3], f: &mut [Vec3], part: usize, parts: usize) -> f64 {
        let r = crate::par::part_range(self.stencils.len(), part, parts);
        let (x, f) = (crate::linalg::flat(x), crate::linalg::flat_mut(f));
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { runs_forces_energy_avx2(x, f, &self.runs, r) };
        }
        runs_forces_energy(x, f, &self.runs, r)
    }

    fn add_jacobians(&self, dfdx: &mut BlockCsr) {
        for (s, &c) in self.stencils.iter().zip(&self.c) {
            for a in 0..N {
                for b in 0..N {
                    dfdx.add(s.idx[a], s.idx[b], Mat3::IDENTITY * (-c * s.w[a] * s.w[b]));
                }
            }
        }
    }

    fn energy(&self, x: &[Vec3]) -> f64 {
        self.stencils
            .iter()
            .zip(&self.c)
            .map(|(s, &c)| {
                let mut d = Vec3::ZERO;
                for k in 0..N {
                    d += x[s.idx[k] as usize] * s.w[k];
                }
                0.5 * c * d.length_squared()
            })
            .sum()
    }

    fn stiffness(&self, mass: &[f64]) -> Option<StiffnessBound> {
        let mut row = vec![0.0; mass.len()];
        for (s, &c) in self.stencils.iter().zip(&self.c) {
            let wsum: f64 = s.w.iter().map(|w| w.abs()).sum();
            for k in 0..N {
                row[s.idx[k] as usize] += c * s.w[k].abs() * wsum;
            }
        }
        let (vertex, omega_sq) = row
            .iter()
            .zip(mass)
            .map(|(r, m)| r / m)
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        Some(StiffnessBound {
            omega_sq,
            vertex,
            parameter: self.parameter.clone(),
        })
    }
}

/// [`runs_forces_energy`] compiled for AVX2 (4 f64 lanes). Rust never fuses a multiply and an add
/// on its own, so the results are bitwise those of the baseline build.
///
/// Safety: AVX2 is available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn runs_forces_energy_avx2<const N: usize>(
    x: &[f64],
    f: &mut [f64],
    runs: &[Run<N>],
    range: std::ops::Range<usize>,
) -> f64 {
    runs_forces_energy(x, f, runs, range)
}

/// Stencils per chunk of a run (the chunk's differences `d` live on the stack).
const CHUNK: usize = 64;

/// Forces and energy of the stencils with indices in `range`, run by run, on flat positions `x`
/// and forces `f`. Per stencil the arithmetic is that of the plain loop (`d = sum w_k x_k` in
/// order, `f_k -= d (c w_k)`); only the order in which contributions reach a vertex, and the
/// energy's summation order, differ. That order is fixed by the chunks: within a chunk, a force
/// component receives its terms in ascending `k`, chunk after chunk.
#[inline(always)]
fn runs_forces_energy<const N: usize>(
    x: &[f64],
    f: &mut [f64],
    runs: &[Run<N>],
    range: std::ops::Range<usize>,
) -> f64 {
    let mut energy = 0.0;
    let mut d = [0.0; 3 * CHUNK];
    for run in runs {
        // The part of this run inside `range`.
        let lo = range.start.max(run.first);
        let hi = range.end.min(run.first + run.len);
        let mut start = lo;
        while start < hi {
            let m = CHUNK.min(hi - start);
            let (d, at) = (&mut d[..3 * m], 3 * (start - run.first));
            // Flat index of the chunk's first component in each stencil slot's span.
            let base = run.idx.map(|i| 3 * i + at);
            let xs = base.map(|b| &x[b..b + 3 * m]);
            // d = ((0 + w0 x0) + w1 x1) + ..., one pass.
            for (j, dj) in d.iter_mut().enumerate() {
                let mut acc = 0.0 + xs[0][j] * run.w[0];
                for k in 1..N {
                    acc += xs[k][j] * run.w[k];
                }
                *dj = acc;
            }
            let cw = run.w.map(|w| run.c * w);
            subtract_spans(f, d, &base, &cw);
            let mut sq = [0.0; 4];
            let quads = d.chunks_exact(4);
            let rest: f64 = quads.remainder().iter().map(|v| v * v).sum();
            for q in quads {
                for l in 0..4 {
                    sq[l] += q[l] * q[l];
                }
            }
            energy += 0.5 * run.c * ((sq[0] + sq[1]) + (sq[2] + sq[3]) + rest);
            start += m;
        }
    }
    energy
}

/// `f[base[k] + j] -= d[j] * cw[k]` for every slot `k` and `j < d.len()`, with the terms of
/// each component of `f` applied in ascending `k` (as `N` passes one slot after the other would),
/// but in one pass per stretch of `f` that the same slots cover: each component is loaded and
/// stored once, instead of once per slot through overlapping spans (whose stores the next
/// slot's loads would wait on).
#[inline(always)]
fn subtract_spans<const N: usize>(f: &mut [f64], d: &[f64], base: &[usize; N], cw: &[f64; N]) {
    let len = d.len();
    // Stretches between consecutive span ends; each is covered by a fixed set of slots.
    let mut cuts = [0usize; 8];
    for k in 0..N {
        (cuts[2 * k], cuts[2 * k + 1]) = (base[k], base[k] + len);
    }
    let cuts = &mut cuts[..2 * N];
    cuts.sort_unstable();
    for w in cuts.windows(2) {
        let (s, e) = (w[0], w[1]);
        if s == e {
            continue;
        }
        let mut mask = 0u32;
        for k in 0..N {
            if base[k] <= s && e <= base[k] + len {
                mask |= 1 << k;
            }
        }
        if mask == 0 {
            // A gap between spans (the stretch may be longer than `d`).
            continue;
        }
        let fs = &mut f[s..e];
        // The slots' differences over this stretch (unused slots get any slice of that length: a covered stretch is no longer than `d`).
        let ds: [&[f64]; N] = std::array::from_fn(|k| {
            if mask & (1 << k) != 0 {
                &d[s - base[k]..e - base[k]]
            } else {
                &d[..e - s]
            }
        });
        macro_rules! dispatch {
            ($($m:literal)*) => {
                match mask {
                    $($m => subtract_stretch::<N, $m>(fs, &ds, cw),)*
                    _ => {}
                }
            };
        }
        dispatch!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
    }
}

/// `fs[j] -= ds[k][j] * cw[k]` for the slots `k` in `MASK`, in ascending `k` (all `ds[k]` as
/// long as `fs`).
#[inline(always)]
fn subtract_stretch<const N: usize, const MASK: u32>(
    fs: &mut [f64],
    ds: &[&[f64]; N],
    cw: &[f64; N],
) {
    let n = fs.len();
    let ds: [&[f64]; N] = ds.map(|d| &d[..n]);
    for j in 0..n {
        let mut a = fs[j];
        for k in 0..N {
            if MASK & (1 << k) != 0 {
                a -= ds[k][j] * cw[k];
            }
        }
        fs[j] = a;
    }
}

impl<const N: usize> Effect for StencilSet<N> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn declare(&self, p: &mut PatternBuilder) {
        StencilSet::declare(self, p)
    }
    fn position_only(&self) -> bool {
        true
    }
    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        StencilSet::add_forces(self, s.x, f, 0, 1);
    }
    fn add_forces_energy(&self, s: &State, f: &mut [Vec3]) -> f64 {
        StencilSet::add_forces(self, s.x, f, 0, 1)
    }
    fn add_forces_energy_part(&self, s: &State, f: &mut [Vec3], part: usize, parts: usize) -> f64 {
        StencilSet::add_forces(self, s.x, f, part, parts)
    }
    fn add_jacobians(&self, _s: &State, dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {
        StencilSet::add_jacobians(self, dfdx)
    }
    fn constant_jacobians(&self) -> bool {
        true
    }
    fn energy(&self, x: &[Vec3]) -> f64 {
        StencilSet::energy(self, x)
    }
    fn stiffness(&self, mass: &[f64]) -> Option<StiffnessBound> {
        StencilSet::stiffness(self, mass)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The former force pass: per chunk, one pass per stencil slot over its span.
    fn per_slot_reference<const N: usize>(x: &[f64], f: &mut [f64], runs: &[Run<N>]) {
        for run in runs {
            let mut start = run.first;
            while start < run.first + run.len {
                let m = CHUNK.min(run.first + run.len - start);
                let at = 3 * (start - run.first);
                let span = |k: usize| 3 * run.idx[k] + at..3 * run.idx[k] + at + 3 * m;
                let mut d = vec![0.0; 3 * m];
                for (dj, &xj) in d.iter_mut().zip(&x[span(0)]) {
                    *dj = 0.0 + xj * run.w[0];
                }
                for k in 1..N {
                    for (dj, &xj) in d.iter_mut().zip(&x[span(k)]) {
                        *dj += xj * run.w[k];
                    }
                }
                for k in 0..N {
                    let cw = run.c * run.w[k];
                    for (fj, &dj) in f[span(k)].iter_mut().zip(&d) {
                        *fj -= dj * cw;
                    }
                }
                start += m;
            }
        }
    }

    /// Warp, weft and twist stencils of a 70 x 9 lattice (runs longer than a chunk, spans that
    /// overlap within a chunk and spans apart): the one-pass-per-stretch forces are bitwise
    /// those of the per-slot passes, for a nonzero starting force.
    #[test]
    fn one_pass_per_stretch_matches_per_slot_passes_bitwise() {
        let (nu, nv) = (70usize, 9usize);
        let id = |i: usize, j: usize| (j * nu + i) as u32;
        let x: Vec<f64> = (0..3 * nu * nv)
            .map(|k| ((k * 7919) % 1013) as f64 * 1e-3 - 0.4)
            .collect();
        let f0: Vec<f64> = (0..3 * nu * nv).map(|k| (k % 17) as f64 * 0.3).collect();
        let mut bend = Vec::new();
        for j in 0..nv {
            for i in 1..nu - 1 {
                bend.push(Stencil {
                    idx: [id(i - 1, j), id(i, j), id(i + 1, j)],
                    w: [1.3, -2.6, 1.3],
                });
            }
        }
        for j in 1..nv - 1 {
            for i in 0..nu {
                bend.push(Stencil {
                    idx: [id(i, j - 1), id(i, j), id(i, j + 1)],
                    w: [0.7, -1.4, 0.7],
                });
            }
        }
        let c = vec![0.37; bend.len()];
        let r3 = runs(&bend, &c);
        let mut twist = Vec::new();
        for j in 0..nv - 1 {
            for i in 0..nu - 1 {
                twist.push(Stencil {
                    idx: [id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)],
                    w: [0.5, -0.5, -0.5, 0.5],
                });
            }
        }
        let r4 = runs(&twist, &vec![0.11; twist.len()]);
        assert!(r3.iter().any(|r| r.len > CHUNK) && r4.len() > 1);

        let (mut want, mut got) = (f0.clone(), f0.clone());
        per_slot_reference(&x, &mut want, &r3);
        runs_forces_energy(&x, &mut got, &r3, 0..bend.len());
        assert_eq!(got, want);
        let (mut want, mut got) = (f0.clone(), f0.clone());
        per_slot_reference(&x, &mut want, &r4);
        runs_forces_energy(&x, &mut got, &r4, 0..twist.len());
        assert_eq!(got, want);
        assert_ne!(got, f0);
    }
}
