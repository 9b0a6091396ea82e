//! Strain limiting (Provot 1995): after each solve, a mesh edge longer than `1 + strain_limit`
//! times its rest length is shortened to that length, its two ends moved along it in proportion
//! to their inverse masses (kinematic ends stay).
//!
//! Why: linear springs let a point load stretch cloth without limit (a sheet pinned at two
//! corners and dragged by a rod stretches the edges at the pins several times their rest
//! length, the more the faster the rod, `tests/fast_links.rs`), and real fabric does not: it
//! stiffens sharply past a few percent. Stiffer springs would cost conditioning;
//! the limit costs a few passes over the edges, and only where a material names it
//! (`material.strain_limit`).
//!
//! Two parts, in this order:
//! - Tethers (long-range attachments, Kim, Chentanez and Müller 2012): a free vertex may be at
//!   most `1 + strain_limit` times its rest geodesic distance from each of its [`TETHERS`] nearest
//!   kinematic vertices (pins, attachments), and is put back on that sphere when it is not, its
//!   velocity away from the anchor removed. A sheet hanging from two corner pins carries its
//!   whole weight through the edges at the pins, and edge passes alone move that correction one
//!   ring per pass (a 40-vertex chain 50 % over rest stays over after all the passes, see the
//!   tests); a tether takes it in one step.
//! - Edge passes: Gauss-Seidel over the edges, alternating direction, until no edge exceeds its
//!   limit by more than [`SLACK`] of its allowed elongation or [`MAX_PASSES`] ran; what is left
//!   is reported (`StepMetrics`). Velocities follow the moves over the substep (Provot), so the
//!   cloth a rod drags feels the pins and slides: removing only the separating velocity left the
//!   rod's contacts and the pins fighting every substep. But an edge's ends get at most their
//!   relative speed as speed towards each other: on the short substeps fast contact splits a
//!   frame into, a centimetre's correction over 65 us is 150 m/s, which Provot's plain update
//!   would put into the cloth.
//!
//! The limit runs before the collision pass, whose answers may stretch an edge again: the pass
//! moves a vertex by up to a contact thickness whatever the stiffness. Where a material sets a
//! limit or a knee (`stretch_knee`), an obstacle's answer that takes an edge past it is held to
//! it ([`ResponseBound`]), in two steps:
//! - a vertex-pass answer goes to the next solve ([`ResponseBound::hold_response`]): the
//!   answering end is moved back towards where the pass found it, along its own move, just far
//!   enough, and only where that way crosses no obstacle's surface (so the collision pass's
//!   guarantee that no vertex crosses a surface stands); its contact stays with the stage, and
//!   the next solve holds it against the surface with the cloth around it;
//! - what is left, mostly feature answers (an obstacle's edge or rod between vertices, whose
//!   answer has no way back that keeps the feature out), is spread over the cloth around it
//!   ([`ResponseBound::spread_response`]): edge passes pull the neighbours after the answer, in
//!   short moves that cross no surface, go no deeper into a contact layer and take no mesh edge
//!   through an obstacle. A stiff tarp landing on a turning box's edge stays within 1.05 of rest
//!   with a knee at 3 % (`tests/stretch_knee.rs`);
//! - cloth-cloth repulsion's answers, which keep layers a contact distance apart, go back to the
//!   next solve the same way (its layer springs hold the layers apart), before the self-contact
//!   CCD passes and impact zones, which keep the layers from crossing whatever went back. A
//!   cloth's free edge folding over as it lands on a ball was pushed 14 % past rest by one
//!   repulsion; every bundled scene with a knee at 3 % and self-collision ends its frames within
//!   1.04 of rest, but the pinched towel (1.11) and the soft-stretch cloth (1.09).
//!
//! Linear materials get neither: held to their rest length, the passes would drag resting cloth
//! (a sheet draped on a box corner slides off it, `tests/contact_rest.rs`).
//! `tests/fast_links.rs` and `tests/stretch_knee.rs` measure what is left.
//!
//! Tethers are built once per set of kinematic vertices, one Dijkstra per anchor over the mesh:
//! a grasp or a release that changes the set pays it again.

