//! The linearised backward-Euler system `A dv = b`: `A = M - h df/dv - h^2 df/dx` from the
//! constant and state-dependent Jacobians, friction drags and contact springs, and
//! `b = h (f0 + h df/dx v0)`.

use super::solver::Implicit;
use crate::effects::State;
use crate::integrate::contact::ContactSpring;
use crate::integrate::friction::{self, Drag};
use crate::integrate::Dynamics;
use crate::linalg::BlockCsr;
use crate::Vec3;

impl Implicit {
    /// Assembles `A = M - h df/dv - h^2 df/dx` at `s` (Jacobians only).
    pub(super) fn assemble_matrix(&mut self, d: &Dynamics, s: &State, h: f64) {
        let (Some(a), Some(dfdv), Some(k)) =
            (self.a.as_mut(), self.dfdv.as_mut(), self.constant.as_ref())
        else {
            unreachable!("prepared before assembling");
        };
        a.assign(&k.dfdx);
        dfdv.assign(&k.dfdv);
        state_jacobians(d, s, a, dfdv);
        a.axpby(-h * h, -h, dfdv);
        a.add_diagonal(d.mass);
        friction::add_to_matrix(a, &self.drags, h);
        let n = s.x.len();
        self.pcg.extra.clear();
        for c in &d.constraints.contacts {
            if c.is_valid(n) && c.depth(s.x) > 0.0 {
                c.add_jacobian(a, h * h);
                self.pcg.extra.push(c, a, h * h);
            }
        }
        for (k, g) in &self.edge_drags {
            d.constraints.contacts[*k].add_point_block(a, g.damping(), h);
        }
    }

    /// Baraff-Witkin's first step at `s`: `f0`, `b = h (f0 + h df/dx v0)` and `A`.
    pub(super) fn assemble(&mut self, d: &Dynamics, s: &State, h: f64) {
        let n = s.x.len();
        let (Some(a), Some(dfdv), Some(k)) =
            (self.a.as_mut(), self.dfdv.as_mut(), self.constant.as_ref())
        else {
            unreachable!("prepared before assembling");
        };
        d.effects.forces(s, &mut self.f0);
        a.assign(&k.dfdx);
        dfdv.assign(&k.dfdv);
        state_jacobians(d, s, a, dfdv);
        a.mul(s.v, &mut self.b);
        for i in 0..n {
            self.b[i] = (self.f0[i] + self.b[i] * h) * h;
        }
        a.axpby(-h * h, -h, dfdv);
        a.add_diagonal(d.mass);
        // Friction drags: linear in v, so `A += h c S` and `b += h f_drag(v0)` are exact.
        let filt = &d.constraints.filter;
        // The last step's tangential load on each vertex, shared among its surfaces by their
        // Coulomb limits (see `Drag::fit`).
        let lagged = self.loads.len() == n;
        self.limit_sum.clear();
        self.limit_sum.resize(n, 0.0);
        for f in &d.constraints.friction {
            match self.limit_sum.get_mut(f.vertex as usize) {
                Some(l) if f.limit.is_finite() && f.limit > 0.0 => *l += f.limit,
                _ => {}
            }
        }
        self.drags.clear();
        let (loads, sums) = (&self.loads, &self.limit_sum);
        self.drags
            .extend(d.constraints.friction.iter().filter_map(|f| {
                let i = f.vertex as usize;
                let load = if lagged && sums[i] > 0.0 {
                    loads[i] * (f.limit / sums[i])
                } else {
                    Vec3::ZERO
                };
                (i < n)
                    .then(|| Drag::fit(f, &filt[i], s.v[i], h / d.mass[i], load))
                    .flatten()
            }));
        friction::fit_patches(&mut self.drags, s.v, d.mass, h);
        friction::add_to_matrix(a, &self.drags, h);
        for g in &self.drags {
            self.b[g.vertex] += g.force(s.v[g.vertex]) * h;
        }
        // Edge springs the cloth is in or heading into.
        self.spring_active.clear();
        for c in &d.constraints.contacts {
            let active = c.is_valid(n) && (c.depth(s.x) > 0.0 || c.depth_after(s.x, s.v, h) > 0.0);
            if active {
                spring_terms(c, a, &mut self.b, s, h, 1.0);
            }
            self.spring_active.push(active);
        }
        // Their contact points' friction: a drag on the point's slip (as the vertex drags
        // above), shared by weight like the normal force.
        self.edge_drags.clear();
        for (k, c) in d.constraints.contacts.iter().enumerate() {
            if !self.spring_active[k] || c.friction <= 0.0 {
                continue;
            }
            let u = c.point_velocity(s.v);
            let Some(g) = Drag::at_point(c.friction, c.normal, u, h / c.point_mass(d.mass)) else {
                continue;
            };
            c.add_point_block(a, g.damping(), h);
            c.add_point_force(g.force(u), h, &mut self.b);
            self.edge_drags.push((k, g));
        }
        self.off_pattern(d, h);
    }
}

impl Implicit {
    /// The active pair springs' couplings outside `A`'s pattern, for the PCG's products (see
    /// [`crate::integrate::contact::OffPattern`]).
    pub(super) fn off_pattern(&mut self, d: &Dynamics, h: f64) {
        self.pcg.extra.clear();
        let Some(a) = self.a.as_ref() else {
            return;
        };
        for (c, active) in d.constraints.contacts.iter().zip(&self.spring_active) {
            if *active {
                self.pcg.extra.push(c, a, h * h);
            }
        }
    }
}

/// Adds the state-dependent Jacobians at `s` to `a` (holding `df/dx`) and `dfdv`, with the
/// springs' stiffness at the front of a link's drag where the coupling names one.
fn state_jacobians(d: &Dynamics, s: &State, a: &mut BlockCsr, dfdv: &mut BlockCsr) {
    d.effects.add_varying_jacobians(s, a, dfdv);
    if !d.constraints.front_strain.is_empty() {
        d.effects
            .add_front_stiffness(s, &d.constraints.front_strain, a);
    }
}

/// Backward Euler's terms of edge spring `c` linearised at the start state `s`, times `sign`:
/// `A += h^2 k J` and `b += h (f(x0) + h df/dx v0)` (see [`crate::integrate::contact`]).
pub(super) fn spring_terms(
    c: &ContactSpring,
    a: &mut BlockCsr,
    b: &mut [Vec3],
    s: &State,
    h: f64,
    sign: f64,
) {
    c.add_jacobian(a, sign * h * h);
    c.add_force(c.depth(s.x), sign * h, b);
    c.add_jacobian_product(a, s.v, -sign * h * h, b);
}
