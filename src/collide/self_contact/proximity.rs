//! Query: proximity of close vertex-triangle and edge-edge (or vertex-vertex) pairs at the end
//! positions, answered by inelastic repulsion with Coulomb friction (Bridson et al. 2002).

use super::changed::any_of;
use super::collider::{ee_vertices, vt_vertices, SelfCollider};
use super::exempt::across_seam;
use super::jacobi::{Correction, Keyed};
use super::rest::FOLD_ARC;
use super::stencil::Stencil;
use super::touch::SelfTouch;
use crate::collide::narrow;
use crate::Vec3;
use rayon::prelude::*;

/// Cosine of the cone about a face's normal in which a vertex beyond the face's boundary still
/// counts as close to the face.
const OUTSIDE_CONE_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Largest push of one repulsion, in rest edge lengths: the strain one correction hands the next
/// solve, as fast contact (`sim/fast.rs`) lets an obstacle move a third of a spacing per substep.
/// A full projection pushes a vertex found deep inside the contact distance out at once, by
/// most of a spacing, and stretches its edges with it (robot_pick_towel as the towel lands); a
/// third keeps that stretch moderate, where a half does not and a quarter leaves too much to
/// the later passes (the 2x crumple stretches more).
const PUSH_CAP: f64 = 1.0 / 3.0;

/// A pair within this fraction of its contact distance counts as settled: the passes stop when
/// every pair is. A mean of a vertex's corrections (`jacobi`) closes only part of each pair's
/// deficit where pairs that hardly move the vertex share in it (a vertex over a layer is pushed
/// by its own pair and, a little, by the layer's vertices' pairs with its triangles): one pass
/// leaves two sheets dropped on each other well inside their contact distance.
pub(super) const SETTLED: f64 = 1e-2;

/// One parallel part of [`SelfCollider::near_answers`]: its tested count, answers and (on a
/// walk of the rest lists) the pairs whose boxes overlap.
#[derive(Default)]
struct NearPart {
    tested: usize,
    found: Vec<Keyed>,
    kept: Vec<(u32, u32)>,
}