use crate::cloth::{Cloth, Kinematic};
use crate::Vec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// An edge counts as within its limit when it exceeds it by at most this fraction of the
/// allowed elongation `strain_limit * rest` (1 % of a 10 % limit is 0.1 % of the rest length).
const SLACK: f64 = 0.01;

/// Passes per substep at most. A corner pin holding a sheet that a rod drags needs the
/// correction to cross the sheet: one pass each way does that in order, more settle the
/// coupling between rows and columns.
const MAX_PASSES: usize = 32;

/// Tethers per free vertex: to its nearest kinematic vertices by rest geodesic distance.
const TETHERS: usize = 4;

/// Passes over the edges at most when the collision pass's answers are held to the bound (a
/// vertex moved back for one edge may stretch another that the same answer moved).
const HOLD_PASSES: usize = 8;

/// Passes over the edges at most when what the collision pass left past the bound is spread
/// over the cloth around its answers (one ring of vertices per pass at least).
const SPREAD_PASSES: usize = 32;

/// The longest move of one spreading pass, over the vertex's contact thickness: an edge whose
/// end moves less than a rod's diameter cannot jump the rod between two checks of its end state.
const SPREAD_MOVE: f64 = 0.25;

/// An edge counts as within the bound when the collision pass's answers left it longer by at
/// most this fraction (0.1 % of its length): what a stretch check reads as none, and no pass
/// for the edges every contact lengthens by round-off.
const SPREAD_SLACK: f64 = 1e-3;

/// Deeper in a contact layer than this fraction of its thickness counts as deeper (round-off of
/// the closest-point query).
const LAYER_ROUND_OFF: f64 = 1e-9;

/// An edge counts as within the collision pass's bound when it exceeds it by at most this
/// fraction (round-off of the way back).
const HOLD_SLACK: f64 = 1e-9;

/// The limit of one cloth's edges (built where a piece's material sets `strain_limit`).
#[derive(Debug, Clone)]
pub(super) struct StrainLimit {
    /// `(i, j, longest allowed length, tolerated length)` of every limited mesh edge.
    edges: Vec<(u32, u32, f64, f64)>,
    /// Per vertex: its neighbours over the mesh edges with their rest lengths, and its piece's
    /// limit (`None`: not limited), for the tethers.
    neighbours: Vec<Vec<(u32, f64)>>,
    limit: Vec<Option<f64>>,
}

/// The tethers for one set of kinematic vertices: a cache the step keeps, rebuilt when the set
/// changes (a grasp, a release) or the cloth is replaced.
#[derive(Debug, Clone, Default)]
pub(super) struct Tethers {
    /// The kinematic vertices they were built for, in the cloth's order.
    anchors: Vec<u32>,
    /// `(free vertex, anchor, longest allowed distance)`.
    list: Vec<(u32, u32, f64)>,
}

/// What one substep's limiting did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct LimitPass {
    /// Edges over their limit in the first pass (the ones the solve left too long).
    pub shortened: u32,
    /// Largest length over the allowed length left after the passes, minus one (0: met).
    pub excess: f64,
}

impl StrainLimit {
    /// The limit for `cloth`'s pieces that set one; `None` when none does (no cost).
    pub fn of(cloth: &Cloth) -> Option<Self> {
        if cloth
            .pieces
            .iter()
            .all(|p| p.material.strain_limit.is_none())
        {
            return None;
        }
        let n = cloth.len();
        let limit: Vec<Option<f64>> = (0..n)
            .map(|i| cloth.piece_of(i).and_then(|p| p.material.strain_limit))
            .collect();
        let mut edges = Vec::new();
        let mut neighbours = vec![Vec::new(); n];
        for (i, j) in crate::cloth::topology::unique_edges(&cloth.triangles) {
            let (a, b) = (i as usize, j as usize);
            let (Some(ua), Some(ub)) = (cloth.uv.get(a), cloth.uv.get(b)) else {
                continue;
            };
            let rest = ua.distance(*ub);
            let Some(s) = limit[a].filter(|_| rest > 0.0 && rest.is_finite()) else {
                continue;
            };
            let allowed = rest * (1.0 + s);
            edges.push((i, j, allowed, allowed + SLACK * s * rest));
            neighbours[a].push((j, rest));
            neighbours[b].push((i, rest));
        }
        Some(Self {
            edges,
            neighbours,
            limit,
        })
    }

