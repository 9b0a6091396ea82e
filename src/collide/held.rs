//! The implicit solver's velocity filter for a vertex held by several contact surfaces at once.
//!
//! A vertex pressed into two surfaces (cloth wedged between a robot's hand and the top of its
//! base) must keep its normal velocity on BOTH: `S = I - n1 n1^T` for only one of them lets the
//! spring forces drive it straight into the other obstacle, whose layer the collision stage then
//! restores by moving the position alone. Each substep stores the solver's push in the springs,
//! and the wedged cloth gains energy without bound. Two independent normals leave one free
//! direction, their edge line `e = n1 x n2 / |n1 x n2|` (`S = e e^T`); three leave none.

use crate::linalg::Filter;
use crate::{Mat3, Vec3};

/// Normals closer than this (sine of the angle to the span of the normals kept so far) add no
/// independent constraint: two contacts on (nearly) the same plane, or facing each other (a
/// pinch, which the collision stage centres). Keeping them would make the target velocity's
/// small linear system ill-conditioned (1/sin^2); at 0.25 (14.5 degrees) it is at most 16.
const MIN_SINE: f64 = 0.25;

/// Contact normals facing each other closer than this cosine (120 degrees) pinch the vertex
/// (the collision stage's `center_pinched` uses the same test).
const PINCH_COSINE: f64 = -0.5;

/// The contact normals a vertex is held against this substep (linearly independent, at most 3).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HeldNormals {
    normals: [Vec3; 3],
    /// World velocity of each surface at the contact.
    surface: [Vec3; 3],
    len: usize,
}

impl HeldNormals {
    /// Collects the contacts `(unit normal, surface velocity)` of one vertex in order (others are
    /// skipped). A contact facing a kept one (more than 120 degrees apart: a pinch, which the
    /// collision stage centres between the two surfaces with their mean normal velocity) gives
    /// the kept normal that mean velocity instead of a constraint of its own: holding each
    /// surface's velocity would crush the vertex between them as the gap closes. A contact whose
    /// normal is (nearly) dependent on the ones kept replaces the only one kept (the latest
    /// contact wins, as for a single surface) or is dropped when two or more are kept.
    pub fn from_contacts(contacts: impl IntoIterator<Item = (Vec3, Vec3)>) -> Self {
        let mut h = Self::default();
        for (n, s) in contacts {
            // Contact normals are unit already; normalizing again would change them by rounding,
            // and the cloth's contact chatter amplifies even that (more fast vertices on
            // tests/contact_rest.rs's shirt).
            if !(n.is_finite() && s.is_finite()) || (n.length_squared() - 1.0).abs() > 1e-6 {
                continue;
            }
            if let Some(k) = (0..h.len).find(|&k| h.normals[k].dot(n) < PINCH_COSINE) {
                let nk = h.normals[k];
                h.surface[k] += nk * (0.5 * (s - h.surface[k]).dot(nk));
                continue;
            }
            if h.len == 3 {
                continue;
            }
            // Residual of n off the span of the kept normals (Gram-Schmidt).
            let mut r = n;
            for q in h.orthonormal().iter().take(h.len) {
                r -= *q * q.dot(r);
            }
            if r.length() >= MIN_SINE {
                h.normals[h.len] = n;
                h.surface[h.len] = s;
                h.len += 1;
            } else if h.len == 1 {
                h.normals[0] = n;
                h.surface[0] = s;
            }
        }
        h
    }

    pub fn normals(&self) -> &[Vec3] {
        &self.normals[..self.len]
    }

