//! Springs between vertex pairs: stretch (warp/weft edges), shear (diagonals) and skip-one.
//!
//! Energy `k/2 (L - l)^2` with `L = |xi - xj|`. The Jacobian is the usual
//! `-k [n n^T + (1 - l/L)(I - n n^T)]`, with the transverse term clamped at zero under compression
//! (Choi and Ko): keeping it would make the system matrix indefinite and break conjugate gradients.
//!
//! A material with a knee (`stretch_knee`, [`Knee`]) adds to each spring a one-sided spring of
//! stiffness `(r - 1) k` that engages past the knee extension `s l`: tension
//! `T = k e + (r - 1) k max(0, e - s l)` with its tangent rising linearly from `k` at the knee
//! to `r k` at [`KNEE_RISE`] of the knee strain past it (a J-curve: force and tangent
//! continuous). The Jacobian carries that tangent along the spring and `T / L` across it, so the
//! implicit solve itself holds edges near `1 + s`. Springs without a knee take the plain pass
//! (the knee pass is never run for them).

use super::effect::{Effect, State, StiffnessBound};
use crate::cloth::topology::Spring;
use crate::linalg::outer;
use crate::linalg::{BlockCsr, PairSlots, PatternBuilder};
use crate::{Mat3, Vec3};
use std::ops::Range;

/// Where a spring stiffens: past `strain` (of its rest length) its tangent stiffness is `ratio`
/// times its own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knee {
    pub strain: f64,
    pub ratio: f64,
}

/// How far past the knee the stiffening takes to reach its full ratio, as a share of the knee
/// strain: the one-sided spring's tangent rises linearly from 0 at the knee to `(r - 1) k` at
/// `(1 + KNEE_RISE) s l`, so the law is a J-curve with a continuous tangent instead of a kink
/// (woven fabric's tensile curve bends over a few percent of strain as its yarns straighten),
/// and stays linear below the knee. Newton iterations on a kinked law cycle: springs at the knee
/// flip between the two tangents from one iterate to the next. Over S1's first 120 frames
/// (`benches/scenes/bench_s1.yaml`, a 3 % knee, 62 to 66 vertices a side) a kink costs 1.43x
/// the linear material's CG iterations, this rise 1.22x, and edges end within 1.04. A rise that
/// starts below the knee costs the hanging cloth (S2) instead: springs short of the knee turn
/// stiff, the multigrid's aggregates follow them, and each V-cycle costs more.
pub const KNEE_RISE: f64 = 0.25;

/// A spring's knee in the units of the force pass: the extension `s l` (m) past which the
/// extra stiffness `(r - 1) k` (N/m) engages, rising over `rise` (m). No knee: an infinite
/// extension, no extra.
#[derive(Debug, Clone, Copy, PartialEq)]
struct KneeAt {
    extension: f64,
    extra: f64,
    rise: f64,
}

impl KneeAt {
    const NONE: KneeAt = KneeAt {
        extension: f64::INFINITY,
        extra: 0.0,
        rise: 0.0,
    };

    fn of(knee: Option<Knee>, rest: f64, k: f64) -> Self {
        match knee {
            Some(n) if n.ratio > 1.0 => KneeAt {
                extension: n.strain * rest,
                extra: (n.ratio - 1.0) * k,
                rise: KNEE_RISE * n.strain * rest,
            },
            _ => KneeAt::NONE,
        }
    }

    /// The one-sided spring's stretch (m) at extension `e`, `u = e - s l` past the knee: 0
    /// below it, `u^2 / (2 rise)` while its stiffness rises, `u - rise / 2` past that.
    #[inline(always)]
    fn over(&self, e: f64) -> f64 {
        let (u, w) = (e - self.extension, self.rise);
        if u <= 0.0 {
            0.0
        } else if u < w {
            u * u / (2.0 * w)
        } else {
            u - 0.5 * w
        }
    }

    /// `d over / de`: 0 below the knee, rising to 1.
    #[inline(always)]
    fn slope(&self, e: f64) -> f64 {
        let (u, w) = (e - self.extension, self.rise);
        if u <= 0.0 {
            0.0
        } else if u < w {
            u / w
        } else {
            1.0
        }
    }

