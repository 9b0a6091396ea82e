//! Bending (second derivative along warp or weft) and twist (mixed derivative) as quadratic
//! energies of linear finite-difference stencils: `E = c/2 |sum_k w_k x_k|^2`.
//!
//! Being quadratic, their forces are linear in positions and their Jacobians are constant
//! (`-c w_a w_b I`), which the implicit solver handles exactly. Separate warp and weft rigidities
//! give anisotropic cloth, as in the survey's figure of four materials.

use super::{Effect, State, StiffnessBound};
use crate::cloth::topology::Stencil;
use crate::integrate::{BlockCsr, PatternBuilder};
use crate::{Mat3, Vec3};

/// A set of stencils of one size with one rigidity per stencil: bending (`N = 3`) or twist (`N = 4`).
pub struct StencilSet<const N: usize> {
    name: &'static str,
    stencils: Vec<Stencil<N>>,
    c: Vec<f64>,
    parameter: String,
    /// One past the largest vertex index, checked once per force pass against the slices so that
    /// the pass indexes without per-stencil bounds checks.
    vertex_bound: usize,
}

/// One past the largest vertex index of `stencils`.
fn vertex_bound<const N: usize>(stencils: &[Stencil<N>]) -> usize {
    stencils
        .iter()
        .flat_map(|s| s.idx)
        .map(|i| i as usize + 1)
        .max()
        .unwrap_or(0)
}

/// Second derivative along warp and/or weft.
pub type Bending = StencilSet<3>;
/// The mixed second derivative `d2r/du dv`.
pub type Twist = StencilSet<4>;

impl Bending {
    pub fn new(stencils: Vec<Stencil<3>>, rigidity: Vec<f64>, parameter: String) -> Self {
        StencilSet {
            name: "bending",
            vertex_bound: vertex_bound(&stencils),
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
            vertex_bound: vertex_bound(&stencils),
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

    /// Adds the forces `-c w_k d` and returns the energy `sum c/2 |d|^2`, `d = sum_k w_k x_k`.
    fn add_forces(&self, x: &[Vec3], f: &mut [Vec3], part: usize, parts: usize) -> f64 {
        let r = super::part_range(self.stencils.len(), part, parts);
        let (stencils, c) = (&self.stencils[r.clone()], &self.c[r]);
        assert!(
            x.len() >= self.vertex_bound && f.len() >= self.vertex_bound,
            "{} stencils reach vertex {} but the state has {} positions and {} forces",
            self.name,
            self.vertex_bound.saturating_sub(1),
            x.len(),
            f.len()
        );
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above); indices were checked above.
            return unsafe { forces_energy_avx2(x, f, stencils, c) };
        }
        // SAFETY: every index is below `vertex_bound`, checked above against both slices.
        unsafe { forces_energy(x, f, stencils, c) }
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

/// [`forces_energy`] compiled for AVX2. Rust never fuses a multiply and an add on its own, so the
/// results are bitwise those of the baseline code.
///
/// Safety: AVX2 is available, and the contract of [`forces_energy`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn forces_energy_avx2<const N: usize>(
    x: &[Vec3],
    f: &mut [Vec3],
    stencils: &[Stencil<N>],
    c: &[f64],
) -> f64 {
    // SAFETY: forwarded from the caller.
    unsafe { forces_energy(x, f, stencils, c) }
}

/// The stencil loop. Safety: every stencil index is below `x.len()` and `f.len()`.
#[inline(always)]
unsafe fn forces_energy<const N: usize>(
    x: &[Vec3],
    f: &mut [Vec3],
    stencils: &[Stencil<N>],
    c: &[f64],
) -> f64 {
    // Two accumulators (even and odd stencils) shorten the dependency chain of the sum.
    let mut energy = [0.0; 2];
    for (k, (s, &c)) in stencils.iter().zip(c).enumerate() {
        let mut d = Vec3::ZERO;
        for k in 0..N {
            // SAFETY: indices below x.len() (function contract).
            d += unsafe { *x.get_unchecked(s.idx[k] as usize) } * s.w[k];
        }
        for k in 0..N {
            // SAFETY: indices below f.len() (function contract).
            unsafe { *f.get_unchecked_mut(s.idx[k] as usize) -= d * (c * s.w[k]) };
        }
        energy[k & 1] += 0.5 * c * d.length_squared();
    }
    energy[0] + energy[1]
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
