//! Work done on the cloth from outside it over a substep, which the energy check allows: wind,
//! driven vertices, and moving obstacles acting through the solve.

use crate::cloth::Cloth;
use crate::effects::{EffectSet, State};
use crate::integrate::{Constraints, StepReport};
use crate::linalg::Filter;
use crate::Vec3;

/// Forces on the cloth from outside it over one substep, per vertex, whose work along the
/// substep's displacement the energy check allows; empty when there are none (then the check
/// allows no outside work and costs no pass over them).
#[derive(Debug, Default)]
pub(in crate::sim) struct OutsideForces {
    forces: Vec<Vec3>,
    any: bool,
}

impl OutsideForces {
    /// The forces, when there are any.
    pub fn forces(&self) -> Option<&[Vec3]> {
        self.any.then_some(self.forces.as_slice())
    }

    /// The forces to add to, for `n` vertices (zeroed when there were none yet).
    fn add(&mut self, n: usize) -> &mut [Vec3] {
        if !self.any {
            crate::linalg::scratch(&mut self.forces, n);
            self.any = true;
        }
        &mut self.forces
    }
}

/// The forces from outside the cloth at the start state `(t, cloth.x, cloth.v)` (wind and
/// moving attachments), into `out` (`scratch`: internal forces). A driven vertex's force is
/// minus the internal force on it: the power it puts into the cloth is that force times its
/// velocity (gravity on the driven vertex itself does no work on the cloth).
pub(super) fn external_forces(
    cloth: &Cloth,
    effects: &EffectSet,
    t: f64,
    out: &mut OutsideForces,
    scratch: &mut Vec<Vec3>,
) {
    out.any = false;
    let has_wind = effects.iter().any(|e| e.injects_energy());
    let moving_attachments =
        (cloth.kinematic.iter()).any(|(i, _)| cloth.v[*i as usize] != Vec3::ZERO);
    if !has_wind && !moving_attachments {
        return;
    }
    let s = State {
        t,
        x: &cloth.x,
        v: &cloth.v,
    };
    let n = cloth.len();
    let fext = out.add(n);
    effects.injecting_forces(&s, fext);
    if moving_attachments {
        crate::linalg::scratch(scratch, n);
        effects.forces(&s, scratch);
        for (i, _) in &cloth.kinematic {
            let i = *i as usize;
            fext[i] = -scratch[i];
        }
    }
}

/// Moving obstacles do work on the cloth inside the solve: through the springs on their
/// features (`moving_springs`: a link carrying the cloth), through the filter holding a vertex
/// at a moving surface's velocity (a ball pushing it) and through that surface's friction (a
/// forearm dragging a hem). All are work from outside: the springs' end forces (when the
/// integrator solves contacts), the held vertices' constraint impulses over `h` and the
/// friction drags' end forces join `out`. Nothing is added where nothing moves.
pub(in crate::sim) fn moving_contact_work(
    c: &Constraints,
    moving_springs: &[usize],
    report: &StepReport,
    solves_contacts: bool,
    (n, h): (usize, f64),
    out: &mut OutsideForces,
) {
    let impulses = report.impulses();
    let held_moving = |i: usize| {
        !matches!(c.filter[i], Filter::Free | Filter::Fixed) && c.target_velocity[i] != Vec3::ZERO
    };
    let any_held = impulses.is_some() && (0..n).any(held_moving);
    let rubbed = &report.moving_friction;
    if !any_held && rubbed.is_empty() && (moving_springs.is_empty() || !solves_contacts) {
        return;
    }
    let fext = out.add(n);
    if solves_contacts {
        for &k in moving_springs {
            if let (Some(spring), Some(f)) = (c.contacts.get(k), report.contact_forces.get(k)) {
                spring.add_point_force(spring.normal * *f, 1.0, fext);
            }
        }
    }
    if let Some(r) = impulses.filter(|_| any_held) {
        for i in (0..n).filter(|&i| held_moving(i)) {
            fext[i] += r[i] / h;
        }
    }
    for &(i, f) in rubbed.iter().filter(|r| (r.0 as usize) < n) {
        fext[i as usize] += f;
    }
}