    /// The tethers of the `kinematic` vertices, from `cache` while the set stays the same.
    fn tethers_for<'a>(
        &self,
        cache: &'a mut Tethers,
        kinematic: &[(u32, Kinematic)],
    ) -> &'a [(u32, u32, f64)] {
        let same = cache.anchors.len() == kinematic.len()
            && (cache.anchors.iter())
                .zip(kinematic)
                .all(|(a, (k, _))| a == k);
        if !same {
            let anchors: Vec<u32> = kinematic.iter().map(|(k, _)| *k).collect();
            *cache = Tethers {
                list: tethers(&self.neighbours, &self.limit, &anchors),
                anchors,
            };
        }
        &cache.list
    }

    /// Holds `x` within the limit over the substep `h`: the tethers of the `kinematic` vertices
    /// (kept in `cache`), then the edge passes (inverse masses `w`, 0 for kinematic vertices).
    #[allow(clippy::too_many_arguments)]
    pub fn apply(
        &self,
        cache: &mut Tethers,
        x: &mut [Vec3],
        v: &mut [Vec3],
        w: &[f64],
        kinematic: &[(u32, Kinematic)],
        h: f64,
    ) -> LimitPass {
        for &(i, a, allowed) in self.tethers_for(cache, kinematic) {
            let (i, a) = (i as usize, a as usize);
            let d = x[i] - x[a];
            let len = d.length();
            if len > allowed {
                let n = d / len;
                x[i] = x[a] + n * allowed;
                let away = n.dot(v[i] - v[a]);
                if away > 0.0 {
                    v[i] -= n * away;
                }
            }
        }
        self.edges(x, v, w, h)
    }

    /// The edge passes alone: edges over their limit shortened (moves in proportion to `w`), the
    /// velocities moved by the same over the substep `h`.
    fn edges(&self, x: &mut [Vec3], v: &mut [Vec3], w: &[f64], h: f64) -> LimitPass {
        let mut out = LimitPass::default();
        for pass in 0..MAX_PASSES {
            let mut over = 0u32;
            let mut fix = |&(i, j, allowed, tolerated): &(u32, u32, f64, f64)| {
                let (i, j) = (i as usize, j as usize);
                let d = x[j] - x[i];
                let len = d.length();
                if len.is_nan() || len <= tolerated {
                    return;
                }
                over += 1;
                let (wi, wj) = (w[i], w[j]);
                let sum = wi + wj;
                if sum <= 0.0 {
                    return;
                }
                let n = d / len;
                let dx = n * ((len - allowed) / sum);
                x[i] += dx * wi;
                x[j] -= dx * wj;
                if h > 0.0 {
                    // Provot's velocity change, at most the ends' relative speed (see above).
                    let rate = ((len - allowed) / h).min((v[j] - v[i]).length());
                    let dv = n * (rate / sum);
                    v[i] += dv * wi;
                    v[j] -= dv * wj;
                }
            };
            if pass % 2 == 0 {
                self.edges.iter().for_each(&mut fix);
            } else {
                self.edges.iter().rev().for_each(&mut fix);
            }
            if pass == 0 {
                out.shortened = over;
            }
            if over == 0 {
                return out;
            }
        }
        out.excess = (self.edges.iter())
            .map(|&(i, j, allowed, _)| x[i as usize].distance(x[j as usize]) / allowed - 1.0)
            .fold(0.0, f64::max);
        out
    }
}

/// The bound the collision pass's answers are held to (built where a piece's material sets
/// `strain_limit` or `stretch_knee`): per mesh edge the shorter of `1 + strain_limit` and
/// `1 + stretch_knee` times its rest length. Past the knee only the solve, which knows the
/// stiffening, stretches an edge; past the limit, nothing does. The collision pass moves
/// vertices by up to a contact thickness whatever the stiffness (a 5 mm push on a 3 cm edge
/// is 17 %): what it would stretch past the bound goes back to the next solve where it can
/// ([`Self::hold_response`]) and is spread over the cloth around it where it cannot
/// ([`Self::spread_response`]).
#[derive(Debug, Clone)]
pub(super) struct ResponseBound {
    /// `(i, j, allowed length)` of every bounded mesh edge.
    edges: Vec<(u32, u32, f64)>,
    /// Per vertex, its neighbours over the mesh edges.
    neighbours: Vec<Vec<u32>>,
}

