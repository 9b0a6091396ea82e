//! The guard's pass over a substep's result: finiteness, the fastest speed, kinetic energy and
//! the speed sum of the gravity error bound, branch-free in interleaved lanes (AVX2 where the
//! CPU has it, bitwise equal to the scalar lanes).

use crate::Vec3;

/// What the guard needs from one pass over the vertices of a substep's result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct VertexScan {
    /// False when some position or velocity may be non-finite (the caller then finds the first
    /// bad vertex with an exact scan; a false alarm on sums that overflow is harmless).
    pub finite: bool,
    /// Largest squared speed.
    pub speed2: f64,
    /// `sum m |v|^2 / 2` over all vertices.
    pub kinetic: f64,
    /// `sum m max(|v|, |v0|)`, the speed sum of the gravity error bound.
    pub mass_speed: f64,
    /// `sum m`.
    pub mass: f64,
}

impl VertexScan {
    /// The scan of two vertex ranges together (in a fixed order: results depend on the split
    /// only, not on thread timing).
    pub fn merge(&self, b: &VertexScan) -> VertexScan {
        VertexScan {
            finite: self.finite && b.finite,
            speed2: self.speed2.max(b.speed2),
            kinetic: self.kinetic + b.kinetic,
            mass_speed: self.mass_speed + b.mass_speed,
            mass: self.mass + b.mass,
        }
    }
}

/// Lanes of the vertex scan: independent accumulators the compiler keeps in SIMD registers.
const LANES: usize = 4;

/// One branch-free pass over positions `x`, velocities `v`, start velocities `v0` and masses
/// (equal lengths). Sums run in [`LANES`] interleaved accumulators, so they differ from a
/// sequential sum at rounding level only.
pub(crate) fn scan_vertices(x: &[Vec3], v: &[Vec3], v0: &[Vec3], mass: &[f64]) -> VertexScan {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { scan_vertices_avx2(x, v, v0, mass) };
    }
    scan_vertices_lanes(x, v, v0, mass)
}

/// [`scan_vertices_lanes`] with the lane arithmetic in AVX registers: each lane does the same
/// operations in the same order (no fused multiply-adds), so the results are bitwise equal.
///
/// Safety: AVX2 is available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn scan_vertices_avx2(x: &[Vec3], v: &[Vec3], v0: &[Vec3], mass: &[f64]) -> VertexScan {
    use std::arch::x86_64::*;
    let n = x.len().min(v.len()).min(v0.len()).min(mass.len());
    let (x, v, v0, mass) = (&x[..n], &v[..n], &v0[..n], &mass[..n]);
    let blocks = n / LANES * LANES;
    let (zero, half) = (_mm256_setzero_pd(), _mm256_set1_pd(0.5));
    let (mut finite, mut speed2, mut kinetic, mut mass_speed, mut total) =
        (zero, zero, zero, zero, zero);
    for b in (0..blocks).step_by(LANES) {
        // Component arrays of the block's positions, velocities and start velocities.
        let mut c = [[0.0; LANES]; 9];
        for l in 0..LANES {
            let (p, w, w0) = (x[b + l], v[b + l], v0[b + l]);
            for (k, value) in [p.x, p.y, p.z, w.x, w.y, w.z, w0.x, w0.y, w0.z]
                .into_iter()
                .enumerate()
            {
                c[k][l] = value;
            }
        }
        // SAFETY: unaligned loads of local 4-element arrays and of `mass[b..b + 4]` (in bounds).
        unsafe {
            let ld = |k: usize| _mm256_loadu_pd(c[k].as_ptr());
            let m = _mm256_loadu_pd(mass.as_ptr().add(b));
            let (px, py, pz, wx, wy, wz) = (ld(0), ld(1), ld(2), ld(3), ld(4), ld(5));
            let d = |a: __m256d| _mm256_mul_pd(a, zero);
            let nan_test = _mm256_add_pd(
                _mm256_add_pd(
                    _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(d(px), d(py)), d(pz)), d(wx)),
                    d(wy),
                ),
                d(wz),
            );
            finite = _mm256_add_pd(finite, nan_test);
            let sq = |a: __m256d, b: __m256d, c: __m256d| {
                _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(a, a), _mm256_mul_pd(b, b)),
                    _mm256_mul_pd(c, c),
                )
            };
            let v2 = sq(wx, wy, wz);
            let v02 = sq(ld(6), ld(7), ld(8));
            speed2 = _mm256_max_pd(speed2, v2);
            kinetic = _mm256_add_pd(kinetic, _mm256_mul_pd(_mm256_mul_pd(half, m), v2));
            let fastest = _mm256_sqrt_pd(_mm256_max_pd(v2, v02));
            mass_speed = _mm256_add_pd(mass_speed, _mm256_mul_pd(m, fastest));
            total = _mm256_add_pd(total, m);
        }
    }
    let lanes = |a: __m256d| {
        let mut out = [0.0; LANES];
        // SAFETY: store to a local 4-element array.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), a) };
        out
    };
    let mut acc = Accumulators {
        finite: lanes(finite),
        speed2: lanes(speed2),
        kinetic: lanes(kinetic),
        mass_speed: lanes(mass_speed),
        total: lanes(total),
    };
    for i in blocks..n {
        acc.add(i - blocks, x[i], v[i], v0[i], mass[i]);
    }
    acc.finish()
}

/// Per-lane sums of the vertex scan.
#[derive(Default)]
struct Accumulators {
    finite: [f64; LANES],
    speed2: [f64; LANES],
    kinetic: [f64; LANES],
    mass_speed: [f64; LANES],
    total: [f64; LANES],
}

impl Accumulators {
    /// Adds one vertex to lane `l`.
    #[inline(always)]
    fn add(&mut self, l: usize, p: Vec3, w: Vec3, w0: Vec3, m: f64) {
        // Zero for finite components, NaN as soon as one is infinite or NaN.
        self.finite[l] +=
            (p.x * 0.0) + (p.y * 0.0) + (p.z * 0.0) + (w.x * 0.0) + (w.y * 0.0) + (w.z * 0.0);
        let v2 = w.length_squared();
        self.speed2[l] = self.speed2[l].max(v2);
        self.kinetic[l] += 0.5 * m * v2;
        self.mass_speed[l] += m * v2.max(w0.length_squared()).sqrt();
        self.total[l] += m;
    }

    fn finish(&self) -> VertexScan {
        let sum = |a: [f64; LANES]| (a[0] + a[1]) + (a[2] + a[3]);
        VertexScan {
            finite: sum(self.finite) == 0.0,
            speed2: self.speed2.iter().fold(0.0, |a, &b| a.max(b)),
            kinetic: sum(self.kinetic),
            mass_speed: sum(self.mass_speed),
            mass: sum(self.total),
        }
    }
}

fn scan_vertices_lanes(x: &[Vec3], v: &[Vec3], v0: &[Vec3], mass: &[f64]) -> VertexScan {
    let n = x.len().min(v.len()).min(v0.len()).min(mass.len());
    let mut acc = Accumulators::default();
    for i in 0..n {
        acc.add(i % LANES, x[i], v[i], v0[i], mass[i]);
    }
    acc.finish()
}
