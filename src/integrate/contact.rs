//! Static obstacle edges and corners as one-sided springs inside the implicit solve.
//!
//! A vertex against an obstacle face is held by the constraint filter. A sharp edge touches the
//! cloth between vertices (the cloth folds over it), where no vertex filter applies. Answered
//! after the solve, by moving the touching segment's vertices back out, it stretches the cloth
//! over the edge: the solver has already moved their neighbours with them, and the tension of
//! that stretch presses the cloth onto the edge (a strip that Coulomb lets slide off a table
//! sticks under many times its hanging weight's tension, tests/table_edge.rs). Here each such
//! contact is a spring on the cloth point `c = sum_k w_k x_k` with depth
//! `d = gap - n . (c - p)` (feature point `p`, normal `n` towards the cloth), energy
//! `k d^2 / 2` while `d > 0`: force `k d w_k n` on vertex `k`, Jacobian `-k w_k w_l n n^T`.
//! It enters backward Euler like the cloth's own springs, so the edge's normal force comes out
//! of the same solve that balances the cloth's tension.
//!
//! A spring acts only while the step ends inside its layer: an active set, started from the
//! springs the cloth is in or heading into, is refitted after the solve (like the friction
//! modes, see [`super::friction`]).

use crate::linalg::outer;
use crate::linalg::BlockCsr;
use crate::{Mat3, Vec3};

/// One contact of a static obstacle feature with the cloth point `sum weights_k x_verts_k`, or,
/// with weights of both signs summing to zero, of two cloth points with each other (a vertex and
/// the face of another layer under it: `x_p - sum b_i x_i`, `point` zero), whose forces are then
/// equal and opposite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSpring {
    pub verts: [u32; 4],
    /// Barycentric weights, or the pair's signed ones (a weight of 0 leaves its slot unused).
    pub weights: [f64; 4],
    /// Unit normal from the feature (or the second point) towards the cloth (the first point).
    pub normal: Vec3,
    /// The feature's contact point (world; zero for two cloth points).
    pub point: Vec3,
    /// Distance the cloth point keeps from `point` along `normal` (m).
    pub gap: f64,
    /// Spring constant (N/m).
    pub stiffness: f64,
    /// Coulomb limit `mu N` of the contact point's friction (N; 0: none).
    pub friction: f64,
}

impl ContactSpring {
    /// Whether the spring can be used with `n` vertices (indices in range, finite, positive).
    pub fn is_valid(&self, n: usize) -> bool {
        self.verts.iter().all(|&v| (v as usize) < n)
            && self.weights.iter().all(|w| w.is_finite())
            && self.weights.iter().any(|w| *w != 0.0)
            && self.normal.is_finite()
            && (self.normal.length() - 1.0).abs() < 1e-6
            && self.point.is_finite()
            && self.gap.is_finite()
            && self.stiffness.is_finite()
            && self.stiffness > 0.0
            && self.friction.is_finite()
            && self.friction >= 0.0
    }

    /// The used slots: (vertex, weight) with weight > 0, each vertex once.
    pub(crate) fn slots(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        (0..4).filter_map(move |k| {
            let repeated = self.verts[..k].contains(&self.verts[k]);
            (self.weights[k] != 0.0 && !repeated)
                .then_some((self.verts[k] as usize, self.weights[k]))
        })
    }

    /// Whether the spring joins two cloth points (weights of both signs): its forces are equal
    /// and opposite.
    pub fn is_pair(&self) -> bool {
        self.weights.iter().any(|w| *w < 0.0)
    }

    /// The factor a lumped diagonal carries: `c c^T <= (sum |c|) diag(|c|)` (Cauchy-Schwarz), so
    /// `k S |w_k| n n^T` per vertex dominates the exact blocks; `S = sum |w_k|` (2 for a
    /// vertex-face pair), 1 for a cloth point's barycentric weights (which sum to one).
    fn spread(&self) -> f64 {
        if self.is_pair() {
            self.slots().map(|(_, w)| w.abs()).sum()
        } else {
            1.0
        }
    }

    /// The cloth point's normal component of `u` (positions or velocities).
    pub fn along(&self, u: &[Vec3]) -> f64 {
        self.slots().map(|(i, w)| w * self.normal.dot(u[i])).sum()
    }

