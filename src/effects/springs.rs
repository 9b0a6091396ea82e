//! Springs between vertex pairs: stretch (warp/weft edges), shear (diagonals) and skip-one.
//!
//! Energy `k/2 (L - l)^2` with `L = |xi - xj|`. The Jacobian is the usual
//! `-k [n n^T + (1 - l/L)(I - n n^T)]`, with the transverse term clamped at zero under compression
//! (Choi and Ko): keeping it would make the system matrix indefinite and break conjugate gradients.

use super::{outer, Effect, State, StiffnessBound};
use crate::cloth::topology::Spring;
use crate::integrate::{BlockCsr, PairSlots, PatternBuilder};
use crate::{Mat3, Vec3};

pub struct Springs {
    name: &'static str,
    springs: Vec<Spring>,
    k: Vec<f64>,
    /// Scene parameter per spring group, for diagnostics.
    parameter: String,
    /// Jacobian block slots of every spring (no search per step).
    slots: PairSlots,
}

impl Springs {
    /// `name` is the effect's scene name (`stretch`, `shear`, `skip_one`); `k` is per spring.
    pub fn new(name: &'static str, springs: Vec<Spring>, k: Vec<f64>, parameter: String) -> Self {
        debug_assert_eq!(springs.len(), k.len());
        Self {
            name,
            springs,
            k,
            parameter,
            slots: PairSlots::default(),
        }
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
        for (s, &k) in self.springs.iter().zip(&self.k) {
            let (fi, _) = tension(st.x, s, k);
            f[s.i as usize] += fi;
            f[s.j as usize] -= fi;
        }
    }

    fn add_forces_energy(&self, st: &State, f: &mut [Vec3]) -> f64 {
        self.add_forces_energy_part(st, f, 0, 1)
    }

    fn add_forces_energy_part(&self, st: &State, f: &mut [Vec3], part: usize, parts: usize) -> f64 {
        let r = super::part_range(self.springs.len(), part, parts);
        let mut energy = 0.0;
        for (s, &k) in self.springs[r.clone()].iter().zip(&self.k[r]) {
            let (fi, e) = tension(st.x, s, k);
            f[s.i as usize] += fi;
            f[s.j as usize] -= fi;
            energy += 0.5 * k * e * e;
        }
        energy
    }

    fn add_jacobians(&self, st: &State, dfdx: &mut BlockCsr, _dfdv: &mut BlockCsr) {
        let slots = self
            .slots
            .get(dfdx, self.springs.iter().map(|s| (s.i, s.j)));
        for ((s, &k), sl) in self.springs.iter().zip(&self.k).zip(&slots.1) {
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
            dfdx.add_at(sl[0], kii);
            dfdx.add_at(sl[1], kii);
            dfdx.add_at(sl[2], -kii);
            dfdx.add_at(sl[3], -kii);
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