impl ResponseBound {
    /// The bound of `cloth`'s pieces that set a limit or a knee; `None` when none does.
    pub fn of(cloth: &Cloth) -> Option<Self> {
        let strain = |m: &crate::cloth::Material| match (m.strain_limit, m.stretch_knee) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        if cloth.pieces.iter().all(|p| strain(&p.material).is_none()) {
            return None;
        }
        let mut edges = Vec::new();
        let mut neighbours = vec![Vec::new(); cloth.len()];
        for (i, j) in crate::cloth::topology::unique_edges(&cloth.triangles) {
            let (a, b) = (i as usize, j as usize);
            if a < neighbours.len() && b < neighbours.len() {
                neighbours[a].push(j);
                neighbours[b].push(i);
            }
            let (Some(ua), Some(ub)) = (cloth.uv.get(a), cloth.uv.get(b)) else {
                continue;
            };
            let rest = ua.distance(*ub);
            let s = cloth.piece_of(a).and_then(|p| strain(&p.material));
            if let Some(s) = s.filter(|_| rest > 0.0 && rest.is_finite()) {
                edges.push((i, j, rest * (1.0 + s)));
            }
        }
        Some(Self { edges, neighbours })
    }

    /// Holds the collision pass's answers to the bound: where an edge ends longer than its
    /// allowed length, and longer than in `before` (the positions the pass started from), its
    /// ends that `deferred` allows (the ones the vertex pass or the repulsion answered) go back towards their
    /// `before` position along their move, both by the same share of it, the least that brings
    /// the edge to the longer of its allowed length and its length in `before`; their contacts
    /// stay with the stage, for the next solve. A vertex goes back only where `clear(from, to)`
    /// says the way crosses no obstacle's surface. Returns the edges that needed it; the
    /// velocities stay those of the answer.
    pub fn hold_response(
        &self,
        before: &[Vec3],
        x: &mut [Vec3],
        deferred: impl Fn(usize) -> bool,
        clear: impl Fn(Vec3, Vec3) -> bool,
    ) -> u32 {
        let mut held = 0u32;
        for pass in 0..HOLD_PASSES {
            let mut changed = false;
            for &(i, j, allowed) in &self.edges {
                let (i, j) = (i as usize, j as usize);
                let len = x[i].distance(x[j]);
                let target = allowed.max(before[i].distance(before[j]));
                if len.is_nan() || len <= target * (1.0 + HOLD_SLACK) {
                    continue;
                }
                let back = |k: usize| (deferred(k) && x[k] != before[k]).then(|| before[k] - x[k]);
                let (bi, bj) = (back(i), back(j));
                if bi.is_none() && bj.is_none() {
                    continue;
                }
                // The edge at share `t` of the way back: `d + t m`; the least `t` in [0, 1]
                // with `|d + t m| = target` (the edge is longer than `target` at `t = 0`).
                let d = x[i] - x[j];
                let m = bi.unwrap_or(Vec3::ZERO) - bj.unwrap_or(Vec3::ZERO);
                let (a, b, c) = (
                    m.length_squared(),
                    d.dot(m),
                    d.length_squared() - target * target,
                );
                let disc = b * b - a * c;
                let t = if a > 0.0 && b < 0.0 && disc >= 0.0 {
                    ((-b - disc.sqrt()) / a).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                if pass == 0 {
                    held += 1;
                }
                for (k, way) in [(i, bi), (j, bj)] {
                    if let Some(way) = way {
                        let to = x[k] + way * t;
                        if clear(x[k], to) {
                            x[k] = to;
                            changed = true;
                        }
                    }
                }
            }
            if !changed {
                break;
            }
        }
        held
    }

    /// Spreads what the collision pass's answers left past the bound over the cloth around
    /// them: where an edge ends longer than its allowed length and longer than in `before`, its
    /// ends move along it towards each other by the excess, shared by inverse mass, Gauss-Seidel
    /// in alternating directions, so the correction reaches further with every pass. A feature
    /// answer (an obstacle's edge or rod held from passing between vertices) cannot go back
    /// along its own move (see [`Self::hold_response`]); it slides along the cloth instead, and
    /// the cloth around it follows, as a membrane stiffened past its knee would.
    ///
    /// Vertex `k` moves at most [`SPREAD_MOVE`] times its contact thickness `thickness(k)` per
    /// pass, and from `from` to `to` only where
    /// `clear(k, from, to)` (no surface crossed, no deeper in a contact layer) and none of its
    /// mesh edges newly crosses an obstacle (`edge_clear(a, b)` false at `to`, true at `from`):
    /// with moves shorter than a rod is thick, an edge cannot jump a rod between two checks.
    /// Returns the edges that needed it on the first pass; velocities stay the solve's.
    pub fn spread_response(
        &self,
        before: &[Vec3],
        x: &mut [Vec3],
        inv_mass: &[f64],
        clear: impl Fn(usize, Vec3, Vec3) -> bool,
        edge_clear: impl Fn(Vec3, Vec3) -> bool,
        thickness: impl Fn(usize) -> f64,
    ) -> u32 {
        let mut spread = 0u32;
        let weight = |k: usize| match inv_mass.get(k) {
            Some(&w) if w > 0.0 && w.is_finite() => w,
            _ => 0.0,
        };
        for pass in 0..SPREAD_PASSES {
            let mut changed = false;
            let mut one = |&(i, j, allowed): &(u32, u32, f64)| {
                let (i, j) = (i as usize, j as usize);
                let d = x[i] - x[j];
                let len = d.length();
                let target = allowed.max(before[i].distance(before[j]));
                if len.is_nan() || len <= target * (1.0 + SPREAD_SLACK) {
                    return;
                }
                let (wi, wj) = (weight(i), weight(j));
                if wi + wj <= 0.0 {
                    return;
                }
                if pass == 0 {
                    spread += 1;
                }
                let shorten = d * ((len - target) / (len * (wi + wj)));
                for (k, step) in [(i, -shorten * wi), (j, shorten * wj)] {
                    let step = step.clamp_length_max(SPREAD_MOVE * thickness(k));
                    let (from, to) = (x[k], x[k] + step);
                    if step == Vec3::ZERO || !clear(k, from, to) {
                        continue;
                    }
                    let ring = self.neighbours.get(k).map_or(&[][..], |n| &n[..]);
                    let x_now = &*x;
                    let crosses = |n: &u32| {
                        let other = x_now[*n as usize];
                        !edge_clear(to, other) && edge_clear(from, other)
                    };
                    if !ring.iter().any(crosses) {
                        x[k] = to;
                        changed = true;
                    }
                }
            };
            if pass % 2 == 0 {
                self.edges.iter().for_each(&mut one);
            } else {
                self.edges.iter().rev().for_each(&mut one);
            }
            if !changed {
                break;
            }
        }
        spread
    }
}

/// Whether vertex `k`'s straight way from `from` to `to` stays clear of the solids of
/// `stage`'s obstacles (see [`clear_of_obstacles`]) and ends no deeper in any obstacle's
/// contact layer than it starts.
pub(super) fn clear_of_layers(
    stage: &crate::collide::CollisionStage,
    k: usize,
    from: Vec3,
    to: Vec3,
) -> bool {
    way_clear(stage, from, to, Some(stage.thickness_of(k)))
}

/// Whether the straight way from `from` to `to` stays clear of the solids of `stage`'s
/// obstacles: `to` inside none, and the segment through no surface.
pub(super) fn clear_of_obstacles(
    stage: &crate::collide::CollisionStage,
    from: Vec3,
    to: Vec3,
) -> bool {
    way_clear(stage, from, to, None)
}

/// The way from `from` to `to` crosses no obstacle's surface and ends in no solid; with a
/// contact thickness `layer`, it also ends no deeper in any obstacle's contact layer than it
/// starts. Obstacles whose local bounds (grown by the layer) the way's box misses are skipped.
fn way_clear(
    stage: &crate::collide::CollisionStage,
    from: Vec3,
    to: Vec3,
    layer: Option<f64>,
) -> bool {
    let th = layer.unwrap_or(0.0);
    stage.obstacles().iter().all(|o| {
        let (a, b) = (
            o.pose.inverse_transform_point(from),
            o.pose.inverse_transform_point(to),
        );
        let (lo, hi) = o.local_bounds();
        if (a.min(b) - th).cmpgt(hi).any() || (a.max(b) + th).cmplt(lo).any() {
            return true;
        }
        if o.contains_local(b) || o.cast_local(a, b).is_some() || o.cast_local(b, a).is_some() {
            return false;
        }
        let depth = |p: Vec3| o.in_layer(p, th).map_or(0.0, |(_, gap)| gap);
        layer.is_none() || depth(b) <= depth(a) + LAYER_ROUND_OFF * th
    })
}

/// For every limited free vertex, its [`TETHERS`] nearest `anchors` by rest geodesic distance
/// (Dijkstra over the mesh edges from each anchor) as `(vertex, anchor, allowed distance)`.
fn tethers(
    neighbours: &[Vec<(u32, f64)>],
    limit: &[Option<f64>],
    anchors: &[u32],
) -> Vec<(u32, u32, f64)> {
    let n = neighbours.len();
    let mut is_anchor = vec![false; n];
    anchors
        .iter()
        .filter(|&&a| (a as usize) < n)
        .for_each(|&a| is_anchor[a as usize] = true);
    // Per vertex: its nearest anchors so far, (distance, anchor), at most TETHERS.
    let mut nearest: Vec<Vec<(f64, u32)>> = vec![Vec::new(); n];
    let mut dist = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    for &a in anchors.iter().filter(|&&a| (a as usize) < n) {
        dist.iter_mut().for_each(|d| *d = f64::INFINITY);
        done.iter_mut().for_each(|d| *d = false);
        dist[a as usize] = 0.0;
        let mut heap = BinaryHeap::new();
        heap.push(Reverse((Dist(0.0), a)));
        while let Some(Reverse((Dist(d), i))) = heap.pop() {
            let i = i as usize;
            if done[i] {
                continue;
            }
            done[i] = true;
            if !is_anchor[i] && limit[i].is_some() {
                let list = &mut nearest[i];
                list.push((d, a));
                list.sort_by(|p, q| p.0.total_cmp(&q.0));
                list.truncate(TETHERS);
            }
            for &(j, l) in &neighbours[i] {
                let e = d + l;
                if e < dist[j as usize] {
                    dist[j as usize] = e;
                    heap.push(Reverse((Dist(e), j)));
                }
            }
        }
    }
    let mut out = Vec::new();
    for (i, list) in nearest.iter().enumerate() {
        if let Some(s) = limit[i] {
            out.extend(list.iter().map(|&(d, a)| (i as u32, a, d * (1.0 + s))));
        }
    }
    out
}

/// A distance ordered by `total_cmp`, for the heap.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Dist(f64);

impl Eq for Dist {}

impl PartialOrd for Dist {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Dist {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Pose;

