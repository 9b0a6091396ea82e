//! Self-contact broad phase: candidate vertex-triangle and edge-edge (or vertex-vertex) pairs
//! over swept boxes, swept in the frame that moves with the cloth's mean motion.
//!
//! Whether two elements come within a distance during a step depends only on their relative
//! motion, and a common translation `t u` of every vertex (`u` the mean motion over the step)
//! changes no pair's separation at any time. So the boxes are swept from `x0` to `x1 - u`
//! instead of to `x1`: the same pairs can collide, but where the cloth moves as a whole
//! (falling, carried by a gripper) neighbours' boxes no longer overlap along the whole motion.

use super::bvh::TopologyBvh;
use super::changed::any_of;
use super::collider::{ee_vertices, vt_vertices, SelfCollider};
use super::exempt::across_seam;
use super::rest::RestShape;
use crate::collide::broad::{cell_size, collect_pairs, Aabb};
use crate::Vec3;
use rayon::prelude::*;

impl SelfCollider {
    /// Candidate pairs over boxes of (x0 .. x1) inflated by per-element `margin`:
    /// vertex-triangle into `pairs`, edge-edge into `pairs_ee` (or vertex-vertex into `pairs`).
    /// Pairs across a seam being sewn are never candidates; with `proximity`, neither are pairs
    /// closer than their contact distance in the rest shape (see `exempt`). Without `with_edges`
    /// no edge-edge pairs are collected. With `changed`, only pairs with a vertex it flags
    /// (the hierarchy's phases; see `changed`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn broad_phase(
        &mut self,
        xa: &[Vec3],
        xb: &[Vec3],
        margin: impl Fn(usize) -> f64 + Sync,
        vertex_vertex: bool,
        proximity: bool,
        with_edges: bool,
        changed: Option<&[bool]>,
    ) {
        let none = RestShape::default();
        let rest = match (&self.rest, proximity) {
            (Some(r), true) => r,
            _ => &none,
        };
        // Only the query boxes are inflated by the contact distance (`margin`); item boxes are
        // the bare swept boxes, so no pair is found at more than the contact distance.
        let n = xa.len().min(xb.len());
        // Proximity passes test the end positions alone (no motion to bound the normals over).
        let swept = !std::ptr::eq(xa.as_ptr(), xb.as_ptr());
        // A re-test of a swept pass from the same start, after only the `changed` vertices
        // moved: the last refit's frame (any common translation serves, see above) and boxes,
        // updated where they changed.
        let retest = match (self.swept_frame, &self.bvh, changed) {
            (Some(u), Some(bvh), Some(_)) if swept && bvh.swept_from(&xa[..n]) => Some(u),
            _ => None,
        };
        // At rest positions (xa == xb, the proximity passes) the mean motion is zero and this
        // is a copy.
        let u = retest.unwrap_or_else(|| mean_motion(&xa[..n], &xb[..n]));
        self.x_mean_frame.clear();
        self.x_mean_frame.extend(xb[..n].iter().map(|b| *b - u));
        self.swept_frame = swept.then_some(u);
        let xb = &self.x_mean_frame[..];
        if vertex_vertex {
            self.qboxes.clear();
            self.qboxes
                .extend((0..n).map(|i| Aabb::from_points(&[xa[i], xb[i]], margin(i))));
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
        if self.bvh.is_none() {
            let x = self.rest.as_ref().map_or(xa, |r| &r.x[..]);
            self.bvh = Some(TopologyBvh::build(&self.triangles, &self.edges, x));
        }
        let Some(bvh) = self.bvh.as_mut() else {
            return;
        };
        // New boxes: the near pairs kept on the old ones are stale.
        self.near_kept_valid = false;
        let (tris, edges, bits) = (&self.triangles, &self.edges, &self.seam_bits);
        match (retest, changed) {
            (Some(_), Some(flags)) => bvh.refit_changed(tris, edges, xb, flags),
            _ => bvh.refit(tris, edges, xa, xb, margin, swept),
        }
        bvh.pairs(
            tris,
            edges,
            with_edges,
            proximity,
            changed,
            // Near pairs are tested below, whatever the cones say: not here too (`rest` is
            // empty outside proximity passes).
            |v, t| {
                changed.is_none_or(|f| any_of(f, &vt_vertices(tris, v, t)))
                    && !across_seam(bits, &[v], &tris[t as usize])
                    && !rest.vt.contains(v, t)
                    && !rest.near_vt.contains(v, t)
            },
            |a, b| {
                let (ea, eb) = (&edges[a as usize], &edges[b as usize]);
                changed.is_none_or(|f| any_of(f, &ee_vertices(edges, a, b)))
                    && !across_seam(bits, ea, eb)
                    && !rest.ee.contains(a, b)
                    && !rest.near_ee.contains(a, b)
            },
            &mut self.pairs,
            &mut self.pairs_ee,
        );
        if proximity {
            // The pairs proximity answers in the cloth's plane, which a cone may have culled.
            // Vertex-triangle ones are read from the rest lists by the repulsion passes
            // (`proximity::near_answers`).
            let pairs_ee = &mut self.pairs_ee;
            if with_edges {
                for e in 0..edges.len().min(rest.near_ee.rows()) {
                    for &f in rest.near_ee.row(e) {
                        let (e, f) = (e as u32, f);
                        if e < f
                            && bvh.ee_overlap(edges, e, f)
                            && !across_seam(bits, &edges[e as usize], &edges[f as usize])
                        {
                            pairs_ee.push((e, f));
                        }
                    }
                }
            }
        }
        // Sorted, not in the tree's order: the passes are Jacobi (`jacobi`), so the order only
        // decides in which order floating-point sums are taken, and sorted keeps a run's bytes
        // independent of the tree's shape.
        self.pairs.par_sort_unstable();
        self.pairs_ee.par_sort_unstable();
        self.report.candidates += self.pairs.len() + self.pairs_ee.len();
        self.report.node_tests += bvh.node_tests;
    }
}

/// The mean of `xb - xa` (zero where that is not finite).
fn mean_motion(xa: &[Vec3], xb: &[Vec3]) -> Vec3 {
    let n = xa.len().max(1) as f64;
    let u = xa.iter().zip(xb).map(|(a, b)| *b - *a).sum::<Vec3>() / n;
    if u.is_finite() {
        u
    } else {
        Vec3::ZERO
    }
}