    /// Tension `k e + extra over(e)` (N) at extension `e`.
    #[inline(always)]
    fn tension(&self, k: f64, e: f64) -> f64 {
        k * e + self.extra * self.over(e)
    }

    /// Energy `k e^2 / 2 + extra int over` (J): the integral is `u^3 / (6 rise)` while the
    /// stiffness rises and `u^2 / 2 - rise u / 2 + rise^2 / 6` past that.
    #[inline(always)]
    fn energy(&self, k: f64, e: f64) -> f64 {
        let (u, w) = (e - self.extension, self.rise);
        let ramp = if u <= 0.0 {
            0.0
        } else if u < w {
            u * u * u / (6.0 * w)
        } else {
            0.5 * u * u - 0.5 * w * u + w * w / 6.0
        };
        0.5 * k * e * e + self.extra * ramp
    }

    /// Tangent stiffness `dT/de` (N/m).
    #[inline(always)]
    fn tangent(&self, k: f64, e: f64) -> f64 {
        k + self.extra * self.slope(e)
    }
}

pub struct Springs {
    name: &'static str,
    springs: Vec<Spring>,
    k: Vec<f64>,
    /// Per spring, where a material stiffens it; `None` where no spring has a knee.
    knee: Option<Vec<KneeAt>>,
    /// One past the largest vertex index: the force pass checks it once against the slices and
    /// then indexes without per-spring bounds checks.
    vertex_bound: usize,
    /// Scene parameter per spring group, for diagnostics.
    parameter: String,
    /// Jacobian block slots of every spring (no search per step).
    slots: PairSlots,
}

impl Springs {
    /// `name` is the effect's scene name (`stretch`, `shear`, `skip_one`); `k` is per spring.
    pub fn new(name: &'static str, springs: Vec<Spring>, k: Vec<f64>, parameter: String) -> Self {
        debug_assert_eq!(springs.len(), k.len());
        let vertex_bound = springs
            .iter()
            .map(|s| s.i.max(s.j) as usize + 1)
            .max()
            .unwrap_or(0);
        Self {
            name,
            springs,
            k,
            knee: None,
            vertex_bound,
            parameter,
            slots: PairSlots::default(),
        }
    }

    /// These springs with the knees `knee` (one per spring, `None` for a linear one, or empty
    /// when none has one; see [`Knee`]). Springs none of which has a knee stay on the linear
    /// pass.
    pub fn with_knee(mut self, knee: &[Option<Knee>]) -> Self {
        if knee.iter().all(Option::is_none) {
            return self;
        }
        debug_assert_eq!(knee.len(), self.springs.len());
        let at: Vec<KneeAt> = (self.springs.iter().zip(&self.k))
            .zip(knee.iter().chain(std::iter::repeat(&None)))
            .map(|((s, &k), n)| KneeAt::of(*n, s.rest, k))
            .collect();
        self.knee = at.iter().any(|a| a.extra > 0.0).then_some(at);
        self
    }

    /// The tension (N) and extension (m) law of spring `q` at extension `e`: `(T, dT/de)`.
    #[inline(always)]
    fn law(&self, q: usize, e: f64) -> (f64, f64) {
        let k = self.k[q];
        match &self.knee {
            Some(at) => (at[q].tension(k, e), at[q].tangent(k, e)),
            None => (k * e, k),
        }
    }

    /// Forces and energy of the springs in `r` with their knees (the knee pass: scalar, one
    /// spring at a time).
    fn knee_forces_energy(
        &self,
        at: &[KneeAt],
        x: &[Vec3],
        f: &mut [Vec3],
        r: Range<usize>,
    ) -> f64 {
        let mut energy = 0.0;
        for q in r {
            let (s, k, a) = (&self.springs[q], self.k[q], &at[q]);
            let d = x[s.i as usize] - x[s.j as usize];
            let len = d.length();
            let e = len - s.rest;
            let fi = if len > 0.0 {
                d * (-a.tension(k, e) / len)
            } else {
                Vec3::ZERO
            };
            f[s.i as usize] += fi;
            f[s.j as usize] -= fi;
            energy += a.energy(k, e);
        }
        energy
    }

