//! Contact holds: the constraint impulses `(I - S)(A dv - b)` of the solved system, and the
//! release of holds that would pull (the filter is bilateral, a contact only pushes).

use super::solver::Implicit;
use crate::integrate::Dynamics;
use crate::linalg::Filter;
use crate::Vec3;

impl Implicit {
    /// The constraint impulses of the linear system just solved, `(I - S)(A dv - b)` (zero for
    /// free vertices; none computed when no vertex is constrained).
    pub(super) fn linear_impulses(&mut self, filt: &[Filter]) {
        let n = self.dv.len();
        self.impulses.clear();
        self.impulses.resize(n, Vec3::ZERO);
        if filt.iter().all(|f| *f == Filter::Free) {
            return;
        }
        let Some(a) = self.a.as_ref() else {
            return;
        };
        self.pcg
            .extra
            .system_product(a, &self.dv, &mut self.impulses);
        for i in 0..n {
            self.impulses[i] = filt[i].constrained(self.impulses[i] - self.b[i]);
        }
    }

    /// Releases the vertices held against one surface whose constraint impulse (just computed by
    /// `linear_impulses`) pulls them into it, and holds again released ones the solve then
    /// moves into it (with those standing by from the step's start, `Constraints::standby`):
    /// the filter is bilateral, a contact can only push (an active set, like the springs'). The collision stage decides from the start-of-step forces which contacts to
    /// hold; a vertex next to an obstacle edge is lifted by the edge's spring within the solve,
    /// and held down it glued the lever a strip bent over the edge rests on. Returns whether
    /// any changed.
    pub(super) fn settle_holds(&mut self, filt: &mut [Filter], d: &Dynamics, v0: &[Vec3]) -> bool {
        /// Adhesion below this velocity change (m/s) is round-off, not a pull.
        const TOL: f64 = 1e-5;
        let mut changed = false;
        for (i, n) in self.released.iter().copied() {
            let target = d.constraints.target_velocity[i];
            if (v0[i] + self.dv[i] - target).dot(n) < -TOL {
                filt[i] = Filter::Direction(n);
                self.z[i] = filt[i].constrained(target - v0[i]);
                changed = true;
            }
        }
        self.released.retain(|(i, _)| filt[*i] == Filter::Free);
        for (i, f) in filt.iter_mut().enumerate() {
            if let Filter::Direction(n) = *f {
                if self.impulses[i].dot(n) < -TOL * d.mass[i]
                    && !self.released.iter().any(|r| r.0 == i)
                {
                    *f = Filter::Free;
                    self.z[i] = Vec3::ZERO;
                    self.released.push((i, n));
                    changed = true;
                }
            }
        }
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::EffectSet;
    use crate::integrate::{Constraints, ImplicitSettings, Integrator, StepReport};

    /// One implicit step of vertex 1 at the origin on a spring of rest length `rest` to a fixed
    /// vertex 0.1 m above it (pulled up when `rest` is shorter, pressed down when longer), with
    /// `constraints` set up for vertex 1 by `hold`; returns its velocity and constraint impulse.
    fn step_under_spring(rest: f64, hold: impl Fn(&mut Constraints)) -> (Vec3, Vec3) {
        use crate::cloth::topology::Spring;
        use crate::effects::Springs;
        let mut effects = EffectSet::new();
        effects.push(Box::new(Springs::new(
            "stretch",
            vec![Spring { i: 0, j: 1, rest }],
            vec![100.0],
            "k".into(),
        )));
        let mass = [1e-3, 1e-3];
        let mut constraints = Constraints::free(2);
        constraints.filter[0] = Filter::Fixed;
        hold(&mut constraints);
        let d = Dynamics {
            effects: &effects,
            mass: &mass,
            constraints: &constraints,
            nominal_step: 0.0,
        };
        let mut x = [Vec3::new(0.0, 0.0, 0.1), Vec3::ZERO];
        let mut v = [Vec3::ZERO; 2];
        let mut solver = Implicit::new(ImplicitSettings::default());
        solver.prepare(&effects, 2);
        let mut report = StepReport::default();
        solver.step(&d, 0.0, 1.0 / 120.0, &mut x, &mut v, &mut report);
        let impulse = report.impulses().map_or(Vec3::ZERO, |r| r[1]);
        (v[1], impulse)
    }

    /// A vertex held on a surface (normal +z) by the filter, pulled off it or pressed into it by a
    /// spring to a fixed vertex above: the filter is bilateral, the contact is not. Pulled, the
    /// step releases it (it moves up, no impulse); pressed, it stays held with a pushing impulse.
    #[test]
    fn holds_are_released_only_when_they_would_pull() {
        for (rest, pulled) in [(0.05, true), (0.2, false)] {
            let (v, impulse) =
                step_under_spring(rest, |c| c.filter[1] = Filter::Direction(Vec3::Z));
            if pulled {
                assert!(v.z > 0.0, "pulled vertex stayed held: v {v:?}");
                assert_eq!(
                    impulse,
                    Vec3::ZERO,
                    "a released vertex has no constraint impulse"
                );
            } else {
                assert_eq!(v.z, 0.0, "pressed vertex left the surface: v {v:?}");
                assert!(impulse.z > 0.0, "the surface must push: {impulse:?}");
            }
        }
    }

    /// A free vertex standing by at a surface (normal +z; cloth on its way out of a solid whose
    /// contact the coupling released) is held after all when the solve drives it into the
    /// surface, and left free when it moves off. Without the standby the pressed vertex goes in.
    #[test]
    fn a_vertex_standing_by_is_held_only_when_the_solve_drives_it_in() {
        for (rest, pressed) in [(0.05, false), (0.2, true)] {
            for standby in [false, true] {
                let (v, _) = step_under_spring(rest, |c| {
                    if standby {
                        c.standby.push((1, Vec3::Z));
                    }
                });
                let what = format!("rest {rest}, standby {standby}: v {v:?}");
                match (pressed, standby) {
                    (true, true) => assert!(v.z.abs() < 1e-9, "{what}"),
                    (true, false) => assert!(v.z < -0.1, "{what}"),
                    (false, _) => assert!(v.z > 0.1, "{what}"),
                }
            }
        }
    }
}
