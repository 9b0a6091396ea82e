//! Springs between vertex pairs: stretch (warp/weft edges), shear (diagonals) and skip-one.
//!
//! Energy `k/2 (L - l)^2` with `L = |xi - xj|`. The Jacobian is the usual
//! `-k [n n^T + (1 - l/L)(I - n n^T)]`, with the transverse term clamped at zero under compression
//! (Choi and Ko): keeping it would make the system matrix indefinite and break conjugate gradients.

use super::spring_runs::SpringLayout;
use super::{outer, Effect, State, StiffnessBound};
use crate::cloth::topology::Spring;
use crate::integrate::{BlockCsr, PatternBuilder};
use crate::{Mat3, Vec3};

pub struct Springs {
    name: &'static str,
    springs: Vec<Spring>,
    k: Vec<f64>,
    /// The same springs regrouped for the force pass.
    layout: SpringLayout,
    /// Scene parameter per spring group, for diagnostics.
    parameter: String,
}

impl Springs {
    /// `name` is the effect's scene name (`stretch`, `shear`, `skip_one`); `k` is per spring.
    pub fn new(name: &'static str, springs: Vec<Spring>, k: Vec<f64>, parameter: String) -> Self {
        debug_assert_eq!(springs.len(), k.len());
        let layout = SpringLayout::new(&springs, &k);
        Self {
            name,
            springs,
            k,
            layout,
            parameter,
        }
    }

    pub fn len(&self) -> usize {
        self.springs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.springs.is_empty()
    }
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
        self.layout.forces_energy(st.x, f, 0, 1);
    }

    fn add_forces_energy(&self, st: &State, f: &mut [Vec3]) -> f64 {
        self.add_forces_energy_part(st, f, 0, 1)
    }

    fn add_forces_energy_part(&self, st: &State, f: &mut [Vec3], part: usize, parts: usize) -> f64 {
        self.layout.forces_energy(st.x, f, part, parts)
    }

    fn add_jacobians(&self, st: &State, dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {
        for (s, &k) in self.springs.iter().zip(&self.k) {
            let d = st.x[s.i as usize] - st.x[s.j as usize];
            let len = d.length();
            let kii = if len > 0.0 {
                let n = d / len;
                let nn = outer(n, n);
                let transverse = (1.0 - s.rest / len).max(0.0);
                (nn + (Mat3::IDENTITY - nn) * transverse) * -k
            } else {
                // Degenerate spring: keep the matrix definite with an isotropic stiffness.
                Mat3::IDENTITY * -k
            };
            dfdx.add(s.i, s.i, kii);
            dfdx.add(s.j, s.j, kii);
            dfdx.add(s.i, s.j, -kii);
            dfdx.add(s.j, s.i, -kii);
        }
    }

    fn energy(&self, x: &[Vec3]) -> f64 {
        self.springs
            .iter()
            .zip(&self.k)
            .map(|(s, k)| {
                let e = (x[s.i as usize] - x[s.j as usize]).length() - s.rest;
                0.5 * k * e * e
            })
            .sum()
    }

    fn stiffness(&self, mass: &[f64]) -> Option<StiffnessBound> {
        // Gershgorin: lambda_max(M^-1 K) <= max_i sum_{springs at i} 2 k / m_i.
        let mut row = vec![0.0; mass.len()];
        for (s, &k) in self.springs.iter().zip(&self.k) {
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