impl SelfCollider {
    /// One pass of proximity repulsion (Jacobi, averaged) on the candidates of a fresh broad
    /// phase, or (`fresh` false) on the previous pass's, of which only those with a changed
    /// vertex (`changed`); returns the pairs still short of their contact distance by more
    /// than [`SETTLED`] of it on end positions.
    /// `with_edges`: edge-edge pairs too (without CCD behind it); with CCD the vertex-triangle
    /// pairs keep the layers apart and CCD answers edges that cross, at about half the
    /// collision stage's cost (robot_pick_towel, still without self-intersection).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn repulsion_pass(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        friction: &[f64],
        vertex_vertex: bool,
        with_edges: bool,
        fresh: bool,
    ) -> usize {
        if fresh {
            // Query boxes: end positions inflated by twice the radius (pair distance).
            let max_th = th.iter().copied().fold(0.0, f64::max);
            self.broad_phase(
                x1,
                x1,
                |i| th[i] + max_th,
                vertex_vertex,
                true,
                with_edges,
                None,
            );
            self.rep_changed.forget();
        }
        // On the previous pass's candidates only the pairs with a changed vertex can answer
        // anew (`changed`).
        let since = self.rep_changed.update(x1, Some(v1));
        if since == Some(false) {
            return 0;
        }
        let pairs = std::mem::take(&mut self.pairs);
        let pairs_ee = std::mem::take(&mut self.pairs_ee);
        // Find close pairs and their answers in parallel on the pass's start state, then move
        // each vertex by the mean of its answers (order-independent; see `jacobi`), taken in
        // the order of the pairs (vertex-triangle by key, then edge-edge).
        let mut found = std::mem::take(&mut self.found);
        let mut found_vt = std::mem::take(&mut self.found_vt);
        let mut found_near = std::mem::take(&mut self.found_near);
        let mut near_kept = std::mem::take(&mut self.near_kept);
        let (tested, near_valid);
        {
            let this = &*self;
            let xr: &[Vec3] = x1;
            let flags = since.map(|_| this.rep_changed.flags());
            let anew = |idx: &[u32]| flags.is_none_or(|f| any_of(f, idx));
            let answer = |c: Option<Close>| c.and_then(|c| this.repel(&c, xr, friction));
            found_vt.clear();
            found_vt.par_extend(
                pairs
                    .par_iter()
                    .filter(|&&(a, b)| {
                        if vertex_vertex {
                            anew(&[a, b])
                        } else {
                            anew(&vt_vertices(&this.triangles, a, b))
                        }
                    })
                    .filter_map(|&(a, b)| {
                        answer(this.vt_close(a, b, x0, xr, th, vertex_vertex)).map(|c| ((a, b), c))
                    }),
            );
            found_near.clear();
            (tested, near_valid) = if vertex_vertex {
                (0, this.near_kept_valid)
            } else {
                this.near_answers(
                    |v, t| answer(this.near_close(v, t, x0, xr, th)),
                    &anew,
                    &mut near_kept,
                    &mut found_near,
                )
            };
            found.clear();
            merge_by_key(&found_vt, &found_near, &mut found);
            found.par_extend(
                pairs_ee
                    .par_iter()
                    .filter(|&&(a, b)| anew(&ee_vertices(&this.edges, a, b)))
                    .filter_map(|&(a, b)| answer(this.ee_close(a, b, x0, xr, th))),
            );
        }
        if fresh {
            self.report.candidates += tested;
        }
        // Two layers resting on each other: for the solver to hold apart next substep.
        for ((v, t), c) in found_vt.iter().chain(&found_near) {
            if let Some((normal, gap)) = c.layers {
                self.touches.push(SelfTouch {
                    vertex: *v,
                    triangle: self.triangles[*t as usize],
                    bary: [-c.st.c[1], -c.st.c[2], -c.st.c[3]],
                    normal,
                    gap,
                });
            }
        }
        let mut pass = std::mem::take(&mut self.jacobi);
        for c in &found {
            pass.add(c, &self.w);
            self.rep_changed.answer_again(&c.st.idx[..c.st.len]);
        }
        self.report.slipping += pass.apply(x1, v1, &self.w_true);
        let unsettled = found.iter().filter(|c| c.residual > SETTLED).count();
        self.report.repulsions += found.len();
        self.jacobi = pass;
        self.found = found;
        self.pairs = pairs;
        self.pairs_ee = pairs_ee;
        self.found_vt = found_vt;
        self.found_near = found_near;
        (self.near_kept, self.near_kept_valid) = (near_kept, near_valid);
        unsettled
    }

    /// The answers `test` gives the vertex-triangle pairs near in the rest shape
    /// (`RestShape::near_vt`) that `anew` keeps, whose boxes overlap at the last proximity
    /// refit and that lie across no seam being sewn, into `out` in (vertex, triangle) order;
    /// returns how many were tested. Read from the rest lists in parallel over vertices: a
    /// crumpling sheet tests a good part of its near pairs, nearly all of them a flat sheet one
    /// ring or two beyond its contact distance, where listing and sorting them would cost as
    /// much as testing.
    ///
    /// The pairs whose boxes overlap are kept in `kept` (valid until the next refit,
    /// `near_kept_valid`; returned with the count), and the step's later passes, on the same
    /// boxes, read those instead of the lists: on a towel (`robot_towel.yaml` at 64x64) only a
    /// small share of the near pairs a walk visits overlap.
    fn near_answers(
        &self,
        test: impl Fn(u32, u32) -> Option<Correction> + Sync,
        anew: &(impl Fn(&[u32]) -> bool + Sync),
        kept: &mut Vec<(u32, u32)>,
        out: &mut Vec<Keyed>,
    ) -> (usize, bool) {
        const CHUNK: usize = 128;
        const KEPT_CHUNK: usize = 1024;
        let (Some(rest), Some(bvh)) = (self.rest.as_ref(), self.bvh.as_ref()) else {
            return (0, false);
        };
        let answer = |part: &mut NearPart, v: u32, t: u32| {
            if anew(&vt_vertices(&self.triangles, v, t)) {
                part.tested += 1;
                if let Some(c) = test(v, t) {
                    part.found.push(((v, t), c));
                }
            }
        };
        let parts: Vec<NearPart> = if self.near_kept_valid {
            kept.par_chunks(KEPT_CHUNK)
                .map(|pairs| {
                    let mut part = NearPart::default();
                    pairs.iter().for_each(|&(v, t)| answer(&mut part, v, t));
                    part
                })
                .collect()
        } else {
            let rows = rest
                .near_vt
                .rows()
                .min(self.nbr_start.len().saturating_sub(1));
            (0..rows.div_ceil(CHUNK))
                .into_par_iter()
                .map(|c| {
                    let mut part = NearPart::default();
                    for v in c * CHUNK..((c + 1) * CHUNK).min(rows) {
                        let v = v as u32;
                        for &t in rest.near_vt.row(v as usize) {
                            let tri = &self.triangles[t as usize];
                            if bvh.vt_overlap(v, t) && !across_seam(&self.seam_bits, &[v], tri) {
                                part.kept.push((v, t));
                                answer(&mut part, v, t);
                            }
                        }
                    }
                    part
                })
                .collect()
        };
        if !self.near_kept_valid {
            kept.clear();
        }
        let mut tested = 0;
        for part in parts {
            tested += part.tested;
            out.extend(part.found);
            kept.extend(part.kept);
        }
        (tested, true)
    }

    /// A close vertex-triangle (or vertex-vertex) pair at positions `x`: its stencil, the
    /// normal its repulsion acts along (oriented to the side the pair was on at `x0`) and its
    /// contact distance.
    ///
    /// Pairs near in the rest shape keep the closest point's direction (see below). Others are
    /// two layers, and act along the face's normal: when the vertex is within the contact
    /// distance of the triangle's plane and projects inside the triangle (to within that
    /// distance; Bridson et al. 2002, sec. 4), or lies beyond its boundary within 45 degrees of
    /// the normal. The closest point's direction there is radial about the boundary: the two
    /// ends of one edge, pressed from either side onto a crease of the other layer (the flag at
    /// twice its resolution), would be pushed apart along such normals by millimetres a substep,
    /// stretching the edge far more than along the face normals. A vertex beside the boundary,
    /// in the triangle's plane, is the neighbouring face's or CCD's.
    fn vt_close(
        &self,
        a: u32,
        b: u32,
        x0: &[Vec3],
        x: &[Vec3],
        th: &[f64],
        vertex_vertex: bool,
    ) -> Option<Close> {
        if vertex_vertex {
            let st = Stencil {
                idx: [a, b, 0, 0],
                c: [1.0, -1.0, 0.0, 0.0],
                len: 2,
            };
            let gap = st.gap(th);
            return radial(st.eval(x), st.eval(x0), gap).map(|n| Close::across(st, n, gap));
        }
        let t = self.triangles[b as usize];
        let [pa, pb, pc] = t.map(|i| x[i as usize]);
        let p = x[a as usize];
        // Farther from the triangle's plane than any contact distance the pair can have (the
        // vertex's radius plus the largest of the triangle's): no closest point is nearer.
        // Most candidates end here, before the closest point is sought.
        let reach = th[a as usize] + t.iter().map(|&i| th[i as usize]).fold(0.0, f64::max);
        let nf = (pb - pa).cross(pc - pa);
        let nf_len = nf.length();
        if nf_len > 0.0 && nf.dot(p - pa).abs() >= reach * nf_len {
            return None;
        }
        let (q, bary) = narrow::point_triangle_closest(p, pa, pb, pc);
        self.vt_close_at(a, b, q, bary, x0, x, th)
    }

    /// `vt_close` for a pair near in the rest shape (`RestShape::near_vt`), most of them the
    /// flat sheet around the vertex one ring or two beyond its contact distance. Such a pair
    /// is rejected on squared distances alone when it is also near in the rest shape at its
    /// closest point (answered along that point's direction, below): beyond its contact
    /// distance, nothing. In-plane, the plane test of `vt_close` rejects none of them.
    fn near_close(&self, a: u32, b: u32, x0: &[Vec3], x: &[Vec3], th: &[f64]) -> Option<Close> {
        let [pa, pb, pc] = self.triangles[b as usize].map(|i| x[i as usize]);
        let p = x[a as usize];
        let (q, bary) = narrow::point_triangle_closest(p, pa, pb, pc);
        let st = self.vt_stencil(a, b, bary);
        let gap = st.gap(th);
        // Margins of a part in 1e12 keep the squares on the side the lengths are on.
        let near = self
            .rest
            .as_ref()
            .and_then(|r| r.distance_squared(&st))
            .is_some_and(|d2| d2 < (FOLD_ARC * gap).powi(2) * (1.0 - 1e-12));
        if near && (p - q).length_squared() >= gap * gap * (1.0 + 1e-12) {
            return None;
        }
        self.vt_close_at(a, b, q, bary, x0, x, th)
    }

    /// `vt_close` from the vertex's closest point `q` (barycentric `bary`) on the triangle.
    #[allow(clippy::too_many_arguments)]
    fn vt_close_at(
        &self,
        a: u32,
        b: u32,
        q: Vec3,
        bary: [f64; 3],
        x0: &[Vec3],
        x: &[Vec3],
        th: &[f64],
    ) -> Option<Close> {
        let t = self.triangles[b as usize];
        let [pa, pb, pc] = t.map(|i| x[i as usize]);
        let p = x[a as usize];
        let st = self.vt_stencil(a, b, bary);
        let rest_d = self
            .rest
            .as_ref()
            .map_or(f64::INFINITY, |r| r.distance(&st));
        if rest_d < FOLD_ARC * st.gap(th) || t.iter().any(|&k| self.adjacent(a, k)) {
            // Near in the rest shape: too near for the cloth between them to fold round (a fold
            // that holds two layers `gap` apart is at least pi/2 gap long), or one edge apart
            // (the triangle touches the vertex's 1-ring: no vertex between them to fold at), so
            // their closeness is the sheet squeezed in its own plane, which the in-surface
            // direction of the closest point undoes. The face normal there would push the
            // vertex out of its own sheet: through the sheet under it in
            // `tests/collide_self.rs`, to a blow-up in the gripper of robot_pick_towel. Skipping
            // these pairs would let the 2x crumple overstretch. Nor is such a pair held farther
            // apart than it is at rest.
            let gap = st.gap(th).min(rest_d);
            return radial(p - q, st.eval(x0), gap).map(|n| Close::across(st, n, gap));
        }
        let (e0, e1, e2) = (pb - pa, pc - pa, pc - pb);
        let max_edge2 = e0
            .length_squared()
            .max(e1.length_squared())
            .max(e2.length_squared());
        let nf = e0.cross(e1);
        let area2 = nf.length();
        if area2 <= 1e-12 * max_edge2 || max_edge2 <= 0.0 {
            // A degenerate triangle has no face normal: its neighbours and CCD answer.
            return None;
        }
        let nf = nf / area2;
        let gap = th[a as usize] + (t.iter().map(|&i| th[i as usize]).sum::<f64>()) / 3.0;
        let s = nf.dot(p - pa);
        if s.abs() >= gap {
            return None;
        }
        let f = p - nf * s;
        let bary = [
            (pb - f).cross(pc - f).dot(nf) / area2,
            (pc - f).cross(pa - f).dot(nf) / area2,
            (pa - f).cross(pb - f).dot(nf) / area2,
        ];
        let tol = gap / max_edge2.sqrt();
        let st = if bary.iter().all(|&w| w >= -tol) {
            let clamped = bary.map(|w| w.max(0.0));
            let sum: f64 = clamped.iter().sum();
            self.vt_stencil(a, b, clamped.map(|w| w / sum))
        } else {
            // Beyond the boundary: the pair is the face's only while the vertex lies within
            // 45 degrees of its normal seen from the closest point.
            let r = p - q;
            let d = r.length();
            if d >= gap || nf.dot(r).abs() < OUTSIDE_CONE_COS * d {
                return None;
            }
            st
        };
        let gap = st.gap(th);
        // Within the contact distance of the plane but not of the triangle: the tolerance above
        // assumes a thickness small against the triangle, and with a thickness near the spacing
        // (128x128 crumple: 6 mm on a 6.3 mm spacing, `tol` 1.35) it would answer thousands of
        // such pairs a step, pushing layers apart beyond their contact distance.
        if (p - q).length_squared() >= gap * gap {
            return None;
        }
        let n = if nf.dot(st.eval(x0)) >= 0.0 { nf } else { -nf };
        let dist = n.dot(st.eval(x));
        // Behind the face it started in front of: a crossing, CCD's (with the crossing's normal).
        (dist >= 0.0 && dist < gap).then_some(Close {
            st,
            n,
            gap,
            layers: true,
        })
    }

    /// A close edge-edge pair at positions `x`, with the normal along the closest points'
    /// direction (perpendicular to both edges where the closest points are inside them),
    /// oriented to the side the pair was on at `x0`.
    fn ee_close(&self, e1: u32, e2: u32, x0: &[Vec3], x: &[Vec3], th: &[f64]) -> Option<Close> {
        let (a, b) = (self.edges[e1 as usize], self.edges[e2 as usize]);
        let (s, u, _, _) = narrow::segment_segment_closest(
            x[a[0] as usize],
            x[a[1] as usize],
            x[b[0] as usize],
            x[b[1] as usize],
        );
        let st = self.ee_stencil(e1, e2, s, u);
        let gap = st.gap(th);
        radial(st.eval(x), st.eval(x0), gap).map(|n| Close::across(st, n, gap))
    }

    /// The answer to a close pair: separation to its contact distance `gap` along `n` (the
    /// side it started on), and for `impulses` that normal (its approaching normal velocity
    /// removed) and the pair's Coulomb coefficient (friction on the tangential part): the mean
    /// of its vertices' by the weight of each in the pair.
    fn repel(&self, close: &Close, x1: &[Vec3], friction: &[f64]) -> Option<Correction> {
        let (st, n, gap) = (&close.st, close.n, close.gap);
        let dist = n.dot(st.eval(x1));
        if dist >= gap || st.inv_mass(&self.w) <= 0.0 {
            return None;
        }
        let cap = self
            .rest
            .as_ref()
            .map_or(f64::INFINITY, |r| PUSH_CAP * r.max_edge);
        let mu = (0..st.len)
            .map(|k| friction[st.idx[k] as usize] * st.c[k].abs())
            .sum::<f64>()
            / (0..st.len).map(|k| st.c[k].abs()).sum::<f64>();
        Some(Correction {
            st: *st,
            dx: n * (gap - dist).min(cap),
            n,
            mu,
            residual: (gap - dist) / gap,
            layers: close.layers.then_some((n, gap)),
        })
    }
}

