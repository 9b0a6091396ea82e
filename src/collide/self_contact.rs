//! Cloth-cloth collision: proximity repulsion (Bridson-Fedkiw-Anderson 2002: inelastic impulse
//! plus Coulomb friction on close pairs), bounded CCD passes, then rigid impact zones
//! (Provot 1997, Harmon et al. 2008) as the fail-safe so a step that starts free of
//! self-intersections also ends free of them.
//!
//! Every pair is written as a weighted sum of up to four vertices, `r = sum c_k x_k` (vertex-
//! triangle: `x_p - sum b_i x_i`; edge-edge: `(1-s) x_a + s x_b - (1-u) x_c - u x_d`;
//! vertex-vertex: `x_i - x_j`). A change `d` of `r` is distributed as `x_k += c_k w_k d / M` with
//! `M = sum c_k^2 w_k` (w = inverse mass), the minimal-kinetic-energy impulse; kinematic
//! vertices (w = 0) never move.

use super::broad::{cell_size, collect_pairs, Aabb, PairScratch, SpatialHash};
use super::narrow;
use super::stage::{CollisionSettings, DetectionMode};
use crate::{Mat3, Vec3};
use rayon::prelude::*;

/// Vertices touching an obstacle respond to cloth-cloth impulses as if this much heavier, so the
/// cloth on top gives way rather than the layer pressed against the obstacle.
const CONTACT_MASS_FACTOR: f64 = 10.0;
/// CCD hit tolerance as a fraction of the pair's contact distance.
const CCD_ETA_FRACTION: f64 = 1e-3;
/// Separation left after a CCD correction, as a fraction of the pair's contact distance.
const CCD_GAP_FRACTION: f64 = 0.1;

#[derive(Debug, Clone, Copy)]
struct Stencil {
    idx: [u32; 4],
    c: [f64; 4],
    len: usize,
}

impl Stencil {
    fn eval(&self, x: &[Vec3]) -> Vec3 {
        (0..self.len)
            .map(|k| x[self.idx[k] as usize] * self.c[k])
            .sum()
    }

    fn inv_mass(&self, w: &[f64]) -> f64 {
        (0..self.len)
            .map(|k| self.c[k] * self.c[k] * w[self.idx[k] as usize])
            .sum()
    }

    /// Changes `r` by `d` (if any vertex can move), returning false otherwise.
    fn apply(&self, x: &mut [Vec3], w: &[f64], d: Vec3) -> bool {
        let m = self.inv_mass(w);
        if m <= 0.0 {
            return false;
        }
        for k in 0..self.len {
            let i = self.idx[k] as usize;
            x[i] += d * (self.c[k] * w[i] / m);
        }
        true
    }
}

pub(crate) struct SelfOutcome {
    pub unresolved: usize,
}

pub(crate) struct SelfCollider {
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    /// CSR vertex -> neighbour vertices (1-ring), for excluding adjacent vertex-vertex pairs.
    nbr_start: Vec<u32>,
    nbr: Vec<u32>,
    hash: SpatialHash,
    qboxes: Vec<Aabb>,
    iboxes: Vec<Aabb>,
    stamp: PairScratch,
    /// Per-candidate CCD hit flags (vertex-triangle, edge-edge), reused.
    flags: (Vec<bool>, Vec<bool>),
    pairs: Vec<(u32, u32)>,
    pairs_ee: Vec<(u32, u32)>,
    w: Vec<f64>,
    parent: Vec<u32>,
    zone_members: Vec<Vec<u32>>,
    in_zone: Vec<bool>,
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[parent[i as usize] as usize];
        parent[i as usize] = p;
        i = p;
    }
    i
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

fn shares_vertex(a: &[u32], b: &[u32]) -> bool {
    a.iter().any(|v| b.contains(v))
}

