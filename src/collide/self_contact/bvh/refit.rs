//! Refitting the boxes and normal cones to new positions: every node, or only those holding a
//! vertex that moved.

use super::{hull, joined, swept_box, Cone, TopologyBvh, LEAF};
use crate::collide::broad::Aabb;
use crate::Vec3;
use rayon::prelude::*;

impl TopologyBvh {
    /// Recomputes every box and cone for the motion `xa -> xb` (`swept`: they differ), with the
    /// vertex query margins `margin`.
    pub fn refit(
        &mut self,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        xa: &[Vec3],
        xb: &[Vec3],
        margin: impl Fn(usize) -> f64 + Sync,
        swept: bool,
    ) {
        let n = xa.len().min(xb.len());
        self.swept = swept;
        self.xa.clear();
        self.xa.extend_from_slice(&xa[..n]);
        self.xb.clear();
        if swept {
            self.xb.extend_from_slice(&xb[..n]);
        }
        self.vbox.clear();
        self.vbox.extend((0..n).map(|i| swept_box(xa[i], xb[i])));
        self.margin.clear();
        self.margin.extend((0..n).map(&margin));
        let vb = &self.vbox;
        let get = |i: u32| vb.get(i as usize).copied().unwrap_or(Aabb::EMPTY);
        self.tbox.clear();
        self.tbox.extend(
            triangles
                .iter()
                .map(|t| joined(joined(get(t[0]), get(t[1])), get(t[2]))),
        );
        self.ebox.clear();
        self.ebox
            .extend(edges.iter().map(|e| joined(get(e[0]), get(e[1]))));
        let m = self.nodes.len();
        self.nbox.clear();
        self.nbox.resize(m, Aabb::EMPTY);
        self.nmargin.clear();
        self.nmargin.resize(m, 0.0);
        self.cone.clear();
        self.cone.resize(m, Cone::FULL);
        // Leaves in parallel, then internal nodes bottom-up (children follow their parent).
        let leaves: Vec<(usize, Aabb, f64, Cone)> = (0..m)
            .into_par_iter()
            .filter(|&k| self.nodes[k].is_leaf())
            .map(|k| {
                let (b, mg, cone) = self.leaf_fit(k, triangles);
                (k, b, mg, cone)
            })
            .collect();
        for (k, b, mg, c) in leaves {
            self.nbox[k] = b;
            self.nmargin[k] = mg;
            self.cone[k] = c;
        }
        for k in (0..m).rev() {
            if !self.nodes[k].is_leaf() {
                self.join_children(k);
            }
        }
    }

    /// `refit` after only the vertices `changed` flags moved, their end positions now `xb`
    /// (start positions, margins and frame as in the last swept refit, which the caller
    /// vouches for): the boxes and cones of what holds them, the rest as they were. A CCD pass
    /// after an obstacle re-test has moved a few vertices, not the whole cloth, so this costs
    /// what moved.
    pub fn refit_changed(
        &mut self,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        xb: &[Vec3],
        changed: &[bool],
    ) {
        let n = self.xb.len().min(xb.len()).min(changed.len());
        for i in (0..n).filter(|&i| changed[i]) {
            self.xb[i] = xb[i];
            self.vbox[i] = swept_box(self.xa[i], xb[i]);
        }
        let hit = |i: u32| changed.get(i as usize).copied().unwrap_or(true);
        let get = |vb: &[Aabb], i: u32| vb.get(i as usize).copied().unwrap_or(Aabb::EMPTY);
        for (k, t) in triangles.iter().enumerate() {
            if t.iter().any(|&v| hit(v)) {
                let vb = &self.vbox;
                self.tbox[k] = joined(joined(get(vb, t[0]), get(vb, t[1])), get(vb, t[2]));
            }
        }
        for (k, e) in edges.iter().enumerate() {
            if e.iter().any(|&v| hit(v)) {
                self.ebox[k] = joined(get(&self.vbox, e[0]), get(&self.vbox, e[1]));
            }
        }
        self.mark_changed(triangles, edges, Some(changed));
        for k in (0..self.nodes.len()).rev() {
            if !self.changed[k] {
                continue;
            }
            if self.nodes[k].is_leaf() {
                (self.nbox[k], self.nmargin[k], self.cone[k]) = self.leaf_fit(k, triangles);
            } else {
                self.join_children(k);
            }
        }
    }

    /// Leaf `k`'s box, largest margin and cone over the current element boxes and motion.
    fn leaf_fit(&self, k: usize, triangles: &[[u32; 3]]) -> (Aabb, f64, Cone) {
        let nd = &self.nodes[k];
        let tris = &self.order[nd.first as usize..(nd.first + nd.count) as usize];
        let mut b = Aabb::EMPTY;
        let mut mg = 0.0f64;
        for &t in tris {
            b = hull(b, self.tbox[t as usize]);
            for &v in &triangles[t as usize] {
                mg = mg.max(self.margin.get(v as usize).copied().unwrap_or(0.0));
            }
        }
        let xb = if self.swept { &self.xb } else { &self.xa };
        (b, mg, leaf_cone(tris, triangles, &self.xa, xb, self.swept))
    }