    /// A limit, positions, inverse masses and kinematic vertices.
    type Chain = (StrainLimit, Vec<Vec3>, Vec<f64>, Vec<(u32, Kinematic)>);

    /// A chain of `n` vertices along x, every edge of rest length 1 stretched to `stretch`,
    /// limited to 10 %; vertex 0 pinned when `pinned`.
    fn chain(n: usize, stretch: f64, pinned: bool) -> Chain {
        let s = 0.1;
        let mut neighbours = vec![Vec::new(); n];
        let mut edges = Vec::new();
        for i in 0..n as u32 - 1 {
            edges.push((i, i + 1, 1.0 + s, 1.0 + s + SLACK * s));
            neighbours[i as usize].push((i + 1, 1.0));
            neighbours[i as usize + 1].push((i, 1.0));
        }
        let limit = StrainLimit {
            edges,
            neighbours,
            limit: vec![Some(s); n],
        };
        let x = (0..n)
            .map(|i| Vec3::new(stretch * i as f64, 0.0, 0.0))
            .collect();
        let mut w = vec![1.0; n];
        let mut kinematic = Vec::new();
        if pinned {
            w[0] = 0.0;
            kinematic.push((0, Kinematic::Pinned(Vec3::ZERO)));
        }
        (limit, x, w, kinematic)
    }