impl SelfCollider {
    pub fn new(triangles: &[[u32; 3]], n_vertices: usize) -> Self {
        let mut edges: Vec<[u32; 2]> = triangles
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let mut deg = vec![0u32; n_vertices + 1];
        for e in &edges {
            deg[e[0] as usize + 1] += 1;
            deg[e[1] as usize + 1] += 1;
        }
        for i in 0..n_vertices {
            deg[i + 1] += deg[i];
        }
        let mut fill = deg.clone();
        let mut nbr = vec![0u32; 2 * edges.len()];
        for e in &edges {
            for (a, b) in [(e[0], e[1]), (e[1], e[0])] {
                nbr[fill[a as usize] as usize] = b;
                fill[a as usize] += 1;
            }
        }
        Self {
            triangles: triangles.to_vec(),
            edges,
            nbr_start: deg,
            nbr,
            hash: SpatialHash::default(),
            qboxes: Vec::new(),
            iboxes: Vec::new(),
            stamp: PairScratch::default(),
            flags: (Vec::new(), Vec::new()),
            pairs: Vec::new(),
            pairs_ee: Vec::new(),
            w: Vec::new(),
            parent: Vec::new(),
            zone_members: Vec::new(),
            in_zone: Vec::new(),
        }
    }

    fn adjacent(&self, a: u32, b: u32) -> bool {
        let (s, e) = (
            self.nbr_start[a as usize] as usize,
            self.nbr_start[a as usize + 1] as usize,
        );
        self.nbr[s..e].contains(&b)
    }

