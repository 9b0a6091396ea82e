//! Self-contact broad phase over a bounding-volume hierarchy built once on the cloth's mesh, with
//! normal cones, so that flat or gently curved parts of the cloth cost no pair tests at all.
//!
//! Why: on a spatial hash nearly every visit is a mesh neighbour (crumple 64x64: 1.07 M visits
//! for 48 k candidates per resolve; robot_towel 159 k for 1.9 k). A surface patch that is a
//! topological disk, whose normals all lie strictly within 90 degrees of one axis and whose
//! contour, projected along that axis, is a simple curve, is a height field over the plane
//! normal to the axis and cannot intersect itself (Volino and Magnenat-Thalmann 1994; Provot
//! 1997). A node needs no test inside it when it passes both halves, and so do two adjacent
//! leaves whose union does (`unions`, precomputed). The contour half is not optional: two
//! sheets crumpled without springs fold in their own plane, every normal up, and the cone
//! alone let a vertex through a triangle two rings away (`collide_self`). The contour test is
//! star-shapedness about the contour's centroid (Schvartzman, Perez and Otaduy 2010): sufficient
//! and linear in the contour; it needs convex-ish nodes, so the tree splits quads (triangle
//! pairs), not triangles, between rows along the grid's own directions (`split`), and a
//! grid's nodes are rectangles.
//!
//! Over a step the cone bounds the normal at every instant: with vertices moving linearly the
//! normal is a quadratic Bezier curve in time whose control vectors are the start normal, the end
//! normal and their cross term, and a cone holding those holds the curve (a positive combination).
//!
//! Proximity (distance below the contact distance `d`) is culled with a narrower cone (45
//! degrees): such a patch is a graph of slope at most 1 over the plane normal to the axis, so two
//! of its points closer than `d` are at most `sqrt(2) d` apart along the cloth. Pairs that near
//! in the rest shape are exempt from proximity (`exempt`) or kept on the rest shape's near lists
//! (`RestShape::near_vt`, `near_ee`, within `FOLD_ARC d > sqrt(2) d`), which the caller tests
//! whatever the cones say; a wider cone would skip the two sides of a crease that is closing.
//!
//! Vertices and edges are each owned by one leaf (the first of their triangles in leaf order),
//! so every vertex-triangle and edge-edge pair is tested once: inside a leaf or between two.

use crate::collide::broad::Aabb;
use crate::Vec3;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Triangles per leaf: small enough that a leaf is flat where the cloth is, large enough that
/// the tree's node tests stay fewer than the element tests they save.
const LEAF: usize = 8;

/// Candidate pairs: (vertex, triangle) or (edge, edge).
type Pairs = Vec<(u32, u32)>;

/// Cosine of the widest cone that culls intersection (CCD): just inside 90 degrees, for the
/// round-off of the cone merges.
const CCD_CONE_COS: f64 = 1e-3;
/// Cosine of the widest cone that culls proximity (45 degrees; see the module doc).
const PROXIMITY_CONE_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// A cone of directions: `axis` (unit), half-angle `half` (rad; `PI` holds every direction)
/// and its cosine.
#[derive(Debug, Clone, Copy)]
struct Cone {
    axis: Vec3,
    half: f64,
    cos: f64,
}

impl Cone {
    const FULL: Cone = Cone {
        axis: Vec3::Z,
        half: PI,
        cos: -1.0,
    };

    fn new(axis: Vec3, half: f64) -> Cone {
        Cone {
            axis,
            half,
            cos: half.cos(),
        }
    }

