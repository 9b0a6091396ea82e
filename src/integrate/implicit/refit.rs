//! The step's active sets after a solve: friction drags (held vertices' and edge springs'
//! contact points') refitted to the sliding speed (see [`crate::integrate::friction`]) and contact springs switched on or
//! off by where the solved step ends (see [`crate::integrate::contact`]); each change updates
//! `A` and `b` in place. Held vertices' friction modes are decided before the solve on the last
//! step's loads (see `Drag::fit`) and refitted only where the solve contradicts them.

use super::assembly::spring_terms;
use super::solver::Implicit;
use crate::effects::State;
use crate::integrate::{friction, Dynamics};
use crate::Vec3;

impl Implicit {
    /// Refits the friction of acting edge springs' contact points that the iterate's velocity
    /// calls another mode for (see `Drag::refit`, and `Drag::refit_unloaded` for two cloth
    /// layers); returns whether any changed (the system
    /// then needs a new solve).
    pub(super) fn refit_edge_drags(&mut self, d: &Dynamics, v0: &[Vec3], h: f64) -> bool {
        let Some(a) = self.a.as_mut() else {
            return false;
        };
        let mut changed = false;
        for (k, g) in self.edge_drags.iter_mut() {
            let c = &d.constraints.contacts[*k];
            let u0 = c.point_velocity(v0);
            let u1 = u0 + c.point_velocity(&self.dv);
            let refit = if c.is_pair() {
                g.refit_unloaded(u1)
            } else {
                g.refit(u1)
            };
            let Some(mode) = refit else {
                continue;
            };
            let (old_force, old_damping) = (g.force(u0), g.damping());
            g.mode = mode;
            c.add_point_block(a, g.damping() - old_damping, h);
            c.add_point_force(g.force(u0) - old_force, h, &mut self.b);
            changed = true;
        }
        changed
    }

    /// Adds (`sign` 1) or removes (-1) edge springs so that exactly those whose cloth point ends
    /// the solved step inside their layer act (see [`crate::integrate::contact`]); returns whether any
    /// changed (the system then needs a new solve).
    pub(super) fn refit_springs(&mut self, d: &Dynamics, s: &State, h: f64) -> bool {
        let Some(a) = self.a.as_mut() else {
            return false;
        };
        let n = s.x.len();
        let mut changed = false;
        for (c, active) in d
            .constraints
            .contacts
            .iter()
            .zip(self.spring_active.iter_mut())
        {
            if !c.is_valid(n) {
                continue;
            }
            let wanted = c.depth_after(s.x, s.v, h) - h * c.along(&self.dv) > 0.0;
            if wanted != *active {
                spring_terms(c, a, &mut self.b, s, h, if wanted { 1.0 } else { -1.0 });
                *active = wanted;
                changed = true;
            }
        }
        if changed {
            self.off_pattern(d, h);
        }
        changed
    }

    /// Makes held vertices' stickers that the iterate `v0 + dv` overloads slide (see
    /// `Drag::overloaded`): what the lagged choice before the solve missed, a load that rose
    /// within the step (a cloth edge shoved by a robot link); returns whether any changed (the
    /// system then needs a new solve). Pinch patches only on an answer solved to the scene's
    /// tolerance (`tight`): their sticking drags are so stiff (`mu N / STICK_SPEED`) that the
    /// loose answer of the first rounds overloads them falsely, and a patch made to slide
    /// does not stick again within the step: a towel carried in a grip three times its weight
    /// slid out of it.
    pub(super) fn refit_drags(&mut self, v0: &[Vec3], mass: &[f64], h: f64, tight: bool) -> bool {
        let Some(a) = self.a.as_mut() else {
            return false;
        };
        let dv = &self.dv;
        let refits = friction::overloaded(&self.drags, |i| v0[i] + dv[i], mass, tight);
        let changed = !refits.is_empty();
        for (k, mode) in refits {
            let g = &mut self.drags[k];
            let i = g.vertex;
            let (old_force, old_damping) = (g.force(v0[i]), g.damping());
            g.mode = mode;
            a.add(i as u32, i as u32, (g.damping() - old_damping) * h);
            self.b[i] += (g.force(v0[i]) - old_force) * h;
        }
        changed
    }
}