    #[test]
    fn a_stretched_chain_ends_within_its_limit_and_keeps_its_momentum() {
        let (limit, mut x, w, k) = chain(6, 1.2, false);
        let x0 = x.clone();
        // Spreading apart at 1 m/s per edge.
        let v0: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new(i as f64 - 2.5, 0.0, 0.0))
            .collect();
        let mut v = v0.clone();
        let h = 0.01;
        let r = limit.apply(&mut Tethers::default(), &mut x, &mut v, &w, &k, h);
        assert_eq!(r.shortened, 5);
        assert_eq!(r.excess, 0.0);
        for e in 0..5 {
            let l = x[e].distance(x[e + 1]);
            assert!(l <= 1.1 + SLACK * 0.1 + 1e-12, "edge {e}: {l}");
        }
        // Equal masses moved in opposite pairs: the centre of mass and the momentum stay.
        let com: Vec3 = x.iter().copied().sum::<Vec3>() / 6.0;
        assert!((com.x - 1.2 * 5.0 / 2.0).abs() < 1e-9, "{com}");
        let p: Vec3 = v.iter().copied().sum();
        assert!(p.length() < 1e-9, "{p}");
        // The velocities moved with the positions over the substep, by at most the relative
        // speed the ends had (1 m/s here, where the moves over h are 10 m/s): no faster.
        for i in 0..6 {
            let dv = (v[i] - v0[i]).length();
            assert!(dv <= (x[i] - x0[i]).length() / h + 1e-9, "vertex {i}");
            assert!(v[i].length() <= v0[i].length() + 1e-9, "vertex {i}");
        }
    }