    /// The smallest cone (up to the merge's over-estimate) holding both; `FULL` once it is
    /// wider than 90 degrees, since no cone that wide culls.
    fn merge(self, o: Cone) -> Cone {
        if self.half >= FRAC_PI_2 || o.half >= FRAC_PI_2 {
            return Cone::FULL;
        }
        let phi = self.axis.dot(o.axis).clamp(-1.0, 1.0).acos();
        if phi + o.half <= self.half {
            return self;
        }
        if phi + self.half <= o.half {
            return o;
        }
        let half = 0.5 * (phi + self.half + o.half);
        if half >= FRAC_PI_2 || phi <= 0.0 {
            return Cone::FULL;
        }
        // Rotate `self.axis` towards `o.axis` by `half - self.half` (spherical interpolation).
        let t = half - self.half;
        let axis = (self.axis * (phi - t).sin() + o.axis * t.sin()) / phi.sin();
        let axis = axis.normalize_or_zero();
        if axis == Vec3::ZERO || !axis.is_finite() {
            return Cone::FULL;
        }
        Cone::new(axis, half)
    }

    /// Whether the cone is narrower than the half-angle whose cosine is `cos`.
    fn culls(&self, cos: f64) -> bool {
        self.cos > cos
    }
}

/// One node: a leaf's triangles are `order[first..first + count]`; an internal node's children
/// are the next node (`index + 1`, pre-order) and `right`.
#[derive(Debug, Clone)]
struct Node {
    first: u32,
    count: u32,
    right: u32,
    /// Its triangles form a topological disk (edge-connected, manifold, one boundary loop,
    /// Euler characteristic 1): only then can its cone cull. The loop (ordered along the
    /// triangles' orientation) is `contour[loop.0..loop.1]`, empty when not a disk.
    contour: (u32, u32),
    /// A leaf's own vertices and edges: ranges into `owned_v`, `owned_e`.
    verts: (u32, u32),
    edges: (u32, u32),
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.right == 0
    }
}

/// The hierarchy (built once) and the boxes and cones of its last refit.
#[derive(Debug, Default)]
pub(super) struct TopologyBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    contour: Vec<u32>,
    /// Leaf pairs `(lower, higher)` forming a disk, sorted, with their union's contour range.
    unions: Vec<((u32, u32), (u32, u32))>,
    owned_v: Vec<u32>,
    owned_e: Vec<u32>,
    /// Per refit: per vertex its swept box and margin, per triangle and edge its swept box, per
    /// node its box (no margin), largest margin and cone.
    /// The last refit's motion (`xb` only when `swept`), for the contour tests.
    xa: Vec<Vec3>,
    xb: Vec<Vec3>,
    swept: bool,
    vbox: Vec<Aabb>,
    margin: Vec<f64>,
    tbox: Vec<Aabb>,
    ebox: Vec<Aabb>,
    nbox: Vec<Aabb>,
    nmargin: Vec<f64>,
    cone: Vec<Cone>,
    /// Leaf pairs the last traversal left to the element tests, and how many node pairs it
    /// tested.
    leaf_pairs: Vec<(u32, u32)>,
    pub node_tests: usize,
    /// Per node, for the current traversal: whether it may hold a changed element (empty:
    /// every node may).
    changed: Vec<bool>,
    chunks: Vec<(Pairs, Pairs)>,
}

