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

/// A set of stencils of one size with one rigidity per stencil.
struct StencilSet<const N: usize> {
    stencils: Vec<Stencil<N>>,
    c: Vec<f64>,
    parameter: String,
}

impl<const N: usize> StencilSet<N> {
    fn declare(&self, p: &mut PatternBuilder) {
        for s in &self.stencils {
            p.couple_all(&s.idx);
        }
    }

    fn add_forces(&self, x: &[Vec3], f: &mut [Vec3]) {
        for (s, &c) in self.stencils.iter().zip(&self.c) {
            let mut d = Vec3::ZERO;
            for k in 0..N {
                d += x[s.idx[k] as usize] * s.w[k];
            }
            for k in 0..N {
                f[s.idx[k] as usize] -= d * (c * s.w[k]);
            }
        }
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

/// Bending along one material direction (warp or weft stencils, or both in one set).
pub struct Bending(StencilSet<3>);

impl Bending {
    pub fn new(stencils: Vec<Stencil<3>>, rigidity: Vec<f64>, parameter: String) -> Self {
        Self(StencilSet {
            stencils,
            c: rigidity,
            parameter,
        })
    }
}

impl Effect for Bending {
    fn name(&self) -> &'static str {
        "bending"
    }
    fn declare(&self, p: &mut PatternBuilder) {
        self.0.declare(p)
    }
    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        self.0.add_forces(s.x, f)
    }
    fn add_jacobians(&self, _s: &State, dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {
        self.0.add_jacobians(dfdx)
    }
    fn energy(&self, x: &[Vec3]) -> f64 {
        self.0.energy(x)
    }
    fn stiffness(&self, mass: &[f64]) -> Option<StiffnessBound> {
        self.0.stiffness(mass)
    }
}

/// Twist: the mixed second derivative `d2r/du dv`.
pub struct Twist(StencilSet<4>);

impl Twist {
    pub fn new(stencils: Vec<Stencil<4>>, rigidity: Vec<f64>, parameter: String) -> Self {
        Self(StencilSet {
            stencils,
            c: rigidity,
            parameter,
        })
    }
}

impl Effect for Twist {
    fn name(&self) -> &'static str {
        "twist"
    }
    fn declare(&self, p: &mut PatternBuilder) {
        self.0.declare(p)
    }
    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        self.0.add_forces(s.x, f)
    }
    fn add_jacobians(&self, _s: &State, dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {
        self.0.add_jacobians(dfdx)
    }
    fn energy(&self, x: &[Vec3]) -> f64 {
        self.0.energy(x)
    }
    fn stiffness(&self, mass: &[f64]) -> Option<StiffnessBound> {
        self.0.stiffness(mass)
    }
}