    /// The point load of a pin: a 40-vertex chain hanging from it, every edge 50 % over rest,
    /// is within its limit after one call (the tethers), where edge passes alone leave it far
    /// over (a correction crosses one ring per pass).
    #[test]
    fn a_chain_pulled_from_its_pin_is_held_by_the_tethers() {
        let (limit, mut x, w, k) = chain(40, 1.5, true);
        let x0 = x[0];
        // Moving away from the pin at 1 m/s.
        let mut v = vec![Vec3::X; 40];
        v[0] = Vec3::ZERO;
        let r = limit.apply(&mut Tethers::default(), &mut x, &mut v, &w, &k, 0.01);
        assert_eq!(x[0], x0, "the pin stays");
        assert_eq!(r.excess, 0.0);
        assert!(x[39].x <= 39.0 * 1.1 + 1e-9, "{}", x[39].x);
        assert!(
            v.iter().all(|v| v.x <= 1e-12),
            "nothing leaves the pin: {v:?}"
        );
        // Without tethers (no anchors), 32 edge passes leave the chain over its limit.
        let (free, mut x, w, _) = chain(40, 1.5, true);
        let r = free.apply(
            &mut Tethers::default(),
            &mut x,
            &mut vec![Vec3::ZERO; 40],
            &w,
            &[],
            0.01,
        );
        assert!(r.excess > 0.05, "{}", r.excess);
    }

    #[test]
    fn edges_within_the_limit_are_left_alone() {
        let (limit, mut x, w, k) = chain(3, 1.1, true);
        let mut v = vec![Vec3::X; 3];
        let x0 = x.clone();
        let r = limit.apply(&mut Tethers::default(), &mut x, &mut v, &w, &k, 0.01);
        assert_eq!(r, LimitPass::default());
        assert_eq!((x, v), (x0, vec![Vec3::X; 3]));
    }