    /// Candidate pairs over boxes of (x0 .. x1) inflated by per-element `margin`:
    /// vertex-triangle into `pairs`, edge-edge into `pairs_ee` (or vertex-vertex into `pairs`).
    fn broad_phase(
        &mut self,
        xa: &[Vec3],
        xb: &[Vec3],
        margin: impl Fn(usize) -> f64,
        vertex_vertex: bool,
    ) {
        // Only the query boxes are inflated by the contact distance (`margin`); item boxes are
        // the bare swept boxes, so no pair is found at more than the contact distance.
        let n = xa.len().min(xb.len());
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
                |a, b| a < b && !self.adjacent(a, b),
                &mut pairs,
            );
            (self.qboxes, self.iboxes) = (q, it);
            self.pairs = pairs;
            self.stamp = stamp;
            self.pairs_ee.clear();
            return;
        }
        let tris = &self.triangles;
        self.iboxes.clear();
        self.iboxes.extend(tris.iter().map(|t| {
            let [a, b, c] = t.map(|i| i as usize);
            Aabb::from_points(&[xa[a], xa[b], xa[c], xb[a], xb[b], xb[c]], 0.0)
        }));
        let cell = cell_size(&self.iboxes, 0.0);
        self.hash.build(cell, &self.iboxes);
        collect_pairs(
            &self.hash,
            &self.qboxes,
            &self.iboxes,
            &mut self.stamp,
            |v, t| !tris[t as usize].contains(&v),
            &mut self.pairs,
        );
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
        let cell = cell_size(&self.iboxes, 0.0);
        self.hash.build(cell, &self.iboxes);
        collect_pairs(
            &self.hash,
            &self.qboxes,
            &self.iboxes,
            &mut self.stamp,
            |a, b| a < b && !shares_vertex(&edges[a as usize], &edges[b as usize]),
            &mut self.pairs_ee,
        );
    }

    fn vt_stencil(&self, v: u32, t: u32, bary: [f64; 3]) -> Stencil {
        let tri = self.triangles[t as usize];
        Stencil {
            idx: [v, tri[0], tri[1], tri[2]],
            c: [1.0, -bary[0], -bary[1], -bary[2]],
            len: 4,
        }
    }

    fn ee_stencil(&self, e1: u32, e2: u32, s: f64, u: f64) -> Stencil {
        let (a, b) = (self.edges[e1 as usize], self.edges[e2 as usize]);
        Stencil {
            idx: [a[0], a[1], b[0], b[1]],
            c: [1.0 - s, s, -(1.0 - u), -u],
            len: 4,
        }
    }

    fn gap_of(&self, st: &Stencil, th: &[f64]) -> f64 {
        // Contact distance: first vertex's radius plus the (weighted) radius of the other side.
        let mut a = 0.0;
        let mut b = 0.0;
        for k in 0..st.len {
            let t = th[st.idx[k] as usize];
            if st.c[k] > 0.0 {
                a += st.c[k] * t;
            } else {
                b -= st.c[k] * t;
            }
        }
        a + b
    }

    #[allow(clippy::too_many_arguments)]
    pub fn resolve(
        &mut self,
        settings: &CollisionSettings,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        thickness: &[f64],
        friction: &[f64],
        in_contact: &[bool],
        h: f64,
    ) -> SelfOutcome {
        let n = x0.len().min(x1.len()).min(inv_mass.len());
        self.w.clear();
        self.w.extend((0..n).map(|i| {
            if in_contact[i] {
                inv_mass[i] / CONTACT_MASS_FACTOR
            } else {
                inv_mass[i]
            }
        }));
        let iters = settings.self_iterations.max(1);
        match settings.mode {
            DetectionMode::Spheres => {
                for _ in 0..iters {
                    if self.repulsion_pass(x0, x1, v1, thickness, friction, h, true) == 0 {
                        break;
                    }
                }
                SelfOutcome { unresolved: 0 }
            }
            DetectionMode::Proximity => {
                for _ in 0..iters {
                    if self.repulsion_pass(x0, x1, v1, thickness, friction, h, false) == 0 {
                        break;
                    }
                }
                SelfOutcome { unresolved: 0 }
            }
            DetectionMode::Continuous => {
                self.repulsion_pass(x0, x1, v1, thickness, friction, h, false);
                let mut clean = false;
                for _ in 0..iters {
                    if self.ccd_pass(x0, x1, v1, thickness, h, true) == 0 {
                        clean = true;
                        break;
                    }
                }
                let unresolved = if clean {
                    0
                } else {
                    self.impact_zones(settings.zone_iterations, x0, x1, v1, thickness, h)
                };
                SelfOutcome { unresolved }
            }
        }
    }

    /// One Gauss-Seidel pass of proximity repulsion on end positions; returns pairs corrected.
    #[allow(clippy::too_many_arguments)]
    fn repulsion_pass(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        friction: &[f64],
        h: f64,
        vertex_vertex: bool,
    ) -> usize {
        // Query boxes: end positions inflated by twice the radius (pair distance).
        let max_th = th.iter().copied().fold(0.0, f64::max);
        self.broad_phase(x1, x1, |i| th[i] + max_th, vertex_vertex);
        let pairs = std::mem::take(&mut self.pairs);
        let pairs_ee = std::mem::take(&mut self.pairs_ee);
        // Find close pairs in parallel, then answer them in order (Gauss-Seidel), re-measuring
        // each on the updated positions.
        let (mut flag_vt, mut flag_ee) = std::mem::take(&mut self.flags);
        {
            let this = &*self;
            let xr: &[Vec3] = x1;
            let close = |st: &Stencil| st.eval(xr).length() < this.gap_of(st, th);
            pairs
                .par_iter()
                .map(|&(a, b)| close(&this.close_stencil(a, b, xr, vertex_vertex)))
                .collect_into_vec(&mut flag_vt);
            pairs_ee
                .par_iter()
                .map(|&(a, b)| close(&this.ee_close_stencil(a, b, xr)))
                .collect_into_vec(&mut flag_ee);
        }
        let mut count = 0;
        for (&(a, b), _) in pairs.iter().zip(&flag_vt).filter(|(_, f)| **f) {
            let st = self.close_stencil(a, b, x1, vertex_vertex);
            count += self.repel(&st, x0, x1, v1, th, friction, h) as usize;
        }
        for (&(e1, e2), _) in pairs_ee.iter().zip(&flag_ee).filter(|(_, f)| **f) {
            let st = self.ee_close_stencil(e1, e2, x1);
            count += self.repel(&st, x0, x1, v1, th, friction, h) as usize;
        }
        self.flags = (flag_vt, flag_ee);
        self.pairs = pairs;
        self.pairs_ee = pairs_ee;
        count
    }

    /// Closest-point stencil of a vertex-triangle (or vertex-vertex) pair at positions `x`.
    fn close_stencil(&self, a: u32, b: u32, x: &[Vec3], vertex_vertex: bool) -> Stencil {
        if vertex_vertex {
            return Stencil {
                idx: [a, b, 0, 0],
                c: [1.0, -1.0, 0.0, 0.0],
                len: 2,
            };
        }
        let t = self.triangles[b as usize];
        let (_, bary) = narrow::point_triangle_closest(
            x[a as usize],
            x[t[0] as usize],
            x[t[1] as usize],
            x[t[2] as usize],
        );
        self.vt_stencil(a, b, bary)
    }

    /// Closest-point stencil of an edge-edge pair at positions `x`.
    fn ee_close_stencil(&self, e1: u32, e2: u32, x: &[Vec3]) -> Stencil {
        let (a, b) = (self.edges[e1 as usize], self.edges[e2 as usize]);
        let (s, u, _, _) = narrow::segment_segment_closest(
            x[a[0] as usize],
            x[a[1] as usize],
            x[b[0] as usize],
            x[b[1] as usize],
        );
        self.ee_stencil(e1, e2, s, u)
    }

    /// Separates a close pair to its contact distance along the normal of the side it started on,
    /// removes approaching normal velocity and applies Coulomb friction to the tangential part.
    #[allow(clippy::too_many_arguments)]
    fn repel(
        &self,
        st: &Stencil,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        friction: &[f64],
        h: f64,
    ) -> bool {
        let gap = self.gap_of(st, th);
        let r = st.eval(x1);
        let d = r.length();
        if d >= gap {
            return false;
        }
        let r0 = st.eval(x0);
        let mut n = if d > 1e-12 * gap.max(1e-12) {
            r / d
        } else {
            r0.normalize_or_zero()
        };
        if n == Vec3::ZERO {
            return false;
        }
        if n.dot(r0) < 0.0 {
            n = -n; // crossed during the step: push back to the starting side
        }
        let dist = n.dot(r);
        if !st.apply(x1, &self.w, n * (gap - dist)) {
            return false;
        }
        let _ = h;
        let vr = st.eval(v1);
        let vn = vr.dot(n);
        if vn < 0.0 {
            let vt = vr - n * vn;
            let mu = (0..st.len)
                .map(|k| friction[st.idx[k] as usize] * st.c[k].abs())
                .sum::<f64>()
                / (0..st.len).map(|k| st.c[k].abs()).sum::<f64>();
            let vt_len = vt.length();
            let dvt = if vt_len <= -mu * vn {
                -vt
            } else {
                vt * (mu * vn / vt_len)
            };
            st.apply(v1, &self.w, n * (-vn) + dvt);
        }
        true
    }

    /// One Gauss-Seidel CCD pass over (x0 -> x1); corrects each crossing pair so it ends
    /// separated on its starting side. Returns the number of hits.
    fn ccd_pass(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        h: f64,
        correct: bool,
    ) -> usize {
        self.broad_phase(x0, x1, |i| th[i] * CCD_ETA_FRACTION * 2.0, false);
        let pairs = std::mem::take(&mut self.pairs);
        let pairs_ee = std::mem::take(&mut self.pairs_ee);
        // Detect in parallel on the current positions, then answer the hits in order
        // (Gauss-Seidel), re-testing each since earlier corrections may have resolved it;
        // hits created by corrections are found by the next pass.
        let (mut flag_vt, mut flag_ee) = std::mem::take(&mut self.flags);
        {
            let this = &*self;
            let xr: &[Vec3] = x1;
            pairs
                .par_iter()
                .map(|&(v, t)| this.vt_hit(v, t, x0, xr, th).is_some())
                .collect_into_vec(&mut flag_vt);
            pairs_ee
                .par_iter()
                .map(|&(a, b)| this.ee_hit(a, b, x0, xr, th).is_some())
                .collect_into_vec(&mut flag_ee);
        }
        let hits = flag_vt.iter().chain(&flag_ee).filter(|f| **f).count();
        for (&(v, t), _) in pairs.iter().zip(&flag_vt).filter(|(_, f)| **f) {
            if let Some((st, nrm)) = self.vt_hit(v, t, x0, x1, th) {
                if correct {
                    self.ccd_correct(&st, nrm, x0, x1, v1, th, h);
                } else {
                    self.merge(&st);
                }
            }
        }
        for (&(e1, e2), _) in pairs_ee.iter().zip(&flag_ee).filter(|(_, f)| **f) {
            if let Some((st, nrm)) = self.ee_hit(e1, e2, x0, x1, th) {
                if correct {
                    self.ccd_correct(&st, nrm, x0, x1, v1, th, h);
                } else {
                    self.merge(&st);
                }
            }
        }
        self.flags = (flag_vt, flag_ee);
        self.pairs = pairs;
        self.pairs_ee = pairs_ee;
        hits
    }

    fn vt_hit(
        &self,
        v: u32,
        t: u32,
        x0: &[Vec3],
        x1: &[Vec3],
        th: &[f64],
    ) -> Option<(Stencil, Vec3)> {
        let tri = self.triangles[t as usize];
        let [a, b, c] = tri.map(|i| i as usize);
        let p = v as usize;
        let eta = CCD_ETA_FRACTION * (th[p] + (th[a] + th[b] + th[c]) / 3.0) + 1e-12;
        let hit = narrow::vertex_triangle_ccd(
            x0[p],
            x1[p],
            [x0[a], x0[b], x0[c]],
            [x1[a], x1[b], x1[c]],
            eta,
        )?;
        Some((self.vt_stencil(v, t, hit.bary), hit.normal))
    }

    fn ee_hit(
        &self,
        e1: u32,
        e2: u32,
        x0: &[Vec3],
        x1: &[Vec3],
        th: &[f64],
    ) -> Option<(Stencil, Vec3)> {
        let (a, b) = (self.edges[e1 as usize], self.edges[e2 as usize]);
        let [a0, a1] = a.map(|i| i as usize);
        let [b0, b1] = b.map(|i| i as usize);
        let eta = CCD_ETA_FRACTION * 0.5 * (th[a0] + th[a1] + th[b0] + th[b1]) + 1e-12;
        let hit = narrow::edge_edge_ccd(
            [x0[a0], x0[a1]],
            [x1[a0], x1[a1]],
            [x0[b0], x0[b1]],
            [x1[b0], x1[b1]],
            eta,
        )?;
        Some((self.ee_stencil(e1, e2, hit.s, hit.u), hit.normal))
    }

    /// Moves a crossing pair's end positions so that, along the hit normal oriented to the side
    /// the pair started on, it ends a small gap apart; velocities follow the changed path (dx / h).
    #[allow(clippy::too_many_arguments)]
    fn ccd_correct(
        &self,
        st: &Stencil,
        normal: Vec3,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        h: f64,
    ) {
        let r0 = st.eval(x0);
        let mut n = normal.normalize_or_zero();
        if n == Vec3::ZERO {
            n = r0.normalize_or(Vec3::Z);
        }
        if n.dot(r0) < 0.0 {
            n = -n;
        }
        let gap = CCD_GAP_FRACTION * self.gap_of(st, th);
        let d1 = n.dot(st.eval(x1));
        if d1 < gap {
            let d = n * (gap - d1);
            if st.apply(x1, &self.w, d) && h > 0.0 {
                st.apply(v1, &self.w, d / h);
            }
        }
    }

    fn merge(&mut self, st: &Stencil) {
        for k in 1..st.len {
            union(&mut self.parent, st.idx[0], st.idx[k]);
        }
    }

    /// Rigid impact zones: merge the vertices of still-colliding pairs and move each zone with
    /// the affine-rigid velocity `v_cm + w x r` from x0 (an invertible affine motion cannot
    /// create an intersection inside the zone). Returns the pairs still colliding at the end.
    fn impact_zones(
        &mut self,
        zone_iterations: usize,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        h: f64,
    ) -> usize {
        let n = x0.len().min(x1.len());
        self.parent.clear();
        self.parent.extend(0..n as u32);
        for _ in 0..zone_iterations.max(1) {
            if self.ccd_pass(x0, x1, v1, th, h, false) == 0 {
                return 0;
            }
            self.rigidify(x0, x1, v1, h);
        }
        // Last resort: vertices of zones stop at x0 (always intersection-free if x0 was).
        if self.ccd_pass(x0, x1, v1, th, h, false) == 0 {
            return 0;
        }
        self.mark_zones(n);
        for i in 0..n {
            if self.in_zone[i] && self.w[i] > 0.0 {
                x1[i] = x0[i];
                v1[i] = Vec3::ZERO;
            }
        }
        let stuck = self.ccd_pass(x0, x1, v1, th, h, false);
        if stuck > 0 {
            log::warn!("self-collision fail-safe left {stuck} colliding pairs");
        }
        stuck
    }

    /// `in_zone[i]`: vertex i shares a zone with another vertex.
    fn mark_zones(&mut self, n: usize) {
        self.in_zone.clear();
        self.in_zone.resize(n, false);
        for i in 0..n as u32 {
            let r = find(&mut self.parent, i);
            if r != i {
                self.in_zone[i as usize] = true;
                self.in_zone[r as usize] = true;
            }
        }
    }

    fn rigidify(&mut self, x0: &[Vec3], x1: &mut [Vec3], v1: &mut [Vec3], h: f64) {
        let n = x0.len().min(x1.len());
        for z in &mut self.zone_members {
            z.clear();
        }
        self.mark_zones(n);
        let mut roots: Vec<u32> = Vec::new();
        // Group members by root.
        let mut slot = vec![u32::MAX; 0];
        slot.resize(n, u32::MAX);
        for i in 0..n as u32 {
            if !self.in_zone[i as usize] {
                continue;
            }
            let r = find(&mut self.parent, i) as usize;
            if slot[r] == u32::MAX {
                slot[r] = roots.len() as u32;
                roots.push(r as u32);
                if self.zone_members.len() < roots.len() {
                    self.zone_members.push(Vec::new());
                }
            }
            self.zone_members[slot[r] as usize].push(i);
        }
        let inv_h = if h > 0.0 { 1.0 / h } else { 0.0 };
        for z in 0..roots.len() {
            let members = &self.zone_members[z];
            let vel = |i: usize| (x1[i] - x0[i]) * inv_h;
            let kinematic: Vec<usize> = members
                .iter()
                .map(|&i| i as usize)
                .filter(|&i| self.w[i] <= 0.0)
                .collect();
            if !kinematic.is_empty() {
                // Pinned vertices drive the zone: translate with their mean velocity.
                let vk = kinematic.iter().map(|&i| vel(i)).sum::<Vec3>() / kinematic.len() as f64;
                for &i in members {
                    let i = i as usize;
                    if self.w[i] > 0.0 {
                        v1[i] = vk;
                        x1[i] = x0[i] + vk * h;
                    }
                }
                continue;
            }
            let mut m_tot = 0.0;
            let mut xc = Vec3::ZERO;
            let mut vc = Vec3::ZERO;
            for &i in members {
                let i = i as usize;
                let m = 1.0 / self.w[i];
                m_tot += m;
                xc += x0[i] * m;
                vc += vel(i) * m;
            }
            xc /= m_tot;
            vc /= m_tot;
            let mut l = Vec3::ZERO;
            let mut inertia = Mat3::ZERO;
            for &i in members {
                let i = i as usize;
                let m = 1.0 / self.w[i];
                let r = x0[i] - xc;
                l += r.cross(vel(i) - vc) * m;
                inertia += (Mat3::IDENTITY * r.length_squared()
                    - Mat3::from_cols(r * r.x, r * r.y, r * r.z))
                    * m;
            }
            // Collinear zones have a singular inertia: regularise by a tiny fraction of its trace.
            let tr = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
            inertia += Mat3::IDENTITY * (1e-9 * tr + 1e-300);
            let omega = if inertia.determinant().abs() > 0.0 {
                inertia.inverse() * l
            } else {
                Vec3::ZERO
            };
            for &i in members {
                let i = i as usize;
                let v = vc + omega.cross(x0[i] - xc);
                v1[i] = v;
                x1[i] = x0[i] + v * h;
            }
        }
    }

    /// Exact count of intersecting non-adjacent triangle pairs at positions `x`.
    pub fn count_intersections(&mut self, x: &[Vec3]) -> usize {
        let tris = &self.triangles;
        self.iboxes.clear();
        self.iboxes.extend(tris.iter().map(|t| {
            Aabb::from_points(&[x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]], 0.0)
        }));
        let cell = cell_size(&self.iboxes, 0.0);
        self.hash.build(cell, &self.iboxes);
        collect_pairs(
            &self.hash,
            &self.iboxes,
            &self.iboxes,
            &mut self.stamp,
            |a, b| a < b && !shares_vertex(&tris[a as usize], &tris[b as usize]),
            &mut self.pairs,
        );
        let p = |t: [u32; 3]| t.map(|i| x[i as usize]);
        self.pairs
            .iter()
            .filter(|&&(a, b)| {
                narrow::triangles_intersect(p(tris[a as usize]), p(tris[b as usize]))
            })
            .count()
    }
}