    pub fn len(&self) -> usize {
        self.springs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.springs.is_empty()
    }
}

/// Force on `i` and the extension `L - l` of one spring. Coincident endpoints have no direction
/// and, by symmetry, no net force (branch-free: the select compiles to a conditional move).
#[inline(always)]
fn tension(x: &[Vec3], s: &Spring, k: f64) -> (Vec3, f64) {
    let d = x[s.i as usize] - x[s.j as usize];
    let len = d.length();
    let e = len - s.rest;
    let scale = if len > 0.0 { -k * e / len } else { 0.0 };
    (d * scale, e)
}

/// Springs per block of the force pass: their arithmetic runs in SIMD lanes, the gathers and
/// scatters around it stay in spring order (so the forces are bitwise those of a plain loop).
const LANES: usize = 4;

/// Adds the forces of `springs` (stiffness `k`) to `f` and returns their energy.
///
/// Every index of `springs` is below `bound` (computed at construction); `x` and `f` are checked
/// against `bound` once here, which is what makes the unchecked indexing below sound.
fn forces_energy(x: &[Vec3], f: &mut [Vec3], springs: &[Spring], k: &[f64], bound: usize) -> f64 {
    assert!(
        x.len() >= bound && f.len() >= bound && springs.len() == k.len(),
        "springs reach vertex {} but the state has {} positions and {} forces",
        bound.saturating_sub(1),
        x.len(),
        f.len()
    );
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above); indices were checked above.
        return unsafe { forces_energy_avx2(x, f, springs, k) };
    }
    // SAFETY: every index is below `bound`, checked above against both slices.
    unsafe { forces_energy_blocks(x, f, springs, k) }
}