impl TopologyBvh {
    /// Builds the hierarchy over `triangles` by median splits of their centroids at `x` (the
    /// rest shape), so nodes are compact pieces of the cloth.
    pub fn build(triangles: &[[u32; 3]], edges: &[[u32; 2]], x: &[Vec3]) -> TopologyBvh {
        let n_v = x.len();
        let ok = |t: &[u32; 3]| t.iter().all(|&i| (i as usize) < n_v);
        let order: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&t| ok(&triangles[t as usize]))
            .collect();
        let centroid = |t: u32| {
            let [a, b, c] = triangles[t as usize].map(|i| x[i as usize]);
            let m = (a + b + c) / 3.0;
            if m.is_finite() {
                m
            } else {
                Vec3::ZERO
            }
        };
        // Split quads (triangle pairs), not triangles: a grid's nodes are then rectangles,
        // whose contours the star test accepts, not staircases of half-quads.
        let units = quads(triangles, &order, x);
        let unit_centroid = |u: u32| match units[u as usize] {
            [a, NONE] => centroid(a),
            [a, b] => 0.5 * (centroid(a) + centroid(b)),
        };
        let frame = grid_frame(triangles, &units, x);
        let mut by_unit: Vec<u32> = (0..units.len() as u32).collect();
        let mut nodes = Vec::new();
        if !by_unit.is_empty() {
            split(&mut by_unit, 0, &unit_centroid, &frame, &mut nodes);
        }
        // Unit ranges to triangle ranges.
        let mut start = Vec::with_capacity(by_unit.len() + 1);
        let mut order = Vec::with_capacity(order.len());
        for &u in &by_unit {
            start.push(order.len() as u32);
            order.extend(units[u as usize].iter().filter(|&&t| t != NONE));
        }
        start.push(order.len() as u32);
        for nd in &mut nodes {
            let (f, c) = (nd.first as usize, nd.count as usize);
            (nd.first, nd.count) = (start[f], start[f + c] - start[f]);
        }
        let mut bvh = TopologyBvh {
            nodes,
            order,
            ..Default::default()
        };
        bvh.topology(triangles, edges, n_v);
        bvh.leaf_unions(triangles, n_v);
        bvh
    }

    /// Per node: its contour when it is a disk; per leaf: its own vertices and edges.
    fn topology(&mut self, triangles: &[[u32; 3]], edges: &[[u32; 2]], n_v: usize) {
        let edge_index = |a: u32, b: u32| edges.binary_search(&[a.min(b), a.max(b)]).ok();
        let (mut v_owned, mut e_owned) = (vec![false; n_v], vec![false; edges.len()]);
        for k in 0..self.nodes.len() {
            let (first, n) = (self.nodes[k].first as usize, self.nodes[k].count as usize);
            let tris = &self.order[first..first + n];
            let start = self.contour.len() as u32;
            disk_contour(tris, triangles, &mut self.contour);
            self.nodes[k].contour = (start, self.contour.len() as u32);
            if self.nodes[k].is_leaf() {
                let vs = self.owned_v.len() as u32;
                let es = self.owned_e.len() as u32;
                for &t in tris {
                    let [a, b, c] = triangles[t as usize];
                    for v in [a, b, c] {
                        if !std::mem::replace(&mut v_owned[v as usize], true) {
                            self.owned_v.push(v);
                        }
                    }
                    for (p, q) in [(a, b), (b, c), (c, a)] {
                        if let Some(e) = edge_index(p, q) {
                            if !std::mem::replace(&mut e_owned[e], true) {
                                self.owned_e.push(e as u32);
                            }
                        }
                    }
                }
                self.nodes[k].verts = (vs, self.owned_v.len() as u32);
                self.nodes[k].edges = (es, self.owned_e.len() as u32);
            }
        }
    }

    /// Every two leaves that share a vertex and form a disk together, with their union's
    /// contour: the pairs between them are culled like a node's (`union_culls`).
    fn leaf_unions(&mut self, triangles: &[[u32; 3]], n_v: usize) {
        let mut at: Vec<(u32, u32)> = Vec::new();
        for (k, nd) in self.nodes.iter().enumerate().filter(|(_, nd)| nd.is_leaf()) {
            for &t in &self.order[nd.first as usize..(nd.first + nd.count) as usize] {
                for &v in &triangles[t as usize] {
                    if (v as usize) < n_v {
                        at.push((v, k as u32));
                    }
                }
            }
        }
        at.sort_unstable();
        at.dedup();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for run in at.chunk_by(|a, b| a.0 == b.0) {
            for (i, a) in run.iter().enumerate() {
                pairs.extend(run[i + 1..].iter().map(|b| (a.1.min(b.1), a.1.max(b.1))));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut tris = Vec::new();
        for (a, b) in pairs {
            let leaf = |k: u32| {
                let nd = &self.nodes[k as usize];
                &self.order[nd.first as usize..(nd.first + nd.count) as usize]
            };
            tris.clear();
            tris.extend_from_slice(leaf(a));
            tris.extend_from_slice(leaf(b));
            let start = self.contour.len() as u32;
            disk_contour(&tris, triangles, &mut self.contour);
            if self.contour.len() as u32 > start {
                self.unions
                    .push(((a, b), (start, self.contour.len() as u32)));
            }
        }
    }

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
    /// after an obstacle re-test moved a few vertices of a 64x64 cloth, not 4096.
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

    /// Candidate vertex-triangle pairs into `vt` and (with `with_edges`) edge-edge pairs
    /// `(lower, higher)` into `ee`, in the traversal's (deterministic) order, over the last refit: boxes (vertex boxes
    /// inflated by their margin) overlap, no cone culls them, and `accept_vt` / `accept_ee`
    /// keep them. `proximity` selects the proximity cone.
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
    fn mark_changed(
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
    fn pairs_within(
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

    /// Whether vertex `v`'s query box (with its margin) overlaps triangle `t`'s box.
    pub fn vt_overlap(&self, v: u32, t: u32) -> bool {
        match (self.vbox.get(v as usize), self.tbox.get(t as usize)) {
            (Some(b), Some(tb)) => near(b, tb, self.margin[v as usize]),
            _ => false,
        }
    }

    /// Whether edges `e` and `f` come nearer than the largest margin of their four ends.
    pub fn ee_overlap(&self, edges: &[[u32; 2]], e: u32, f: u32) -> bool {
        match (self.ebox.get(e as usize), self.ebox.get(f as usize)) {
            (Some(b), Some(fb)) => near(
                b,
                fb,
                self.edge_margin(edges, e).max(self.edge_margin(edges, f)),
            ),
            _ => false,
        }
    }

    fn edge_margin(&self, edges: &[[u32; 2]], e: u32) -> f64 {
        let m = |i: u32| self.margin.get(i as usize).copied().unwrap_or(0.0);
        edges.get(e as usize).map_or(0.0, |[p, q]| m(*p).max(m(*q)))
    }

    /// Pairs inside node `k`.
    /// The node pairs under `k` left to the element tests, into `out` (in an order fixed by the
    /// tree); the top `depth` levels in parallel.
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

    /// Whether the contour `contour[s..e]`, projected along `axis`, is star-shaped about its
    /// centroid at every instant of the last refit's motion (then it is a simple curve, and
    /// with the cone the node cannot touch itself: Schvartzman, Perez and Otaduy 2010). Each
    /// contour edge's orientation about the centroid is quadratic in time; its Bernstein
    /// coefficients all positive bound it above zero over the step.
    fn star(&self, (s, e): (u32, u32), axis: Vec3) -> bool {
        let lp = &self.contour[s as usize..e as usize];
        if lp.len() < 3 {
            return false;
        }
        let u = axis.any_orthonormal_vector();
        let w = axis.cross(u);
        let (xa, xb) = (&self.xa, if self.swept { &self.xb } else { &self.xa });
        let at = |x: &[Vec3], i: u32| x.get(i as usize).copied().unwrap_or(Vec3::NAN);
        let centre = |x: &[Vec3]| lp.iter().map(|&i| at(x, i)).sum::<Vec3>() / lp.len() as f64;
        let (c0, c1) = (centre(xa), centre(xb));
        let flat = |p: Vec3| (p.dot(u), p.dot(w));
        let cross = |a: (f64, f64), b: (f64, f64)| a.0 * b.1 - a.1 * b.0;
        let mut turn = 0.0;
        for (i, &p) in lp.iter().enumerate() {
            let q = lp[(i + 1) % lp.len()];
            let (a0, b0) = (flat(at(xa, p) - c0), flat(at(xa, q) - c0));
            let (a1, b1) = (flat(at(xb, p) - c1), flat(at(xb, q) - c1));
            let (f0, f2) = (cross(a0, b0), cross(a1, b1));
            let f1 = 0.5 * (cross(a0, b1) + cross(a1, b0));
            // Written so that NaN fails.
            if !(f0 > 0.0 && f1 > 0.0 && f2 > 0.0) {
                return false;
            }
            turn += f0.atan2(a0.0 * b0.0 + a0.1 * b0.1);
        }
        // Every edge turns forward about the centre: the loop winds once (2 pi), not twice.
        turn < 3.0 * PI
    }

    /// The element pairs of leaves `a` and `b` (`a == b`: inside one leaf).
    #[allow(clippy::too_many_arguments)]
    fn leaf_elements(
        &self,
        a: u32,
        b: u32,
        triangles: &[[u32; 3]],
        edges: &[[u32; 2]],
        with_edges: bool,
        accept_vt: &(impl Fn(u32, u32) -> bool + Sync),
        accept_ee: &(impl Fn(u32, u32) -> bool + Sync),
        vt: &mut Vec<(u32, u32)>,
        ee: &mut Vec<(u32, u32)>,
    ) {
        let (na, nb) = (&self.nodes[a as usize], &self.nodes[b as usize]);
        let tris = |n: &Node| &self.order[n.first as usize..(n.first + n.count) as usize];
        let verts = |n: &Node| &self.owned_v[n.verts.0 as usize..n.verts.1 as usize];
        let own_e = |n: &Node| &self.owned_e[n.edges.0 as usize..n.edges.1 as usize];
        let mut vt_side = |vn: &Node, tn: &Node, tbox_node: &Aabb| {
            for &v in verts(vn) {
                let (q, m) = (&self.vbox[v as usize], self.margin[v as usize]);
                if !near(q, tbox_node, m) {
                    continue;
                }
                for &t in tris(tn) {
                    if near(q, &self.tbox[t as usize], m)
                        && !triangles[t as usize].contains(&v)
                        && accept_vt(v, t)
                    {
                        vt.push((v, t));
                    }
                }
            }
        };
        vt_side(na, nb, &self.nbox[b as usize]);
        if a != b {
            vt_side(nb, na, &self.nbox[a as usize]);
        }
        if !with_edges {
            return;
        }
        let (ea, eb) = (own_e(na), own_e(nb));
        let box_b = &self.nbox[b as usize];
        for (i, &e) in ea.iter().enumerate() {
            let (q, me) = (&self.ebox[e as usize], self.edge_margin(edges, e));
            // `f`'s margin may be the larger: the node's bounds both.
            if !near(q, box_b, me.max(self.nmargin[b as usize])) {
                continue;
            }
            let others = if a == b { &ea[i + 1..] } else { eb };
            for &f in others {
                let (lo, hi) = (e.min(f), e.max(f));
                let (el, eh) = (&edges[lo as usize], &edges[hi as usize]);
                if near(
                    q,
                    &self.ebox[f as usize],
                    me.max(self.edge_margin(edges, f)),
                ) && !el.iter().any(|v| eh.contains(v))
                    && accept_ee(lo, hi)
                {
                    ee.push((lo, hi));
                }
            }
        }
    }
}

/// The box holding both (the empty box holds nothing).
/// Levels of the traversal run in parallel (about `2^PARALLEL_LEVELS` tasks): the serial walk
/// was a fifth of the 64x64 crumple's broad phase.
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

/// A vertex's box over its motion `a -> b`: empty where that is not finite.
fn swept_box(a: Vec3, b: Vec3) -> Aabb {
    let bx = Aabb::from_points(&[a, b], 0.0);
    if bx.lo.is_finite() && bx.hi.is_finite() {
        bx
    } else {
        Aabb::EMPTY
    }
}

/// The box of an element from its vertices' boxes: empty where one is (a non-finite vertex
/// box), so the element is near nothing.
fn joined(a: Aabb, b: Aabb) -> Aabb {
    if a == Aabb::EMPTY || b == Aabb::EMPTY {
        return Aabb::EMPTY;
    }
    Aabb {
        lo: a.lo.min(b.lo),
        hi: a.hi.max(b.hi),
    }
}

fn hull(a: Aabb, b: Aabb) -> Aabb {
    Aabb {
        lo: a.lo.min(b.lo),
        hi: a.hi.max(b.hi),
    }
}

/// Whether two boxes come nearer than `m` (Euclidean: tighter than growing one by `m` on each
/// axis, and as conservative, since every point of either element lies in its box). Empty
/// boxes (elements with a non-finite vertex) are near nothing.
fn near(a: &Aabb, b: &Aabb, m: f64) -> bool {
    let gap = (b.lo - a.hi).max(a.lo - b.hi).max(Vec3::ZERO);
    gap.length_squared() < m * m
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

/// No triangle (the second of a unit that is a lone triangle).
const NONE: u32 = u32::MAX;

/// Pairs each triangle of `order` with its neighbour across its longest edge at `x` where
/// that edge is the neighbour's longest too (a grid's quads); the rest stay alone.
fn quads(triangles: &[[u32; 3]], order: &[u32], x: &[Vec3]) -> Vec<[u32; 2]> {
    let longest = |t: u32| {
        let [a, b, c] = triangles[t as usize];
        let len = |p: u32, q: u32| (x[p as usize] - x[q as usize]).length();
        let mut best = (a.min(b), a.max(b));
        let mut l = len(a, b);
        for (p, q) in [(b, c), (c, a)] {
            if len(p, q) > l {
                (best, l) = ((p.min(q), p.max(q)), len(p, q));
            }
        }
        best
    };
    let mut keys: Vec<((u32, u32), u32)> = order.iter().map(|&t| (longest(t), t)).collect();
    keys.sort_unstable();
    let mut paired = vec![false; triangles.len()];
    let mut units = Vec::with_capacity(order.len());
    for run in keys.chunk_by(|a, b| a.0 == b.0) {
        if let [(_, a), (_, b)] = *run {
            units.push([a, b]);
            paired[a as usize] = true;
            paired[b as usize] = true;
        }
    }
    units.extend(
        order
            .iter()
            .filter(|&&t| !paired[t as usize])
            .map(|&t| [t, NONE]),
    );
    units
}

/// Split directions: the two sides of the first quad and their normal (a grid's rows and
/// columns, however the cloth is turned), else the world axes.
fn grid_frame(triangles: &[[u32; 3]], units: &[[u32; 2]], x: &[Vec3]) -> [Vec3; 3] {
    let world = [Vec3::X, Vec3::Y, Vec3::Z];
    let Some(&[a, b]) = units.iter().find(|u| u[1] != NONE) else {
        return world;
    };
    // The quad's sides: the edges of its first triangle other than the shared diagonal.
    let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
    let sides: Vec<Vec3> = [(0, 1), (1, 2), (2, 0)]
        .iter()
        .map(|&(i, j)| (ta[i], ta[j]))
        .filter(|(p, q)| !(tb.contains(p) && tb.contains(q)))
        .map(|(p, q)| x[q as usize] - x[p as usize])
        .collect();
    let [s, t] = sides[..] else {
        return world;
    };
    let u = s.normalize_or_zero();
    let w = (t - u * t.dot(u)).normalize_or_zero();
    let n = u.cross(w);
    if u == Vec3::ZERO || w == Vec3::ZERO || !n.is_finite() {
        return world;
    }
    [u, w, n]
}

/// Median split of `order` (units of one or two triangles) along the `frame` direction of the
/// widest extent of its centroids, down to `LEAF / 2` units. The cut goes between two rows of
/// centroids (equal projections go to one side) nearest the median, so a grid's nodes are
/// rectangles. Appends nodes in pre-order and returns the index of the node made.
fn split(
    order: &mut [u32],
    first: usize,
    centroid: &impl Fn(u32) -> Vec3,
    frame: &[Vec3; 3],
    nodes: &mut Vec<Node>,
) -> usize {
    let k = nodes.len();
    nodes.push(Node {
        first: first as u32,
        count: order.len() as u32,
        right: 0,
        contour: (0, 0),
        verts: (0, 0),
        edges: (0, 0),
    });
    if order.len() <= LEAF / 2 {
        return k;
    }
    let extent = |d: Vec3| {
        let (lo, hi) = order
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                let p = centroid(t).dot(d);
                (lo.min(p), hi.max(p))
            });
        hi - lo
    };
    let (axis, ext) =
        frame
            .iter()
            .map(|&d| (d, extent(d)))
            .fold(
                (frame[0], f64::NEG_INFINITY),
                |a, b| if b.1 > a.1 { b } else { a },
            );
    let key = |t: u32| centroid(t).dot(axis);
    order.sort_unstable_by(|&a, &b| {
        key(a)
            .partial_cmp(&key(b))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let tol = 1e-6 * ext.max(f64::MIN_POSITIVE);
    let n = order.len();
    let mid = n / 2;
    // Nearest gap between rows to the median (either side); none: the median itself.
    let gap = |i: usize| key(order[i]) - key(order[i - 1]) > tol;
    let cut = (0..n / 2)
        .flat_map(|d| [mid - d, mid + d])
        .find(|&i| i > 0 && i < n && gap(i))
        .unwrap_or(mid);
    let (left, right) = order.split_at_mut(cut);
    split(left, first, centroid, frame, nodes);
    let r = split(right, first + cut, centroid, frame, nodes);
    nodes[k].right = r as u32;
    k
}

/// Appends the boundary loop of triangles `tris` (ordered along their orientation) to `out`
/// when they form a topological disk: edge-connected, manifold, one boundary loop, Euler
/// characteristic 1. Appends nothing otherwise.
fn disk_contour(tris: &[u32], triangles: &[[u32; 3]], out: &mut Vec<u32>) {
    let n = tris.len();
    if n == 0 {
        return;
    }
    // Undirected edges with the triangle using them, grouped.
    let mut keys: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * n);
    for (i, &t) in tris.iter().enumerate() {
        let [a, b, c] = triangles[t as usize];
        for (p, q) in [(a, b), (b, c), (c, a)] {
            keys.push((p.min(q), p.max(q), i as u32));
        }
    }
    keys.sort_unstable();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let (mut n_edges, mut manifold) = (0i64, true);
    let mut next: Vec<(u32, u32)> = Vec::new();
    for run in keys.chunk_by(|a, b| (a.0, a.1) == (b.0, b.1)) {
        for w in run.windows(2) {
            union(&mut parent, w[0].2, w[1].2);
        }
        n_edges += 1;
        manifold &= run.len() <= 2;
        if let [(lo, hi, tri)] = *run {
            // A boundary edge, directed as its triangle runs.
            let [a, b, c] = triangles[tris[tri as usize] as usize];
            let forward = [(a, b), (b, c), (c, a)].contains(&(lo, hi));
            next.push(if forward { (lo, hi) } else { (hi, lo) });
        }
    }
    let root = find(&mut parent, 0);
    let connected = (0..n as u32).all(|i| find(&mut parent, i) == root);
    let mut verts: Vec<u32> = tris.iter().flat_map(|&t| triangles[t as usize]).collect();
    verts.sort_unstable();
    verts.dedup();
    let euler = verts.len() as i64 - n_edges + n as i64;
    if !(connected && manifold && euler == 1) || next.is_empty() {
        return;
    }
    next.sort_unstable();
    // A vertex with two outgoing boundary edges pinches the loop: not a disk.
    if next.windows(2).any(|w| w[0].0 == w[1].0) {
        return;
    }
    let start = out.len();
    let first = next[0].0;
    let mut v = first;
    loop {
        out.push(v);
        match next.binary_search_by_key(&v, |e| e.0) {
            Ok(e) => v = next[e].1,
            Err(_) => break,
        }
        if v == first || out.len() - start > next.len() {
            break;
        }
    }
    // One loop through every boundary edge, or none.
    if v != first || out.len() - start != next.len() {
        out.truncate(start);
    }
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `n x n` grid of triangles over the unit square (rest shape), its edges sorted.
    fn grid(n: usize) -> (Vec<[u32; 3]>, Vec<[u32; 2]>, Vec<Vec3>) {
        let id = |i: usize, j: usize| (i * n + j) as u32;
        let mut tris = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let mut edges: Vec<[u32; 2]> = tris
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let h = 1.0 / (n - 1) as f64;
        let x = (0..n * n)
            .map(|k| Vec3::new((k / n) as f64 * h, (k % n) as f64 * h, 0.0))
            .collect();
        (tris, edges, x)
    }

    fn rnd(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
    }

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

    /// Every pair whose (Euclidean) box distance is below the margin, by brute force.
    fn brute(
        bvh: &TopologyBvh,
        tris: &[[u32; 3]],
        edges: &[[u32; 2]],
        n_v: usize,
    ) -> (Pairs, Pairs) {
        let mut vt = Vec::new();
        for v in 0..n_v as u32 {
            for t in 0..tris.len() as u32 {
                if !tris[t as usize].contains(&v) && bvh.vt_overlap(v, t) {
                    vt.push((v, t));
                }
            }
        }
        let mut ee = Vec::new();
        for e in 0..edges.len() as u32 {
            for f in e + 1..edges.len() as u32 {
                let (a, b) = (edges[e as usize], edges[f as usize]);
                if !a.iter().any(|v| b.contains(v)) && bvh.ee_overlap(edges, e, f) {
                    ee.push((e, f));
                }
            }
        }
        (vt, ee)
    }

    fn found(
        bvh: &mut TopologyBvh,
        tris: &[[u32; 3]],
        edges: &[[u32; 2]],
        cos: f64,
    ) -> (Pairs, Pairs) {
        let (mut vt, mut ee) = (Vec::new(), Vec::new());
        bvh.pairs_within(
            tris,
            edges,
            true,
            cos,
            |_, _| true,
            |_, _| true,
            &mut vt,
            &mut ee,
        );
        vt.sort_unstable();
        ee.sort_unstable();
        (vt, ee)
    }

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

    /// A ribbon wound one and a half turns in (nearly) one plane: every normal is within a few
    /// degrees of +z, so only its contour shows that it overlaps itself. Every pair between
    /// the overlapping turns that brute force finds is found (an in-plane fold: the failure
    /// of the cone test alone, seen in two sheets crumpled without springs).
    #[test]
    fn a_ribbon_wound_over_itself_in_plane_is_not_culled() {
        let (segs, turns) = (96usize, 1.5);
        let mut x = Vec::new();
        for i in 0..=segs {
            let a = 2.0 * PI * turns * i as f64 / segs as f64;
            let z = 0.002 * a / (2.0 * PI);
            for r in [0.1, 0.2] {
                x.push(Vec3::new(r * a.cos(), r * a.sin(), z));
            }
        }
        let mut tris = Vec::new();
        for i in 0..segs as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            // Counter-clockwise seen from +z: outer (odd) vertices lead.
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
        let mut edges: Vec<[u32; 2]> = tris
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        for t in &tris {
            let [a, b, c] = t.map(|i| x[i as usize]);
            assert!((b - a).cross(c - a).normalize().z > 0.99);
        }
        let mut bvh = TopologyBvh::build(&tris, &edges, &x);
        bvh.refit(&tris, &edges, &x, &x, |_| 0.004, false);
        assert!(bvh.cone[0].culls(CCD_CONE_COS));
        let (vt, _) = found(&mut bvh, &tris, &edges, CCD_CONE_COS);
        let (bvt, _) = brute(&bvh, &tris, &edges, x.len());
        // Pairs a turn apart along the ribbon.
        let seg = |v: u32| (v / 2) as i64;
        let across: Vec<_> = bvt
            .iter()
            .filter(|(v, t)| (seg(*v) - seg(tris[*t as usize][0])).abs() > segs as i64 / 3)
            .collect();
        assert!(across.len() > 20, "{}", across.len());
        for p in across {
            assert!(vt.binary_search(p).is_ok(), "pair {p:?} culled");
        }
    }
}
