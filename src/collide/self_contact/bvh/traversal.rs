//! The pair queries: a simultaneous descent of the tree from the root, skipping what boxes,
//! cones and contours prove apart, then the element tests of the leaf pairs left, in parallel
//! chunks kept in order.

use super::{near, TopologyBvh, CCD_CONE_COS, PROXIMITY_CONE_COS};
use rayon::prelude::*;

impl TopologyBvh {
    /// Candidate vertex-triangle pairs into `vt` and (with `with_edges`) edge-edge pairs
    /// `(lower, higher)` into `ee`, in the traversal's (deterministic) order, over the last
    /// refit: boxes (vertex boxes inflated by their margin) overlap, no cone culls them, and
    /// `accept_vt` / `accept_ee` keep them. `proximity` selects the proximity cone.
    #[allow(clippy::too_many_arguments)]
    pub fn pairs(
        &mut self,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        with_edges: bool,
        proximity: bool,
        changed: Option<&[bool]>,
        accept_vt: impl Fn(u32, u32) -> bool + Sync,
        accept_ee: impl Fn(u32, u32) -> bool + Sync,
        vt: &mut Vec<(u32, u32)>,
        ee: &mut Vec<(u32, u32)>,
    ) {
        let cos = if proximity {
            PROXIMITY_CONE_COS
        } else {
            CCD_CONE_COS
        };
        self.mark_changed(triangles, edges, changed);
        self.pairs_within(
            triangles, edges, with_edges, cos, accept_vt, accept_ee, vt, ee,
        );
    }

    /// Per node: whether an element under it has a vertex in `changed` (None: every node).
    /// The traversal skips node pairs where neither has: their element pairs are the caller's
    /// to skip too (`changed.rs`), and this keeps the traversal at the cost of what changed.
    pub(super) fn mark_changed(
        &mut self,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        changed: Option<&[bool]>,
    ) {
        self.changed.clear();
        let Some(flags) = changed else {
            return;
        };
        let hit = |i: u32| flags.get(i as usize).copied().unwrap_or(true);
        let m = self.nodes.len();
        self.changed.resize(m, false);
        for k in (0..m).rev() {
            let nd = &self.nodes[k];
            self.changed[k] = if nd.is_leaf() {
                let tris = &self.order[nd.first as usize..(nd.first + nd.count) as usize];
                let own_v = &self.owned_v[nd.verts.0 as usize..nd.verts.1 as usize];
                let own_e = &self.owned_e[nd.edges.0 as usize..nd.edges.1 as usize];
                tris.iter()
                    .any(|&t| triangles[t as usize].iter().any(|&v| hit(v)))
                    || own_v.iter().any(|&v| hit(v))
                    || own_e
                        .iter()
                        .any(|&e| edges[e as usize].iter().any(|&v| hit(v)))
            } else {
                self.changed[k + 1] || self.changed[nd.right as usize]
            };
        }
    }

    /// Whether node `k` may hold a changed element (every node when none were given).
    fn may_change(&self, k: usize) -> bool {
        self.changed.get(k).copied().unwrap_or(true)
    }

