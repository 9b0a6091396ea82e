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
}

/// Second derivative along warp and/or weft.
pub type Bending = StencilSet<3>;
/// The mixed second derivative `d2r/du dv`.
pub type Twist = StencilSet<4>;

impl Bending {
    pub fn new(stencils: Vec<Stencil<3>>, rigidity: Vec<f64>, parameter: String) -> Self {
        StencilSet {
            name: "bending",
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
        let mut energy = 0.0;
        for (s, &c) in self.stencils[r.clone()].iter().zip(&self.c[r]) {
            let mut d = Vec3::ZERO;
            for k in 0..N {
                d += x[s.idx[k] as usize] * s.w[k];
            }
            for k in 0..N {
                f[s.idx[k] as usize] -= d * (c * s.w[k]);
            }
            energy += 0.5 * c * d.length_squared();
        }
        energy
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