/// [`forces_energy_blocks`] with the lane arithmetic in AVX registers (4 f64 lanes). Each lane
/// does the scalar code's operations in the same order, without fused multiply-adds, so the
/// forces are bitwise those of the scalar loop (only the energy's summation order differs).
///
/// Safety: AVX2 is available, and the contract of [`forces_energy_blocks`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn forces_energy_avx2(x: &[Vec3], f: &mut [Vec3], springs: &[Spring], k: &[f64]) -> f64 {
    use std::arch::x86_64::*;
    let mut energy = _mm256_setzero_pd();
    let (zero, half) = (_mm256_setzero_pd(), _mm256_set1_pd(0.5));
    // Components as flat f64: vertex `v` is at `3 v`, its (x, y) pair loads as one 128-bit value.
    let xp = x.as_ptr().cast::<f64>();
    let fp = f.as_mut_ptr().cast::<f64>();
    for (sb, kb) in springs.chunks_exact(LANES).zip(k.chunks_exact(LANES)) {
        let ii: [usize; LANES] = std::array::from_fn(|l| 3 * sb[l].i as usize);
        let jj: [usize; LANES] = std::array::from_fn(|l| 3 * sb[l].j as usize);
        // SAFETY: every `3 i + 2`, `3 j + 2` is inside `x` and `f` (indices below their lengths,
        // function contract); the loads and stores below touch only those components.
        unsafe {
            // d = x_i - x_j per spring, as (x, y) pairs and z scalars, then transposed to one
            // vector per component with the springs in lane order.
            let dxy: [__m128d; LANES] = std::array::from_fn(|l| {
                _mm_sub_pd(_mm_loadu_pd(xp.add(ii[l])), _mm_loadu_pd(xp.add(jj[l])))
            });
            let dz: [__m128d; LANES] = std::array::from_fn(|l| {
                _mm_sub_sd(
                    _mm_load_sd(xp.add(ii[l] + 2)),
                    _mm_load_sd(xp.add(jj[l] + 2)),
                )
            });
            let pair =
                |a: __m128d, b: __m128d| _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(a), b);
            let (t02, t13) = (pair(dxy[0], dxy[2]), pair(dxy[1], dxy[3]));
            let vx = _mm256_unpacklo_pd(t02, t13);
            let vy = _mm256_unpackhi_pd(t02, t13);
            let vz = pair(_mm_unpacklo_pd(dz[0], dz[1]), _mm_unpacklo_pd(dz[2], dz[3]));
            let kv = _mm256_loadu_pd(kb.as_ptr());
            let rest = _mm256_set_pd(sb[3].rest, sb[2].rest, sb[1].rest, sb[0].rest);
            let len2 = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(vx, vx), _mm256_mul_pd(vy, vy)),
                _mm256_mul_pd(vz, vz),
            );
            let len = _mm256_sqrt_pd(len2);
            let e = _mm256_sub_pd(len, rest);
            // -k e / len, zeroed where len = 0 (coincident endpoints: no direction, no force).
            let q = _mm256_div_pd(_mm256_mul_pd(_mm256_sub_pd(zero, kv), e), len);
            let positive = _mm256_cmp_pd::<_CMP_GT_OQ>(len, zero);
            let scale = _mm256_and_pd(q, positive);
            let el = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(half, kv), e), e);
            energy = _mm256_add_pd(energy, el);
            // f_i = d scale, back to (x, y) pairs and z scalars per spring.
            let (fx, fy, fz) = (
                _mm256_mul_pd(vx, scale),
                _mm256_mul_pd(vy, scale),
                _mm256_mul_pd(vz, scale),
            );
            let (lo, hi) = (_mm256_unpacklo_pd(fx, fy), _mm256_unpackhi_pd(fx, fy));
            let fxy = [
                _mm256_castpd256_pd128(lo),
                _mm256_castpd256_pd128(hi),
                _mm256_extractf128_pd::<1>(lo),
                _mm256_extractf128_pd::<1>(hi),
            ];
            let (z01, z23) = (_mm256_castpd256_pd128(fz), _mm256_extractf128_pd::<1>(fz));
            let fzs = [
                z01,
                _mm_unpackhi_pd(z01, z01),
                z23,
                _mm_unpackhi_pd(z23, z23),
            ];
            // Scatter in spring order: f_i += f, f_j -= f.
            for l in 0..LANES {
                let (pi, pj) = (fp.add(ii[l]), fp.add(jj[l]));
                _mm_storeu_pd(pi, _mm_add_pd(_mm_loadu_pd(pi), fxy[l]));
                _mm_store_sd(pi.add(2), _mm_add_sd(_mm_load_sd(pi.add(2)), fzs[l]));
                _mm_storeu_pd(pj, _mm_sub_pd(_mm_loadu_pd(pj), fxy[l]));
                _mm_store_sd(pj.add(2), _mm_sub_sd(_mm_load_sd(pj.add(2)), fzs[l]));
            }
        }
    }
    let mut lanes = [0.0; 4];
    // SAFETY: store to a local 4-element array.
    unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), energy) };
    let tail = springs.len() / LANES * LANES;
    let tail_energy = tail_forces_energy(x, f, &springs[tail..], &k[tail..]);
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + tail_energy
}

/// Springs that do not fill a block, one by one (bounds-checked).
fn tail_forces_energy(x: &[Vec3], f: &mut [Vec3], springs: &[Spring], k: &[f64]) -> f64 {
    let mut energy = 0.0;
    for (s, &kl) in springs.iter().zip(k) {
        let (fi, e) = tension(x, s, kl);
        f[s.i as usize] += fi;
        f[s.j as usize] -= fi;
        energy += 0.5 * kl * e * e;
    }
    energy
}

