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
