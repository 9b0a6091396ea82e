//! In-solve Coulomb friction of the held vertices, one per surface a vertex is held against,
//! with each surface's velocity as its reference; its limit lags a substep: `mu N` of the last
//! solve's normal impulse on the vertex against that surface.

use super::Coupling;
use crate::collide::HeldNormals;
use crate::integrate::Friction;
use crate::Vec3;

impl Coupling {
    /// In-solve friction of vertex `i` held against `normals` (force `f` on it), one per surface:
    /// each surface rubs with its own velocity (a cloth wedged between a moving hand and a
    /// static torso is dragged by one and held by the other; one drag towards their mean
    /// velocity with both limits summed would drag it at half the hand's speed with twice the
    /// grip). The Coulomb limit is the last substep's `mu N` for that surface when the solve
    /// held the vertex against it, else `mu` times the force pressing it into it now.
    pub(super) fn held_friction(
        &self,
        i: usize,
        normals: &HeldNormals,
        mu: f64,
        f: Vec3,
        out: &mut Vec<Friction>,
    ) {
        let lagged = self.friction_limit.get(i).copied().unwrap_or_default();
        for (n, surface) in normals.normals().iter().zip(normals.surfaces()) {
            let limit = match lagged.iter().find(|l| l.1 > 0.0 && l.0.dot(*n) > 0.9) {
                Some(l) => l.1,
                None => mu * (-f.dot(*n)).max(0.0),
            };
            if limit > 0.0 {
                out.push(Friction {
                    vertex: i as u32,
                    limit,
                    reference: *surface,
                    normal: None,
                    patch: None,
                });
            }
        }
    }
}

/// In-solve friction's Coulomb limits of a vertex of mass `m` for the next substep, into its
/// `slots`: per surface of `normals`, `mu N` of the normal impulse per unit mass `split` the
/// solve of substep `h` gave it against that surface (zero when it pulled). Slots past the
/// surfaces are left as they are.
pub(super) fn next_limits(
    slots: &mut [(Vec3, f64); 3],
    normals: &HeldNormals,
    split: [f64; 3],
    mu: f64,
    m: f64,
    h: f64,
) {
    for (slot, (normal, l)) in slots.iter_mut().zip(normals.normals().iter().zip(split)) {
        *slot = (*normal, mu * l.max(0.0) * m / h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn next_limits_are_mu_times_each_surfaces_pressing_force() {
        let normals = HeldNormals::from_contacts([(Vec3::Z, Vec3::ZERO), (Vec3::X, Vec3::ZERO)]);
        let mut slots = [(Vec3::ZERO, 0.0); 3];
        // 0.02 m/s per unit mass into the table, a pull off the wall.
        next_limits(&mut slots, &normals, [0.02, -0.01, 0.0], 0.5, 0.1, 0.01);
        assert_eq!(slots[0], (Vec3::Z, 0.5 * 0.02 * 0.1 / 0.01));
        assert_eq!(slots[1], (Vec3::X, 0.0));
        assert_eq!(slots[2], (Vec3::ZERO, 0.0));
    }

    #[test]
    fn held_friction_takes_the_lagged_limit_of_the_same_surface_else_the_pressing_force() {
        let coupling = Coupling {
            friction_limit: vec![[(Vec3::Z, 0.7), (Vec3::ZERO, 0.0), (Vec3::ZERO, 0.0)]],
            ..Coupling::default()
        };
        let wall = Vec3::new(0.0, 1.0, 0.0);
        let normals = HeldNormals::from_contacts([(Vec3::Z, Vec3::X), (wall, Vec3::ZERO)]);
        let mut out = Vec::new();
        let f = Vec3::new(0.0, -2.0, -1.0);
        coupling.held_friction(0, &normals, 0.5, f, &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!(
            (out[0].vertex, out[0].limit, out[0].reference),
            (0, 0.7, Vec3::X)
        );
        assert_eq!((out[1].limit, out[1].reference), (0.5 * 2.0, Vec3::ZERO));
    }
}