/// The block loop. Safety: every spring index is below `x.len()` and `f.len()`.
#[inline(always)]
unsafe fn forces_energy_blocks(x: &[Vec3], f: &mut [Vec3], springs: &[Spring], k: &[f64]) -> f64 {
    let mut energy = [0.0; LANES];
    for (sb, kb) in springs.chunks_exact(LANES).zip(k.chunks_exact(LANES)) {
        let (mut dx, mut dy, mut dz) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        for l in 0..LANES {
            let s = &sb[l];
            // SAFETY: indices below x.len() (function contract).
            let d = unsafe { *x.get_unchecked(s.i as usize) - *x.get_unchecked(s.j as usize) };
            (dx[l], dy[l], dz[l]) = (d.x, d.y, d.z);
        }
        let mut scale = [0.0; LANES];
        for l in 0..LANES {
            let (kl, rest) = (kb[l], sb[l].rest);
            let len = (dx[l] * dx[l] + dy[l] * dy[l] + dz[l] * dz[l]).sqrt();
            let e = len - rest;
            scale[l] = if len > 0.0 { -kl * e / len } else { 0.0 };
            energy[l] += 0.5 * kl * e * e;
        }
        for l in 0..LANES {
            let s = &sb[l];
            let fi = Vec3::new(dx[l] * scale[l], dy[l] * scale[l], dz[l] * scale[l]);
            // SAFETY: indices below f.len() (function contract).
            unsafe {
                *f.get_unchecked_mut(s.i as usize) += fi;
                *f.get_unchecked_mut(s.j as usize) -= fi;
            }
        }
    }
    let tail = springs.len() / LANES * LANES;
    let tail_energy = tail_forces_energy(x, f, &springs[tail..], &k[tail..]);
    (energy[0] + energy[1]) + (energy[2] + energy[3]) + tail_energy
}