/// A close pair: its stencil, the normal its repulsion acts along (towards the side it started
/// on), its contact distance, and whether it is two layers (a vertex over a face, along the
/// face's normal), the pairs the solver holds apart next substep (`CollisionStage::self_touches`).
struct Close {
    st: Stencil,
    n: Vec3,
    gap: f64,
    layers: bool,
}

impl Close {
    /// A pair answered along its closest points' direction: not two layers.
    fn across(st: Stencil, n: Vec3, gap: f64) -> Self {
        Self {
            st,
            n,
            gap,
            layers: false,
        }
    }
}

/// The answers of two lists, each in key order, merged in key order (keys are distinct).
fn merge_by_key(a: &[Keyed], b: &[Keyed], out: &mut Vec<Correction>) {
    out.reserve(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        if j == b.len() || (i < a.len() && a[i].0 < b[j].0) {
            out.push(a[i].1);
            i += 1;
        } else {
            out.push(b[j].1);
            j += 1;
        }
    }
}

/// The direction `r` of a pair closer than `gap` (`r0` where `r` vanishes), when the pair is on
/// the side it started on (`r0`, at the start of the step).
///
/// Seen from the start of the step on the other side, the pair either crossed (CCD's case, with
/// the crossing's own normal) or its closest feature changed. Pushed here by `gap + d` through
/// the other element, it went 26 m/s where robot_cape's attachments squeeze the cloth between
/// the torso and a shoulder.
fn radial(r: Vec3, r0: Vec3, gap: f64) -> Option<Vec3> {
    let d = r.length();
    if d >= gap {
        return None;
    }
    let n = if d > 0.0 {
        r / d
    } else {
        r0.normalize_or_zero()
    };
    (n != Vec3::ZERO && n.dot(r0) >= 0.0).then_some(n)
}