    /// The contact point's velocity, `sum w_k v_k`.
    pub fn point_velocity(&self, v: &[Vec3]) -> Vec3 {
        self.slots().map(|(i, w)| v[i] * w).sum()
    }

    /// The contact point's effective mass, `1 / sum (w_k^2 / m_k)` (kg): what a force on the
    /// point accelerates.
    pub fn point_mass(&self, mass: &[f64]) -> f64 {
        1.0 / self.slots().map(|(i, w)| w * w / mass[i]).sum::<f64>()
    }

    /// Adds the force `f` on the contact point, shared by weight, times `scale` to `out`.
    pub fn add_point_force(&self, f: Vec3, scale: f64, out: &mut [Vec3]) {
        for (i, w) in self.slots() {
            out[i] += f * (w * scale);
        }
    }

    /// Depth into the layer at positions `x` (positive: inside).
    pub fn depth(&self, x: &[Vec3]) -> f64 {
        self.gap - self.along(x) + self.normal.dot(self.point)
    }

    /// Depth after moving from `x` at velocities `v` for `h`.
    pub fn depth_after(&self, x: &[Vec3], v: &[Vec3], h: f64) -> f64 {
        self.depth(x) - h * self.along(v)
    }

    /// Normal force (N) at positions `x`: `k max(d, 0)`.
    pub fn force(&self, x: &[Vec3]) -> f64 {
        self.stiffness * self.depth(x).max(0.0)
    }

    /// Adds `scale` times the force `k d w_k n` for depth `d` to `f`.
    pub fn add_force(&self, d: f64, scale: f64, f: &mut [Vec3]) {
        let magnitude = self.stiffness * d * scale;
        for (i, w) in self.slots() {
            f[i] += self.normal * (w * magnitude);
        }
    }

    /// Whether every pair of the used slots has its block in `a`'s pattern (else the point's
    /// blocks are lumped onto the diagonal).
    fn in_pattern(&self, a: &BlockCsr) -> bool {
        self.slots().all(|(i, _)| {
            self.slots()
                .all(|(j, _)| i == j || a.try_slot(i as u32, j as u32).is_some())
        })
    }

    /// Adds `scale k w_k w_l n n^T` (the negated force Jacobian) to `a`. Pairs missing from the
    /// sparsity pattern (cloth without shear springs has no block across a triangle diagonal; a
    /// vertex and a face of another layer never share one) are lumped onto the diagonal,
    /// `k S |w_k| n n^T` per vertex ([`Self::spread`]): that dominates the exact block, so the
    /// system only gets stiffer, never indefinite.
    pub fn add_jacobian(&self, a: &mut BlockCsr, scale: f64) {
        let nn = outer(self.normal, self.normal) * self.stiffness;
        self.add_point_block(a, nn, scale);
    }

    /// Adds `scale w_k w_l B` for a block `B` acting on the contact point (the point's
    /// stiffness or damping), lumped onto the diagonal as in [`Self::add_jacobian`] when a
    /// pair is missing from the pattern.
    pub fn add_point_block(&self, a: &mut BlockCsr, block: Mat3, scale: f64) {
        let nn = block * scale;
        let complete = self.in_pattern(a);
        let spread = self.spread();
        for (i, wi) in self.slots() {
            if complete {
                for (j, wj) in self.slots() {
                    a.add(i as u32, j as u32, nn * (wi * wj));
                }
            } else {
                a.add(i as u32, i as u32, nn * (wi.abs() * spread));
            }
        }
    }

    /// The Jacobian's product with `u` as [`Self::add_jacobian`] adds it, times `scale`, into `out`.
    pub fn add_jacobian_product(&self, a: &BlockCsr, u: &[Vec3], scale: f64, out: &mut [Vec3]) {
        let k = self.stiffness * scale;
        // A pair's lumped diagonal is completed by `OffPattern` in the solver's products: its
        // product here is the exact one.
        let exact = self.is_pair() || self.in_pattern(a);
        let un = self.along(u);
        let spread = self.spread();
        for (i, wi) in self.slots() {
            let kw = if exact {
                k * wi * un
            } else {
                k * wi.abs() * spread * self.normal.dot(u[i])
            };
            out[i] += self.normal * kw;
        }
    }
}

