//! Self-contact broad phase: candidate vertex-triangle and edge-edge (or vertex-vertex) pairs
//! over swept boxes, swept in the frame that moves with the cloth's mean motion.
//!
//! Whether two elements come within a distance during a step depends only on their relative
//! motion, and a common translation `t u` of every vertex (`u` the mean motion over the step)
//! changes no pair's separation at any time. So the boxes are swept from `x0` to `x1 - u`
//! instead of to `x1`: the same pairs can collide, but where the cloth moves as a whole
//! (falling, carried by a gripper) neighbours' boxes no longer overlap along the whole motion.

use super::collider::{shares_vertex, SelfCollider};
use super::exempt::across_seam;
use super::rest::RestShape;
use crate::collide::broad::{cell_size, collect_pairs, Aabb};
use crate::Vec3;

impl SelfCollider {
    /// Candidate pairs over boxes of (x0 .. x1) inflated by per-element `margin`:
    /// vertex-triangle into `pairs`, edge-edge into `pairs_ee` (or vertex-vertex into `pairs`).
    /// Pairs across a seam being sewn are never candidates; with `proximity`, neither are pairs
    /// closer than their contact distance in the rest shape (see `exempt`). Without `with_edges`
    /// no edge-edge pairs are collected.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn broad_phase(
        &mut self,
        xa: &[Vec3],
        xb: &[Vec3],
        margin: impl Fn(usize) -> f64,
        vertex_vertex: bool,
        proximity: bool,
        with_edges: bool,
    ) {
        let none = RestShape::default();
        let rest = match (&self.rest, proximity) {
            (Some(r), true) => r,
            _ => &none,
        };
        // Only the query boxes are inflated by the contact distance (`margin`); item boxes are
        // the bare swept boxes, so no pair is found at more than the contact distance.
        let n = xa.len().min(xb.len());
        // At rest positions (xa == xb, the proximity passes) the mean motion is zero and this
        // is a copy.
        in_mean_frame(&mut self.x_mean_frame, &xa[..n], &xb[..n]);
        let xb = &self.x_mean_frame[..];
        self.qboxes.clear();
        self.qboxes
            .extend((0..n).map(|i| Aabb::from_points(&[xa[i], xb[i]], margin(i))));
        if vertex_vertex {
            self.iboxes.clear();
            self.iboxes
                .extend((0..n).map(|i| Aabb::from_points(&[xa[i], xb[i]], 0.0)));
            let cell = cell_size(&self.qboxes, 0.0);
            self.hash.build(cell, &self.iboxes);
            let mut pairs = std::mem::take(&mut self.pairs);
            let mut stamp = std::mem::take(&mut self.stamp);
            let (q, it) = (
                std::mem::take(&mut self.qboxes),
                std::mem::take(&mut self.iboxes),
            );
            collect_pairs(
                &self.hash,
                &q,
                &it,
                &mut stamp,
                |a, b| {
                    a < b
                        && !self.adjacent(a, b)
                        && !across_seam(&self.seam_bits, &[a], &[b])
                        && !rest.vv.contains(a, b)
                },
                &mut pairs,
            );
            (self.qboxes, self.iboxes) = (q, it);
            self.pairs = pairs;
            self.stamp = stamp;
            self.pairs_ee.clear();
            self.report.candidates += self.pairs.len();
            return;
        }
        let tris = &self.triangles;
        let bits = &self.seam_bits;
        self.iboxes.clear();
        self.iboxes.extend(tris.iter().map(|t| {
            let [a, b, c] = t.map(|i| i as usize);
            Aabb::from_points(&[xa[a], xa[b], xa[c], xb[a], xb[b], xb[c]], 0.0)
        }));
        let cell = cell_size(&self.iboxes, 0.0).max(cell_size(&self.qboxes, 0.0));
        self.hash.build(cell, &self.iboxes);
        collect_pairs(
            &self.hash,
            &self.qboxes,
            &self.iboxes,
            &mut self.stamp,
            |v, t| {
                let tri = &tris[t as usize];
                !tri.contains(&v) && !across_seam(bits, &[v], tri) && !rest.vt.contains(v, t)
            },
            &mut self.pairs,
        );
        self.report.candidates += self.pairs.len();
        if !with_edges {
            self.pairs_ee.clear();
            return;
        }
        let edges = &self.edges;
        self.iboxes.clear();
        self.iboxes.extend(edges.iter().map(|e| {
            let (a, b) = (e[0] as usize, e[1] as usize);
            Aabb::from_points(&[xa[a], xa[b], xb[a], xb[b]], 0.0)
        }));
        self.qboxes.clear();
        self.qboxes
            .extend(self.iboxes.iter().zip(edges).map(|(bx, e)| {
                let m = margin(e[0] as usize).max(margin(e[1] as usize));
                Aabb {
                    lo: bx.lo - Vec3::splat(m),
                    hi: bx.hi + Vec3::splat(m),
                }
            }));
        let cell = cell_size(&self.iboxes, 0.0).max(cell_size(&self.qboxes, 0.0));
        self.hash.build(cell, &self.iboxes);
        collect_pairs(
            &self.hash,
            &self.qboxes,
            &self.iboxes,
            &mut self.stamp,
            |a, b| {
                let (ea, eb) = (&edges[a as usize], &edges[b as usize]);
                a < b
                    && !shares_vertex(ea, eb)
                    && !across_seam(bits, ea, eb)
                    && !rest.ee.contains(a, b)
            },
            &mut self.pairs_ee,
        );
        self.report.candidates += self.pairs_ee.len();
    }
}

/// `out[i] = xb[i] - u`, `u` the mean of `xb - xa` (unchanged where that is not finite).
fn in_mean_frame(out: &mut Vec<Vec3>, xa: &[Vec3], xb: &[Vec3]) {
    let n = xa.len().max(1) as f64;
    let u = xa.iter().zip(xb).map(|(a, b)| *b - *a).sum::<Vec3>() / n;
    let u = if u.is_finite() { u } else { Vec3::ZERO };
    out.clear();
    out.extend(xb.iter().map(|b| *b - u));
}