    #[test]
    fn tethers_follow_the_rest_geodesic_to_the_nearest_anchors() {
        // A 3x3 grid pinned at two corners: each free vertex is tethered to both, at its rest
        // distance (the grid's diagonals give straight-line distances here).
        let mut c = Cloth::new();
        let panel = crate::cloth::Panel::grid("g", [2.0, 2.0], [3, 3], &Pose::IDENTITY);
        let material = crate::cloth::Material {
            strain_limit: Some(0.1),
            ..Default::default()
        };
        c.add_panel(panel, material);
        c.pin(0);
        c.pin(2);
        let limit = StrainLimit::of(&c).expect("a limited material");
        let mut cache = Tethers::default();
        let list = limit.tethers_for(&mut cache, &c.kinematic).to_vec();
        assert_eq!(list.len(), 7 * 2);
        for (i, a, allowed) in list {
            let rest = c.uv[i as usize].distance(c.uv[a as usize]);
            assert!(
                allowed >= 1.1 * rest - 1e-12,
                "{i} -> {a}: {allowed} vs {rest}"
            );
        }
        c.release(2);
        assert_eq!(
            limit.tethers_for(&mut cache, &c.kinematic).len(),
            8,
            "rebuilt for the one pin left"
        );
    }

    /// An edge a vertex-pass answer stretched past the bound: the answered end goes back along
    /// its move to the allowed length; where the way back is not clear, or the end was not
    /// answered, nothing moves.
    #[test]
    fn an_answer_past_the_bound_goes_back_along_its_move() {
        let bound = ResponseBound {
            edges: vec![(0, 1, 1.03)],
            neighbours: vec![vec![1], vec![0]],
        };
        let before = [Vec3::ZERO, Vec3::X];
        let answered = [Vec3::ZERO, Vec3::new(1.2, 0.1, 0.0)];
        let mut x = answered;
        assert_eq!(
            bound.hold_response(&before, &mut x, |k| k == 1, |_, _| true),
            1
        );
        assert!((x[0].distance(x[1]) - 1.03).abs() < 1e-12, "{x:?}");
        // On the way back: between the answer and where the pass found it.
        let (way, done) = (before[1] - answered[1], x[1] - answered[1]);
        assert!(way.cross(done).length() < 1e-12 && way.dot(done) > 0.0);
        for (deferred, clear) in [(false, true), (true, false)] {
            let mut x = answered;
            bound.hold_response(&before, &mut x, |_| deferred, |_, _| clear);
            assert_eq!(x, answered);
        }
    }

    /// A chain 0-1-2 whose end 0 an answer pushed 0.2 out: the spread brings every edge back
    /// to its allowed length by moving the free vertices along the chain, in moves of at most
    /// a quarter of their thickness; a kinematic end stays; a move that `clear` refuses, or that takes an edge
    /// through an obstacle, is not made.
    #[test]
    fn an_answer_past_the_bound_is_spread_along_the_cloth() {
        let bound = ResponseBound {
            edges: vec![(0, 1, 1.03), (1, 2, 1.03)],
            neighbours: vec![vec![1], vec![0, 2], vec![1]],
        };
        let before = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let answered = [Vec3::new(-0.2, 0.0, 0.0), Vec3::X, Vec3::X * 2.0];
        let inv_mass = [1.0, 1.0, 0.0];
        let (all, none) = (|_: usize, _: Vec3, _: Vec3| true, |_: Vec3, _: Vec3| true);
        let mut x = answered;
        let n = bound.spread_response(&before, &mut x, &inv_mass, all, none, |_| 0.2);
        assert!(n >= 1, "an edge past the bound on the first pass");
        for (a, b) in [(0, 1), (1, 2)] {
            let len = x[a].distance(x[b]);
            assert!(len <= 1.03 * (1.0 + SPREAD_SLACK) + 1e-12, "{a}-{b}: {len}");
        }
        assert_eq!(x[2], answered[2], "a kinematic vertex stays");
        // Refused ways and edges through an obstacle: nothing moves.
        let mut x = answered;
        bound.spread_response(&before, &mut x, &inv_mass, |_, _, _| false, none, |_| 0.2);
        assert_eq!(x, answered);
        let mut x = answered;
        let through = |a: Vec3, _: Vec3| a == answered[0] || a == answered[1];
        bound.spread_response(&before, &mut x, &inv_mass, all, through, |_| 0.2);
        assert_eq!(x, answered);
    }
}
