//! The checks that decide whether Newton iterations follow the linearised solve: the energy
//! it creates ([`EnergyCheck`]) and the stretch its springs' turning hides from it
//! ([`unseen_stretch`]).

use super::solver::Implicit;
use crate::effects::State;
use crate::integrate::Dynamics;
use crate::Vec3;

/// Energy a step may create, relative to its kinetic energy (start plus end), before Newton
/// iterations are added: well above what the linearisation error of an ordinary cloth step
/// creates, far below a stiff spring's rotation gain (see [`EnergyCheck`]).
const CREATED_ENERGY: f64 = 1e-2;

/// Relative round-off of the energy sums (the gravity potential can dwarf the changes).
const ROUND_OFF: f64 = 1e-12;

/// The energy a backward-Euler iterate `v1 = v0 + dv`, `x1 = x0 + h v1` creates.
///
/// With `g = M dv - h f(x1, v1)` the residual of the nonlinear system, the kinetic energy obeys
/// `KE1 - KE0 = v1 . M dv - |dv|^2_M / 2` exactly, so
///
/// `E1 - E0 = [U1 - U0 - (x1 - x0) . grad U(x1)] + h v1 . f_other + v1 . (I - S) g + v1 . S g - |dv|^2_M / 2`
///
/// (`f_other` the damping and wind forces, `(I - S) g` the constraint reaction). The bracket is
/// `<= 0` for convex `U`; so a converged step (`S g = 0`) dissipates, and
/// `created = E1 - E0 - h v1 . f_other - v1 . (I - S) g` is the energy the step makes up.
///
/// One linearised solve leaves `S g` large when stiff springs rotate: the linearisation has no
/// transverse stiffness at rest length, so moving along the tangent stretches the spring to
/// second order (`dL ~ |dx|^2 / 2L`) and `k dL^2 / 2` appears from nothing (a 1e6 N/m cloth
/// gains joules per step). Newton iterations remove it.
#[derive(Debug, Clone, Copy)]
pub(super) struct EnergyCheck {
    pub(super) created: f64,
    pub(super) allowed: f64,
    /// Potential energy at the iterate's end positions.
    pub(super) u1: f64,
}

impl EnergyCheck {
    pub(super) fn accepted(&self) -> bool {
        self.created <= self.allowed
    }
}

/// The largest stretch over rest length a linearisation at `x0` does not see at `x1`, over the
/// effects' springs ([`crate::effects::Effect::unseen_stretch`]); Newton iterations follow while
/// it exceeds `ImplicitSettings::linearisation_tolerance`. The energy check is global: one edge
/// turned across the skirt's flapping border of a cloth landing on a ball (S1 64x64, `cargo
/// bench --bench contact`) can stretch far in one solve while the landing's dissipation
/// elsewhere keeps the sum negative.
pub(super) fn unseen_stretch(d: &Dynamics, x0: &[Vec3], x1: &[Vec3]) -> f64 {
    d.effects
        .iter()
        .map(|e| e.unseen_stretch(x0, x1))
        .fold(0.0, f64::max)
}

/// Potential energy of the conservative effects at `x`.
pub(super) fn potential(d: &Dynamics, x: &[Vec3]) -> f64 {
    d.effects.energy(x)
}