impl Effect for Springs {
    fn name(&self) -> &'static str {
        self.name
    }

    fn declare(&self, p: &mut PatternBuilder) {
        for s in &self.springs {
            p.couple(s.i, s.j);
        }
    }

    fn position_only(&self) -> bool {
        true
    }

    fn add_forces(&self, st: &State, f: &mut [Vec3]) {
        // The fused pass: the energy costs a few multiplies next to the square root and division.
        self.add_forces_energy_part(st, f, 0, 1);
    }

    fn add_forces_energy(&self, st: &State, f: &mut [Vec3]) -> f64 {
        self.add_forces_energy_part(st, f, 0, 1)
    }

    fn add_forces_energy_part(&self, st: &State, f: &mut [Vec3], part: usize, parts: usize) -> f64 {
        let r = crate::par::part_range(self.springs.len(), part, parts);
        if let Some(at) = &self.knee {
            return self.knee_forces_energy(at, st.x, f, r);
        }
        forces_energy(
            st.x,
            f,
            &self.springs[r.clone()],
            &self.k[r],
            self.vertex_bound,
        )
    }

    fn add_jacobians(&self, st: &State, dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {
        let slots = self
            .slots
            .get(dfdx, self.springs.iter().map(|s| (s.i, s.j)));
        if self.knee.is_some() {
            // Tangent `dT/de` along the spring, `T / L` across it (clamped at zero).
            dfdx.add_pairs(&slots.1, |q| {
                let s = &self.springs[q];
                let d = st.x[s.i as usize] - st.x[s.j as usize];
                let len = d.length();
                let (t, kt) = self.law(q, len - s.rest);
                if len > 0.0 {
                    let n = d / len;
                    let nn = outer(n, n);
                    (nn * -kt) + (Mat3::IDENTITY - nn) * -(t / len).max(0.0)
                } else {
                    Mat3::IDENTITY * -kt
                }
            });
            return;
        }
        dfdx.add_pairs(&slots.1, |q| {
            let (s, k) = (&self.springs[q], self.k[q]);
            let d = st.x[s.i as usize] - st.x[s.j as usize];
            let len = d.length();
            if len > 0.0 {
                let n = d / len;
                let nn = outer(n, n);
                let transverse = (1.0 - s.rest / len).max(0.0);
                (nn + (Mat3::IDENTITY - nn) * transverse) * -k
            } else {
                // Degenerate spring: keep the matrix definite with an isotropic stiffness.
                Mat3::IDENTITY * -k
            }
        });
    }

    /// A spring under strain `e` has transverse stiffness `k e / (1 + e)` (the `1 - l/L` term
    /// at `L = (1 + e) l`); at rest length it has none, so a linearised step in which a link
    /// drags a vertex sideways leaves its neighbours behind and the edges between stretch. Where
    /// the drag's front is on its way (`front_strain`), the transverse term is raised to that of
    /// the front's tension, as if the spring were already at it. A spring with a knee takes the
    /// front's strain only up to its knee: past it the stiffened tension (up to `r` times the
    /// linear one) would tie the link's neighbours to the link so tightly that cloth cannot
    /// slide round a rod, and a sheet pinned behind one is pulled taut between pins and rod (a
    /// pinned sheet hit by 3 and 5 mm rods at 5-40 m/s, `tests/fast_links.rs`: edges to 1.22
    /// against up to 1.99 when linearised at the stiffened tension).
    fn add_front_stiffness(&self, st: &State, front_strain: &[f64], dfdx: &mut BlockCsr) {
        let front = |i: u32| front_strain.get(i as usize).copied().unwrap_or(0.0);
        let slots = self
            .slots
            .get(dfdx, self.springs.iter().map(|s| (s.i, s.j)));
        for (q, (s, sl)) in self.springs.iter().zip(&slots.1).enumerate() {
            let k = self.k[q];
            let e = front(s.i).max(front(s.j));
            if e <= 0.0 || !e.is_finite() {
                continue;
            }
            let d = st.x[s.i as usize] - st.x[s.j as usize];
            let len = d.length();
            if len <= 0.0 {
                continue;
            }
            let n = d / len;
            // `T / (k L)`: at the spring's length now and at the front's strain.
            let transverse = (self.law(q, len - s.rest).0 / (k * len)).max(0.0);
            // A stiffening spring is linearised at no more than its knee's strain (see above).
            let e = match &self.knee {
                Some(at) => e.min(at[q].extension / s.rest),
                None => e,
            };
            let at_front = self.law(q, e * s.rest).0 / (k * (1.0 + e) * s.rest);
            let extra = at_front - transverse;
            if extra <= 0.0 {
                continue;
            }
            let kii = (Mat3::IDENTITY - outer(n, n)) * (-k * extra);
            dfdx.add_at(sl[0], kii);
            dfdx.add_at(sl[1], kii);
            dfdx.add_at(sl[2], -kii);
            dfdx.add_at(sl[3], -kii);
        }
    }

    fn energy(&self, x: &[Vec3]) -> f64 {
        if let Some(at) = &self.knee {
            return (self.springs.iter().zip(&self.k).zip(at))
                .map(|((s, &k), a)| {
                    a.energy(k, (x[s.i as usize] - x[s.j as usize]).length() - s.rest)
                })
                .sum();
        }
        self.springs
            .iter()
            .zip(&self.k)
            .map(|(s, k)| {
                let e = (x[s.i as usize] - x[s.j as usize]).length() - s.rest;
                0.5 * k * e * e
            })
            .sum()
    }

    /// With knees, also the stiffening a linearisation below the knee did not see: a spring
    /// that ends `o` past its knee from a start below it carries `(r - 1) k o` more tension
    /// than the linearisation's, as much as `(r - 1) o` of stretch would at its stiffness below
    /// the knee.
    fn unseen_stretch(&self, x0: &[Vec3], x1: &[Vec3]) -> f64 {
        let dir = |x: &[Vec3], s: &Spring| x[s.i as usize] - x[s.j as usize];
        let turning = self.turning_unseen(x0, x1);
        let Some(at) = &self.knee else {
            return turning;
        };
        (self.springs.iter().zip(&self.k).zip(at))
            .filter(|((s, _), a)| s.rest > 0.0 && a.extra > 0.0)
            .map(|((s, &k), a)| {
                // What the tangent at `x0` left out of the tension at `x1` where the spring
                // stretched further into its knee (the ramp is convex: the miss is never
                // negative), as the strain of the linear spring that would pull as hard.
                let e0 = dir(x0, s).length() - s.rest;
                let e1 = dir(x1, s).length() - s.rest;
                if e1 <= e0 {
                    return 0.0;
                }
                let miss = a.over(e1) - a.over(e0) - a.slope(e0) * (e1 - e0);
                a.extra / k * miss.max(0.0) / s.rest
            })
            .fold(turning, f64::max)
    }

    fn stiffness(&self, mass: &[f64]) -> Option<StiffnessBound> {
        // Gershgorin: lambda_max(M^-1 K) <= max_i sum_{springs at i} 2 k / m_i, with `k` the
        // stiffness past the knee where there is one.
        let mut row = vec![0.0; mass.len()];
        for (q, s) in self.springs.iter().enumerate() {
            let k = self.k[q] + self.knee.as_ref().map_or(0.0, |at| at[q].extra);
            row[s.i as usize] += 2.0 * k;
            row[s.j as usize] += 2.0 * k;
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

impl Springs {
    /// The stretch the springs' turning hides from a linearisation at `x0` (see
    /// [`Effect::unseen_stretch`]).
    fn turning_unseen(&self, x0: &[Vec3], x1: &[Vec3]) -> f64 {
        let dir = |x: &[Vec3], s: &Spring| x[s.i as usize] - x[s.j as usize];
        self.springs
            .iter()
            .filter(|s| s.rest > 0.0)
            .map(|s| {
                let (d0, d1) = (dir(x0, s), dir(x1, s));
                // Coincident ends at `x0`: linearised isotropically, nothing turns unseen.
                let n0 = d0.normalize_or_zero();
                if n0 == Vec3::ZERO {
                    return 0.0;
                }
                (d1.length() - n0.dot(d1)) / s.rest
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Springs of a 7x5 lattice (rows, columns, diagonals, skip-one) and a few irregular ones, at
    /// a deformed state with one pair of coincident endpoints: the block pass gives bitwise the
    /// forces of a plain loop and its energy to rounding, whole and in two parts.
    #[test]
    fn block_pass_matches_a_plain_loop() {
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
            i: 30,
            j: 3,
            rest: 0.4,
        });
        let k: Vec<f64> = (0..springs.len()).map(|s| 100.0 + s as f64).collect();
        let mut x: Vec<Vec3> = (0..nu * nv)
            .map(|v| {
                let (i, j) = ((v % nu) as f64, (v / nu) as f64);
                Vec3::new(0.1 * i + 0.01 * j.sin(), 0.1 * j, 0.02 * (i * j).cos())
            })
            .collect();
        x[9] = x[8];
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
        assert!(reference[8].is_finite() && reference[9].is_finite());
        let effect = Springs::new("stretch", springs, k, "k".into());
        let st = State {
            t: 0.0,
            x: &x,
            v: &[],
        };
        let mut f = vec![Vec3::ZERO; x.len()];
        let energy = effect.add_forces_energy(&st, &mut f);
        assert_eq!(f, reference);
        // Four interleaved partial sums instead of one: a few ulps.
        assert!(
            (energy - e_ref).abs() <= 1e-14 * e_ref,
            "{energy} vs {e_ref}"
        );
        // Two parts into separate buffers sum to the whole (to rounding).
        let (mut a, mut b) = (vec![Vec3::ZERO; x.len()], vec![Vec3::ZERO; x.len()]);
        let e2 = effect.add_forces_energy_part(&st, &mut a, 0, 2)
            + effect.add_forces_energy_part(&st, &mut b, 1, 2);
        for ((p, q), r) in a.iter().zip(&b).zip(&reference) {
            assert!((*p + *q - *r).length() <= 1e-13 * (1.0 + r.length()), "{r}");
        }
        assert!((e2 - e_ref).abs() <= 1e-14 * e_ref);
    }
    /// A spring turned by `a` at its length gains `1 - cos a` of it unseen by a linearisation
    /// at the start; stretched along itself, nothing.
    #[test]
    fn unseen_stretch_is_the_turning_not_the_stretch() {
        let springs = Springs::new(
            "stretch",
            vec![Spring {
                i: 0,
                j: 1,
                rest: 0.5,
            }],
            vec![1.0],
            "k".into(),
        );
        let x0 = [Vec3::ZERO, Vec3::X];
        let a = 0.5f64;
        let turned = [Vec3::ZERO, Vec3::new(a.cos(), a.sin(), 0.0)];
        let seen = springs.unseen_stretch(&x0, &turned);
        assert!((seen - 2.0 * (1.0 - a.cos())).abs() < 1e-12, "{seen}");
        assert_eq!(
            springs.unseen_stretch(&x0, &[Vec3::ZERO, Vec3::X * 3.0]),
            0.0
        );
        assert_eq!(springs.unseen_stretch(&[Vec3::ZERO; 2], &turned), 0.0);
    }

    /// A spring with a knee: force continuous at the knee, the force minus the energy's
    /// gradient and the Jacobian against finite differences of the force, below and past it.
    #[test]
    fn a_knee_is_continuous_and_its_jacobian_is_the_forces_derivative() {
        let knee = Knee {
            strain: 0.03,
            ratio: 100.0,
        };
        let spring = Spring {
            i: 0,
            j: 1,
            rest: 0.5,
        };
        let s = Springs::new("stretch", vec![spring], vec![1000.0], "k".into())
            .with_knee(&[Some(knee)]);
        let force = |x: &[Vec3]| {
            let mut f = vec![Vec3::ZERO; 2];
            let e = s.add_forces_energy(&State { t: 0.0, x, v: &[] }, &mut f);
            (f, e)
        };
        let at = |len: f64| [Vec3::ZERO, Vec3::new(len * 0.6, len * 0.8, 0.0)];
        // Continuity: just below and just past the knee extension, the same tension.
        let (below, _) = force(&at(0.5 * 1.03 - 1e-12));
        let (past, _) = force(&at(0.5 * 1.03 + 1e-12));
        assert!((below[1] - past[1]).length() < 1e-6, "{below:?} {past:?}");
        // Past the rise (3 % to 4.5 %) the tension is k e + (r - 1) k (e - s l - rise / 2);
        // half-way up it, (r - 1) k u^2 / (2 rise) on top of k e.
        let rise = KNEE_RISE * 0.03 * 0.5;
        let (f, _) = force(&at(0.5 * 1.05));
        let t = 1000.0 * 0.025 + 99.0 * 1000.0 * (0.01 - 0.5 * rise);
        assert!((f[1].length() - t).abs() < 1e-9 * t, "{}", f[1].length());
        let u = 0.5 * rise;
        let (f, _) = force(&at(0.5 * 1.03 + u));
        let t = 1000.0 * (0.015 + u) + 99.0 * 1000.0 * u * u / (2.0 * rise);
        assert!((f[1].length() - t).abs() < 1e-9 * t, "{}", f[1].length());

        // Below the knee, on the rise and past it.
        for len in [0.5 * 1.01, 0.5 * 1.035, 0.5 * 1.06] {
            let x = at(len);
            let x = [x[0], x[1] + Vec3::new(0.0, 0.0, 0.01)];
            let h = 1e-7;
            // Energy: -dE/dx of vertex 1 along z is the force's z.
            let (f0, _) = force(&x);
            let mut xp = x;
            xp[1].z += h;
            let mut xm = x;
            xm[1].z -= h;
            let (fp, ep) = force(&xp);
            let (fm, em) = force(&xm);
            assert!(((ep - em) / (2.0 * h) + f0[1].z).abs() < 1e-5 * (1.0 + f0[1].length()));
            // Jacobian column of vertex 1's z against the force's difference.
            let pattern = || {
                let mut p = PatternBuilder::new();
                s.declare(&mut p);
                p.build(2)
            };
            let (mut dfdx, mut dfdv) = (pattern(), pattern());
            s.add_jacobians(
                &State {
                    t: 0.0,
                    x: &x,
                    v: &[],
                },
                &mut dfdx,
                &mut dfdv,
            );
            let column = (fp[1] - fm[1]) / (2.0 * h);
            let analytic = dfdx.diagonal(1) * Vec3::Z;
            assert!(
                (analytic - column).length() < 1e-4 * (1.0 + column.length()),
                "at {len}: {analytic} vs {column}"
            );
        }
    }
}