    /// Internal node `k`'s box, margin and cone from its children's.
    fn join_children(&mut self, k: usize) {
        let (l, r) = (k + 1, self.nodes[k].right as usize);
        self.nbox[k] = hull(self.nbox[l], self.nbox[r]);
        self.nmargin[k] = self.nmargin[l].max(self.nmargin[r]);
        self.cone[k] = self.cone[l].merge(self.cone[r]);
    }

    /// Whether the last refit was swept from exactly `xa` (the start positions a re-test
    /// keeps).
    pub fn swept_from(&self, xa: &[Vec3]) -> bool {
        self.swept && self.xa == xa
    }
}

/// The cone of a leaf's normals over the motion (start, end and cross-term control vectors).
fn leaf_cone(tris: &[u32], triangles: &[[u32; 3]], xa: &[Vec3], xb: &[Vec3], swept: bool) -> Cone {
    let mut dirs = [Vec3::ZERO; 3 * LEAF];
    let mut k = 0;
    let mut sum = Vec3::ZERO;
    for &t in tris {
        let [a, b, c] = triangles[t as usize].map(|i| i as usize);
        let (Some(&a0), Some(&b0), Some(&c0), Some(&a1), Some(&b1), Some(&c1)) = (
            xa.get(a),
            xa.get(b),
            xa.get(c),
            xb.get(a),
            xb.get(b),
            xb.get(c),
        ) else {
            return Cone::FULL;
        };
        let (e0, f0) = (b0 - a0, c0 - a0);
        let n0 = e0.cross(f0);
        let controls = if swept {
            let (e1, f1) = (b1 - a1, c1 - a1);
            [n0, 0.5 * (e0.cross(f1) + e1.cross(f0)), e1.cross(f1)]
        } else {
            [n0, n0, n0]
        };
        for n in controls.iter().take(if swept { 3 } else { 1 }) {
            let u = n.normalize_or_zero();
            if u == Vec3::ZERO || !u.is_finite() || k == dirs.len() {
                return Cone::FULL;
            }
            dirs[k] = u;
            k += 1;
            sum += u;
        }
    }
    let axis = sum.normalize_or_zero();
    if axis == Vec3::ZERO || !axis.is_finite() {
        return Cone::FULL;
    }
    let min_dot = dirs[..k].iter().map(|d| d.dot(axis)).fold(1.0, f64::min);
    if min_dot <= 0.0 {
        return Cone::FULL;
    }
    Cone::new(axis, min_dot.clamp(-1.0, 1.0).acos())
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{grid, rnd};
    use super::*;

    /// A refit of what changed equals a refit from scratch: boxes, margins and cones, bit for
    /// bit, after a few vertices of a swept crumpled sheet moved again.
    #[test]
    fn refit_of_what_changed_equals_a_full_refit() {
        let (tris, edges, x) = grid(12);
        let mut seed = 7u64;
        let xa: Vec<Vec3> = x
            .iter()
            .map(|p| *p + Vec3::new(0.0, 0.0, 0.05 * rnd(&mut seed)))
            .collect();
        let xb: Vec<Vec3> = xa
            .iter()
            .map(|p| *p + Vec3::new(0.01 * rnd(&mut seed), 0.0, -0.02 * rnd(&mut seed)))
            .collect();
        let mut changed = vec![false; x.len()];
        let mut xc = xb.clone();
        for i in [3usize, 40, 41, 77, 143] {
            changed[i] = true;
            xc[i] += Vec3::new(0.0, 0.004, 0.003);
        }
        let margin = |i: usize| 1e-3 * (1.0 + (i % 3) as f64);
        let mut partial = TopologyBvh::build(&tris, &edges, &x);
        partial.refit(&tris, &edges, &xa, &xb, margin, true);
        partial.refit_changed(&tris, &edges, &xc, &changed);
        let mut full = TopologyBvh::build(&tris, &edges, &x);
        full.refit(&tris, &edges, &xa, &xc, margin, true);
        assert_eq!(partial.xb, full.xb);
        assert_eq!(partial.vbox, full.vbox);
        assert_eq!(partial.tbox, full.tbox);
        assert_eq!(partial.ebox, full.ebox);
        assert_eq!(partial.nbox, full.nbox);
        assert_eq!(partial.nmargin, full.nmargin);
        let cones = |b: &TopologyBvh| {
            b.cone
                .iter()
                .map(|c| (c.axis, c.half.to_bits(), c.cos.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(cones(&partial), cones(&full));
    }
}