impl Implicit {
    /// Energy bookkeeping of the iterate in `xk`, `vk` (see [`EnergyCheck`]); leaves the forces
    /// at the iterate's end state in `f0` and the right-hand side of the next Newton correction,
    /// `-g = h f(x1, v1) - M dv`, in `b`.
    pub(super) fn energy_check(
        &mut self,
        d: &Dynamics,
        t1: f64,
        h: f64,
        v0: &[Vec3],
        u0: f64,
    ) -> EnergyCheck {
        let filt = &d.constraints.filter;
        let s = State {
            t: t1,
            x: &self.xk,
            v: &self.vk,
        };
        // Conservative (position-only) forces and their energy in one pass into `f0`; the rest
        // (damping, wind) into `b`.
        self.f0.fill(Vec3::ZERO);
        self.b.fill(Vec3::ZERO);
        let mut u1 = 0.0;
        for e in d.effects.iter() {
            if e.position_only() {
                u1 += e.add_forces_energy(&s, &mut self.f0);
            } else {
                e.add_forces(&s, &mut self.b);
            }
        }
        for g in &self.drags {
            self.b[g.vertex] += g.force(self.vk[g.vertex]);
        }
        // Edge springs count as outside work (their energy is not in the potential).
        for c in &d.constraints.contacts {
            if c.is_valid(self.xk.len()) {
                c.add_force(c.depth(&self.xk).max(0.0), 1.0, &mut self.b);
            }
        }
        for (k, g) in &self.edge_drags {
            let c = &d.constraints.contacts[*k];
            c.add_point_force(g.force(c.point_velocity(&self.vk)), 1.0, &mut self.b);
        }
        let (mut ke0, mut ke1, mut w_other, mut w_constraint) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..self.f0.len() {
            let (m, v1) = (d.mass[i], self.vk[i]);
            let g = self.dv[i] * m - (self.f0[i] + self.b[i]) * h;
            w_other += h * v1.dot(self.b[i]);
            w_constraint += v1.dot(filt[i].constrained(g));
            ke0 += 0.5 * m * v0[i].length_squared();
            ke1 += 0.5 * m * v1.length_squared();
            self.b[i] = -g;
        }
        EnergyCheck {
            u1,
            created: (ke1 + u1) - (ke0 + u0) - w_other - w_constraint,
            allowed: CREATED_ENERGY * (ke0 + ke1) + ROUND_OFF * (ke0 + ke1 + u0.abs() + u1.abs()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::EffectSet;
    use crate::integrate::{ImplicitSettings, Integrator, StepReport};
    use crate::linalg::Filter;
    /// A stiff spring swinging about a pinned end (a stiff cloth's energy gain in one spring): at
    /// rest length the linearisation has no transverse stiffness, so one Baraff-Witkin solve moves
    /// the free end along the tangent by `v h` and stretches the spring by
    /// `sqrt(l^2 + (v h)^2) - l` = 7 mm, i.e. `k e^2 / 2` = 26 J out of 25 uJ of kinetic energy.
    /// The Newton iterations must bring it back onto (about) the circle without creating energy.
    #[test]
    fn stiff_rotating_spring_creates_no_energy() {
        use crate::cloth::topology::Spring;
        use crate::effects::Springs;
        use crate::integrate::Constraints;
        let (l, k, m, speed, h) = (1.0 / 64.0, 1e6, 5e-5, 1.0, 1.0 / 60.0);
        let mut effects = EffectSet::new();
        effects.push(Box::new(Springs::new(
            "stretch",
            vec![Spring {
                i: 0,
                j: 1,
                rest: l,
            }],
            vec![k],
            "k".into(),
        )));
        let mass = [m, m];
        let mut constraints = Constraints::free(2);
        constraints.filter[0] = Filter::Fixed;
        let d = Dynamics {
            effects: &effects,
            mass: &mass,
            constraints: &constraints,
            nominal_step: 0.0,
        };
        let mut x = [Vec3::ZERO, Vec3::new(l, 0.0, 0.0)];
        let mut v = [Vec3::ZERO, Vec3::new(0.0, speed, 0.0)];
        let energy = |x: &[Vec3], v: &[Vec3]| 0.5 * m * v[1].length_squared() + effects.energy(x);
        let e0 = energy(&x, &v);
        let mut solver = Implicit::new(ImplicitSettings {
            cg_tolerance: 1e-10,
            ..ImplicitSettings::default()
        });
        solver.prepare(&effects, 2);
        for step in 0..20 {
            let before = energy(&x, &v);
            let mut stats = StepReport::default();
            solver.step(&d, step as f64 * h, h, &mut x, &mut v, &mut stats);
            let after = energy(&x, &v);
            assert!(
                after.is_finite() && after <= before,
                "step {step}: {before} J -> {after} J ({stats:?})"
            );
            // Backward Euler keeps the stiff spring near its rest length: within the strain
            // whose energy is the kinetic energy, sqrt(2 E0 / k) / l.
            let strain = (x[1].length() - l).abs() / l;
            assert!(
                strain <= (2.0 * e0 / k).sqrt() / l,
                "step {step}: strain {strain}"
            );
            assert!(
                stats.force_evaluations > 2 || step > 0,
                "the first step must iterate"
            );
        }
    }
    /// The energy check is global: a step that dissipates elsewhere hides a spring the solve
    /// turned. The same stiff spring turning about a pinned end (0.6 m/s: the linearised solve
    /// stretches it by `sqrt(l^2 + (v h)^2) - l`, 18.7 %, 4.3 J) beside a stiff spring released
    /// 10 mm from rest, whose backward-Euler step removes its 50 J: the sum is negative, and
    /// only the turned spring's unseen stretch sends the step to Newton, which must end it within
    /// the default linearisation tolerance of rest.
    #[test]
    fn a_turned_spring_gets_newton_where_dissipation_hides_its_energy() {
        use crate::cloth::topology::Spring;
        use crate::effects::Springs;
        use crate::integrate::Constraints;
        let (l, k, m, speed, h) = (1.0 / 64.0, 1e6, 5e-5, 0.6, 1.0 / 60.0);
        let mut effects = EffectSet::new();
        let spring = |i, j| Spring { i, j, rest: l };
        effects.push(Box::new(Springs::new(
            "stretch",
            vec![spring(0, 1), spring(2, 3)],
            vec![k, k],
            "k".into(),
        )));
        let mass = [m; 4];
        let mut constraints = Constraints::free(4);
        constraints.filter[0] = Filter::Fixed;
        constraints.filter[2] = Filter::Fixed;
        let d = Dynamics {
            effects: &effects,
            mass: &mass,
            constraints: &constraints,
            nominal_step: 0.0,
        };
        let far = Vec3::new(0.0, 0.0, 1.0);
        let mut x = [
            Vec3::ZERO,
            Vec3::new(l, 0.0, 0.0),
            far,
            far + Vec3::new(l + 0.01, 0.0, 0.0),
        ];
        let mut v = [
            Vec3::ZERO,
            Vec3::new(0.0, speed, 0.0),
            Vec3::ZERO,
            Vec3::ZERO,
        ];
        let mut solver = Implicit::new(ImplicitSettings {
            cg_tolerance: 1e-10,
            ..ImplicitSettings::default()
        });
        solver.prepare(&effects, 4);
        let e0 = effects.energy(&x) + 0.5 * m * speed * speed;
        let mut stats = StepReport::default();
        solver.step(&d, 0.0, h, &mut x, &mut v, &mut stats);
        let e1 = effects.energy(&x) + v.iter().map(|v| 0.5 * m * v.length_squared()).sum::<f64>();
        assert!(e1 < e0, "the step dissipates: {e0} J -> {e1} J");
        let strain = x[1].length() / l - 1.0;
        assert!(
            stats.force_evaluations > 2
                && strain.abs() <= ImplicitSettings::default().linearisation_tolerance,
            "turned spring at {strain:.4} strain after {} force evaluations",
            stats.force_evaluations
        );
    }
}
