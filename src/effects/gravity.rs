//! Uniform gravity.

use super::effect::{Effect, State};
use crate::Vec3;

pub struct Gravity {
    pub g: Vec3,
    mass: Vec<f64>,
}

impl Gravity {
    pub fn new(g: Vec3, mass: &[f64]) -> Self {
        Self {
            g,
            mass: mass.to_vec(),
        }
    }
}

impl Effect for Gravity {
    fn name(&self) -> &'static str {
        "gravity"
    }

    fn add_forces(&self, _s: &State, f: &mut [Vec3]) {
        for (fi, m) in f.iter_mut().zip(&self.mass) {
            *fi += self.g * *m;
        }
    }

    fn position_only(&self) -> bool {
        true
    }

    fn add_forces_energy(&self, s: &State, f: &mut [Vec3]) -> f64 {
        self.add_forces_energy_part(s, f, 0, 1)
    }

    /// The vertices of the `part`-th slice, so that both threads of a split pass share the work.
    fn add_forces_energy_part(&self, s: &State, f: &mut [Vec3], part: usize, parts: usize) -> f64 {
        let r = crate::par::part_range(self.mass.len(), part, parts);
        let mut energy = 0.0;
        for ((fi, m), xi) in f[r.clone()]
            .iter_mut()
            .zip(&self.mass[r.clone()])
            .zip(&s.x[r])
        {
            *fi += self.g * *m;
            energy -= m * self.g.dot(*xi);
        }
        energy
    }

    fn energy(&self, x: &[Vec3]) -> f64 {
        -x.iter()
            .zip(&self.mass)
            .map(|(xi, m)| m * self.g.dot(*xi))
            .sum::<f64>()
    }
}