    /// `pairs` with cones culling below the half-angle whose cosine is `cos` (1: none cull).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn pairs_within(
        &mut self,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        with_edges: bool,
        cos: f64,
        accept_vt: impl Fn(u32, u32) -> bool + Sync,
        accept_ee: impl Fn(u32, u32) -> bool + Sync,
        vt: &mut Vec<(u32, u32)>,
        ee: &mut Vec<(u32, u32)>,
    ) {
        vt.clear();
        ee.clear();
        self.leaf_pairs.clear();
        self.node_tests = 0;
        if self.nodes.is_empty() {
            return;
        }
        let mut leaf_pairs = std::mem::take(&mut self.leaf_pairs);
        let mut tests = 0usize;
        self.self_test(0, cos, &mut leaf_pairs, &mut tests, PARALLEL_LEVELS);
        self.node_tests = tests;
        self.leaf_pairs = leaf_pairs;
        // Element tests per leaf pair, in parallel chunks kept in order.
        const CHUNK: usize = 64;
        let n_chunks = self.leaf_pairs.len().div_ceil(CHUNK);
        let mut chunks = std::mem::take(&mut self.chunks);
        if chunks.len() < n_chunks {
            chunks.resize_with(n_chunks, Default::default);
        }
        {
            let this = &*self;
            chunks[..n_chunks]
                .par_iter_mut()
                .enumerate()
                .for_each(|(c, (cvt, cee))| {
                    cvt.clear();
                    cee.clear();
                    let end = ((c + 1) * CHUNK).min(this.leaf_pairs.len());
                    for &(a, b) in &this.leaf_pairs[c * CHUNK..end] {
                        this.leaf_elements(
                            a, b, triangles, edges, with_edges, &accept_vt, &accept_ee, cvt, cee,
                        );
                    }
                });
        }
        for (cvt, cee) in &chunks[..n_chunks] {
            vt.extend_from_slice(cvt);
            ee.extend_from_slice(cee);
        }
        self.chunks = chunks;
    }

    /// Pairs inside node `k`: the node pairs under `k` left to the element tests, into `out`
    /// (in an order fixed by the tree); the top `depth` levels in parallel.
    fn self_test(
        &self,
        k: usize,
        cos: f64,
        out: &mut Vec<(u32, u32)>,
        tests: &mut usize,
        depth: u32,
    ) {
        let nd = &self.nodes[k];
        if !self.may_change(k) {
            return;
        }
        *tests += 1;
        if self.cone[k].culls(cos) && self.star(self.nodes[k].contour, self.cone[k].axis) {
            return;
        }
        if nd.is_leaf() {
            out.push((k as u32, k as u32));
            return;
        }
        let (l, r) = (k + 1, nd.right as usize);
        let d = depth.saturating_sub(1);
        both(
            depth,
            out,
            tests,
            |o, t| self.self_test(l, cos, o, t, d),
            |o, t| {
                both(
                    depth,
                    o,
                    t,
                    |o, t| self.self_test(r, cos, o, t, d),
                    |o, t| self.pair_test(l, r, cos, o, t, d),
                )
            },
        );
    }

    /// Pairs between nodes `a` and `b` (disjoint).
    fn pair_test(
        &self,
        a: usize,
        b: usize,
        cos: f64,
        out: &mut Vec<(u32, u32)>,
        tests: &mut usize,
        depth: u32,
    ) {
        if !self.may_change(a) && !self.may_change(b) {
            return;
        }
        *tests += 1;
        let m = self.nmargin[a].max(self.nmargin[b]);
        let (ba, bb) = (&self.nbox[a], &self.nbox[b]);
        if !near(ba, bb, m) {
            return;
        }
        let (na, nb) = (&self.nodes[a], &self.nodes[b]);
        match (na.is_leaf(), nb.is_leaf()) {
            (true, true) => {
                let key = (a.min(b) as u32, a.max(b) as u32);
                if !self.union_culls(key, cos) {
                    out.push(key);
                }
            }
            // Descend the larger (or the only internal) node.
            (false, true) => self.split_pair(a, b, cos, out, tests, depth),
            (true, false) => self.split_pair(b, a, cos, out, tests, depth),
            (false, false) => {
                if na.count >= nb.count {
                    self.split_pair(a, b, cos, out, tests, depth)
                } else {
                    self.split_pair(b, a, cos, out, tests, depth)
                }
            }
        }
    }

    /// Whether leaves `key` form a disk (`leaf_unions`) whose merged cone culls and whose
    /// contour is star-shaped: then no pair between them can touch.
    fn union_culls(&self, key: (u32, u32), cos: f64) -> bool {
        let Ok(u) = self.unions.binary_search_by_key(&key, |u| u.0) else {
            return false;
        };
        let cone = self.cone[key.0 as usize].merge(self.cone[key.1 as usize]);
        cone.culls(cos) && self.star(self.unions[u].1, cone.axis)
    }

    fn split_pair(
        &self,
        inner: usize,
        other: usize,
        cos: f64,
        out: &mut Vec<(u32, u32)>,
        tests: &mut usize,
        depth: u32,
    ) {
        let r = self.nodes[inner].right as usize;
        let d = depth.saturating_sub(1);
        both(
            depth,
            out,
            tests,
            |o, t| self.pair_test(inner + 1, other, cos, o, t, d),
            |o, t| self.pair_test(r, other, cos, o, t, d),
        );
    }
}