    /// The surface velocity of each kept normal (a pinch's: the mean of its two surfaces).
    pub fn surfaces(&self) -> &[Vec3] {
        &self.surface[..self.len]
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn orthonormal(&self) -> [Vec3; 3] {
        let mut q = [Vec3::ZERO; 3];
        for k in 0..self.len {
            let mut r = self.normals[k];
            for p in q.iter().take(k) {
                r -= *p * p.dot(r);
            }
            q[k] = r.normalize_or_zero();
        }
        q
    }

    /// The filter and the target velocity whose constrained components are the surfaces' normal
    /// velocities: `target . n_k = surface_k . n_k` for every kept normal.
    pub fn filter(&self) -> (Filter, Vec3) {
        match self.len {
            0 => (Filter::Free, Vec3::ZERO),
            1 => (Filter::Direction(self.normals[0]), self.surface[0]),
            2 => {
                let e = self.normals[0].cross(self.normals[1]).normalize();
                let rhs = [0, 1].map(|k| self.surface[k].dot(self.normals[k]));
                (Filter::Line(e), self.combine(&self.solve(rhs)))
            }
            _ => {
                let rhs = [0, 1, 2].map(|k| self.surface[k].dot(self.normals[k]));
                (Filter::Fixed, self.combine(&self.solve(rhs)))
            }
        }
    }

    /// Splits a velocity change into its components along the kept normals: the `lambda_k` with
    /// `sum lambda_k n_k` = the part of `dv` in their span (the normal impulse per unit mass each
    /// surface gave, for its friction).
    pub fn split(&self, dv: Vec3) -> [f64; 3] {
        let mut rhs = [0.0; 3];
        for (r, n) in rhs.iter_mut().zip(self.normals()) {
            *r = n.dot(dv);
        }
        self.solve(rhs)
    }

    fn combine(&self, lambda: &[f64; 3]) -> Vec3 {
        self.normals()
            .iter()
            .zip(lambda)
            .fold(Vec3::ZERO, |a, (n, l)| a + *n * *l)
    }

    /// Solves the Gram system `G lambda = rhs`, `G_jk = n_j . n_k`, over the kept normals
    /// (well-conditioned: each normal is at least `MIN_SINE` off the span of the others kept
    /// before it).
    fn solve<const K: usize>(&self, rhs: [f64; K]) -> [f64; 3] {
        let n = &self.normals;
        let mut out = [0.0; 3];
        match self.len {
            1 => out[0] = rhs[0],
            2 => {
                let c = n[0].dot(n[1]);
                let det = 1.0 - c * c;
                out[0] = (rhs[0] - c * rhs[1]) / det;
                out[1] = (rhs[1] - c * rhs[0]) / det;
            }
            3 => {
                let g = Mat3::from_cols(
                    Vec3::new(1.0, n[0].dot(n[1]), n[0].dot(n[2])),
                    Vec3::new(n[1].dot(n[0]), 1.0, n[1].dot(n[2])),
                    Vec3::new(n[2].dot(n[0]), n[2].dot(n[1]), 1.0),
                );
                let r = Vec3::new(rhs[0], rhs[1], rhs.get(2).copied().unwrap_or(0.0));
                let l = g.inverse() * r;
                out = [l.x, l.y, l.z];
            }
            _ => {}
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wedge(deg: f64) -> (Vec3, Vec3) {
        let a = deg.to_radians();
        (Vec3::Z, Vec3::new(a.sin(), 0.0, a.cos()))
    }

    #[test]
    fn two_surfaces_leave_only_their_edge_line_free() {
        let (n1, n2) = wedge(103.0);
        let (s1, s2) = (Vec3::ZERO, Vec3::new(-1.5, 0.3, -0.4));
        let h = HeldNormals::from_contacts([(n1, s1), (n2, s2)]);
        let (f, target) = h.filter();
        // Both normal components are removed, the edge line (y) is kept.
        let a = Vec3::new(0.7, -1.3, 2.1);
        let fa = f.apply(a);
        assert!(fa.dot(n1).abs() < 1e-12 && fa.dot(n2).abs() < 1e-12, "{fa}");
        assert!((fa - Vec3::new(0.0, -1.3, 0.0)).length() < 1e-12, "{fa}");
        // The target velocity meets both surfaces' normal velocities.
        assert!((target.dot(n1) - s1.dot(n1)).abs() < 1e-12);
        assert!((target.dot(n2) - s2.dot(n2)).abs() < 1e-12);
        // The impulse split recovers the per-normal components.
        let l = h.split(n1 * 2.0 + n2 * 0.5 + Vec3::Y * 9.0);
        assert!(
            (l[0] - 2.0).abs() < 1e-12 && (l[1] - 0.5).abs() < 1e-12,
            "{l:?}"
        );
    }

    #[test]
    fn a_single_surface_and_a_pinch_keep_the_plane_filter() {
        let h = HeldNormals::from_contacts([(Vec3::Z, Vec3::X)]);
        assert_eq!(h.filter(), (Filter::Direction(Vec3::Z), Vec3::X));
        // Facing surfaces (a pinch), 132 degrees apart: the first normal, with the two surface
        // velocities' mean along it (as `center_pinched` sets).
        let a = 132f64.to_radians();
        let n2 = Vec3::new(a.sin(), 0.0, a.cos());
        let h = HeldNormals::from_contacts([(Vec3::Z, Vec3::ZERO), (n2, Vec3::Z * -0.4)]);
        let (f, target) = h.filter();
        assert_eq!(f, Filter::Direction(Vec3::Z));
        assert!((target.z - 0.5 * (0.0 - 0.4)).abs() < 1e-12, "{target}");
        // Nearly coplanar (10 degrees): no independent constraint.
        let (n1, n2) = wedge(10.0);
        assert_eq!(
            HeldNormals::from_contacts([(n1, Vec3::ZERO), (n2, Vec3::ZERO)]).len,
            1
        );
    }

    #[test]
    fn a_corner_of_three_surfaces_fixes_the_vertex_at_their_velocities() {
        let n = [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.6, 0.8)];
        let s = [
            Vec3::ZERO,
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(-0.4, 0.0, 1.0),
        ];
        let h = HeldNormals::from_contacts((0..3).map(|k| (n[k], s[k])));
        let (f, target) = h.filter();
        assert_eq!(f, Filter::Fixed);
        for k in 0..3 {
            assert!((target.dot(n[k]) - s[k].dot(n[k])).abs() < 1e-12, "{k}");
        }
    }
}
