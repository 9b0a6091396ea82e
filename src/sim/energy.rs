//! The energies of a cloth state the guard and the metrics use: kinetic energy of the free
//! vertices, elastic and gravitational potential.

use crate::cloth::Cloth;
use crate::effects::EffectSet;

/// Energies of a state: kinetic (free vertices), elastic and gravitational potential.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Energies {
    pub kinetic: f64,
    pub elastic: f64,
    pub gravity: f64,
}

impl Energies {
    /// The energies of the cloth's current state (and the position-only forces there, cached by
    /// the effects for the next substep).
    pub fn of(cloth: &Cloth, effects: &EffectSet) -> Energies {
        let (elastic, gravity) = effects.energy_split(&cloth.x);
        Energies {
            kinetic: kinetic_energy(cloth),
            elastic,
            gravity,
        }
    }

    /// Kinetic plus every potential.
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravity
    }

    /// Kinetic plus elastic: the total without the gravity potential, so never negative.
    pub fn dynamic(&self) -> f64 {
        self.kinetic + self.elastic
    }
}

/// `sum m |v|^2 / 2` over the free vertices (kinematic ones move with their frames).
pub(super) fn kinetic_energy(c: &Cloth) -> f64 {
    let mut ke: f64 =
        c.v.iter()
            .zip(&c.mass)
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum();
    for (i, _) in &c.kinematic {
        ke -= 0.5 * c.mass[*i as usize] * c.v[*i as usize].length_squared();
    }
    ke
}