/// Levels of the traversal run in parallel (about `2^PARALLEL_LEVELS` tasks): a serial walk of
/// the tree would be a large share of a big cloth's broad phase.
const PARALLEL_LEVELS: u32 = 4;

/// `a` then `b` into `out` (and their node tests into `tests`), in that order: in parallel
/// while `depth` levels are left.
fn both<A, B>(depth: u32, out: &mut Vec<(u32, u32)>, tests: &mut usize, a: A, b: B)
where
    A: FnOnce(&mut Vec<(u32, u32)>, &mut usize) + Send,
    B: FnOnce(&mut Vec<(u32, u32)>, &mut usize) + Send,
{
    if depth == 0 {
        a(out, tests);
        b(out, tests);
        return;
    }
    let (mut ob, mut tb) = (Vec::new(), 0);
    rayon::join(|| a(out, tests), || b(&mut ob, &mut tb));
    out.append(&mut ob);
    *tests += tb;
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{brute, found, grid, rnd};
    use super::super::*;

    /// Without cones the hierarchy finds exactly the pairs brute force does, each once, on a
    /// crumpled and moving sheet.
    #[test]
    fn without_cones_it_finds_what_brute_force_finds() {
        let (tris, edges, rest) = grid(12);
        let mut seed = 7u64;
        let mut shake = |x: &[Vec3], a: f64| -> Vec<Vec3> {
            x.iter()
                .map(|p| {
                    *p + Vec3::new(
                        rnd(&mut seed) - 0.5,
                        rnd(&mut seed) - 0.5,
                        rnd(&mut seed) - 0.5,
                    ) * a
                })
                .collect()
        };
        let xa = shake(&rest, 0.3);
        let xb = shake(&xa, 0.05);
        let mut bvh = TopologyBvh::build(&tris, &edges, &rest);
        bvh.refit(
            &tris,
            &edges,
            &xa,
            &xb,
            |i| 0.002 + 0.001 * (i % 3) as f64,
            true,
        );
        let (vt, ee) = found(&mut bvh, &tris, &edges, 1.0);
        let (bvt, bee) = brute(&bvh, &tris, &edges, rest.len());
        assert!(
            bvt.len() > 100 && bee.len() > 100,
            "{} {}",
            bvt.len(),
            bee.len()
        );
        let missing: Vec<_> = bvt
            .iter()
            .filter(|p| vt.binary_search(p).is_err())
            .collect();
        let extra: Vec<_> = vt
            .iter()
            .filter(|p| bvt.binary_search(p).is_err())
            .collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "vt missing {missing:?} extra {extra:?}"
        );
        let missing: Vec<_> = bee
            .iter()
            .filter(|p| ee.binary_search(p).is_err())
            .collect();
        let extra: Vec<_> = ee
            .iter()
            .filter(|p| bee.binary_search(p).is_err())
            .collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "ee missing {missing:?} extra {extra:?}"
        );
    }

    /// On a flat sheet the cones cull every pair; folded over onto itself, every pair between
    /// the two layers that brute force finds is still found (the fold's cone is wide).
    #[test]
    fn cones_cull_a_flat_sheet_and_keep_the_layers_of_a_folded_one() {
        let (tris, edges, rest) = grid(16);
        let mut bvh = TopologyBvh::build(&tris, &edges, &rest);
        // A margin of a whole spacing: brute force finds the flat sheet's 2-ring neighbours.
        let m = 1.0 / 15.0;
        bvh.refit(&tris, &edges, &rest, &rest, |_| m, false);
        let (vt, ee) = found(&mut bvh, &tris, &edges, PROXIMITY_CONE_COS);
        assert!(!brute(&bvh, &tris, &edges, rest.len()).0.is_empty());
        assert!(vt.is_empty() && ee.is_empty(), "{} {}", vt.len(), ee.len());
        // Fold at x = 0.5 over a half-circle of radius r, the far half lying on the near. The
        // CCD cone only promises the pairs that may cross: its fold is wide enough (2 r = 0.2,
        // three spacings) that no union of two adjacent leaves holds both layers; the proximity
        // cone keeps the layers of a fold tighter than the spacing too.
        for (cos, r, margin) in [(PROXIMITY_CONE_COS, 0.02, 0.05), (CCD_CONE_COS, 0.1, 0.25)] {
            let folded: Vec<Vec3> = rest
                .iter()
                .map(|p| {
                    let s = p.x - 0.5;
                    if s <= 0.0 {
                        *p
                    } else if s < PI * r {
                        let a = s / r;
                        Vec3::new(0.5 + r * a.sin(), p.y, r - r * a.cos())
                    } else {
                        Vec3::new(0.5 - (s - PI * r), p.y, 2.0 * r)
                    }
                })
                .collect();
            let layer = |v: u32| rest[v as usize].x > 0.5 + PI * r;
            let below = |v: u32| rest[v as usize].x < 0.5;
            bvh.refit(&tris, &edges, &folded, &folded, |_| margin, false);
            let (vt, _) = found(&mut bvh, &tris, &edges, cos);
            let (bvt, _) = brute(&bvh, &tris, &edges, rest.len());
            let across: Vec<_> = bvt
                .iter()
                .filter(|(v, t)| {
                    let tri = tris[*t as usize];
                    (layer(*v) && tri.iter().all(|&k| below(k)))
                        || (below(*v) && tri.iter().all(|&k| layer(k)))
                })
                .collect();
            assert!(across.len() > 50, "{}", across.len());
            for p in across {
                assert!(vt.binary_search(p).is_ok(), "layer pair {p:?} culled");
            }
        }
    }

    /// Turning rigidly by 120 degrees over a step the sheet stays flat at every instant and is
    /// culled; a folded sheet whose upper layer passes through the lower one during the step is
    /// not, and every pair between the layers is found.
    #[test]
    fn a_layer_passing_through_another_is_not_culled() {
        let (tris, edges, rest) = grid(8);
        let lim = CCD_CONE_COS;
        let turned: Vec<Vec3> = rest
            .iter()
            .map(|p| Vec3::new(p.x, 0.5 - (p.y - 0.5) * 0.5, (p.y - 0.5) * -0.866))
            .collect();
        let mut bvh = TopologyBvh::build(&tris, &edges, &rest);
        bvh.refit(&tris, &edges, &rest, &turned, |_| 0.01, true);
        assert!(bvh.cone[0].culls(lim));
        // The far half folded over the near half, passing from 1 cm above it to 1 cm below.
        let folded = |z: f64| -> Vec<Vec3> {
            rest.iter()
                .map(|p| {
                    if p.x <= 0.5 {
                        *p
                    } else {
                        Vec3::new(1.0 - p.x, p.y, z)
                    }
                })
                .collect()
        };
        bvh.refit(
            &tris,
            &edges,
            &folded(0.01),
            &folded(-0.01),
            |_| 0.001,
            true,
        );
        assert!(!bvh.cone[0].culls(lim));
        let (vt, _) = found(&mut bvh, &tris, &edges, CCD_CONE_COS);
        let (bvt, _) = brute(&bvh, &tris, &edges, rest.len());
        let far = |v: u32| rest[v as usize].x > 0.6;
        let crossing: Vec<_> = bvt
            .iter()
            .filter(|(v, t)| far(*v) && tris[*t as usize].iter().all(|&k| rest[k as usize].x < 0.4))
            .collect();
        assert!(crossing.len() > 20, "{}", crossing.len());
        for p in crossing {
            assert!(vt.binary_search(p).is_ok(), "pair {p:?} culled");
        }
    }
}