/// The part of the active pair springs' Jacobian that the matrix's pattern cannot hold (a
/// vertex and a face of another layer share no block), applied without a matrix: the exact
/// `k w_k w_l n n^T` minus the lumped diagonal [`ContactSpring::add_jacobian`] put in `A`.
/// `A` plus this is the exact backward-Euler matrix, so the solve's forces on a pair's two
/// sides stay equal and opposite (with the diagonal alone a towel resting on a hammock pushes
/// it down with several times its weight); `A` alone, stiffer, preconditions it.
#[derive(Debug, Default)]
pub(crate) struct OffPattern {
    terms: Vec<(ContactSpring, f64)>,
}

impl OffPattern {
    pub fn clear(&mut self) {
        self.terms.clear();
    }

    /// Adds pair spring `c` (when its blocks are missing from `a`'s pattern) at `scale`.
    pub fn push(&mut self, c: &ContactSpring, a: &BlockCsr, scale: f64) {
        if c.is_pair() && !c.in_pattern(a) {
            self.terms.push((*c, scale));
        }
    }

    /// `out = (A + exact - lumped) u`: the system's product, `A`'s and the terms'.
    pub fn system_product(&self, a: &BlockCsr, u: &[Vec3], out: &mut [Vec3]) {
        a.mul(u, out);
        self.add_product(u, out);
    }

    /// `out += (exact - lumped) u` over the terms.
    fn add_product(&self, u: &[Vec3], out: &mut [Vec3]) {
        for (c, scale) in &self.terms {
            let k = c.stiffness * scale;
            let (un, spread) = (c.along(u), c.spread());
            for (i, wi) in c.slots() {
                out[i] += c.normal * (k * (wi * un - wi.abs() * spread * c.normal.dot(u[i])));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::PatternBuilder;

    fn spring() -> ContactSpring {
        ContactSpring {
            verts: [0, 1, 1, 1],
            weights: [0.25, 0.75, 0.0, 0.0],
            normal: Vec3::Z,
            point: Vec3::new(0.0, 0.0, 1.0),
            gap: 0.01,
            stiffness: 100.0,
            friction: 0.0,
        }
    }

    #[test]
    fn depth_and_force_follow_the_contact_point() {
        let s = spring();
        // c = 0.25 * 1.000 + 0.75 * 1.004 = 1.003: 3 mm above p, 7 mm into the 1 cm layer.
        let x = [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.004)];
        assert!((s.depth(&x) - 0.007).abs() < 1e-12);
        assert!((s.force(&x) - 0.7).abs() < 1e-10);
        let mut f = [Vec3::ZERO; 2];
        s.add_force(s.depth(&x), 1.0, &mut f);
        assert!((f[0] - Vec3::new(0.0, 0.0, 0.175)).length() < 1e-12);
        assert!((f[1] - Vec3::new(0.0, 0.0, 0.525)).length() < 1e-12);
        let v = [Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0)];
        assert!((s.depth_after(&x, &v, 0.01) - (0.007 - 0.0075)).abs() < 1e-12);
    }

    /// The exact Jacobian block when the pair is in the pattern, the lumped one when it is not;
    /// both match their products.
    #[test]
    fn jacobian_is_exact_or_lumped() {
        let s = spring();
        let mut p = PatternBuilder::new();
        p.couple(0, 1);
        for (mut a, exact) in [(p.build(2), true), (PatternBuilder::new().build(2), false)] {
            s.add_jacobian(&mut a, 1.0);
            let u = [Vec3::new(0.3, -0.2, 0.5), Vec3::new(0.1, 0.4, -0.7)];
            let mut au = [Vec3::ZERO; 2];
            a.mul(&u, &mut au);
            let mut ju = [Vec3::ZERO; 2];
            s.add_jacobian_product(&a, &u, 1.0, &mut ju);
            for i in 0..2 {
                assert!(
                    (au[i] - ju[i]).length() < 1e-12,
                    "{exact}: {au:?} vs {ju:?}"
                );
            }
            let expect0 = if exact {
                100.0 * 0.25 * (0.25 * 0.5 + 0.75 * -0.7)
            } else {
                100.0 * 0.25 * 0.5
            };
            assert!((au[0].z - expect0).abs() < 1e-12, "{exact}: {}", au[0].z);
        }
    }
}
