//! Continuous collision detection over one step with linear vertex motion, `t` in `[0, 1]`.
//!
//! Two families:
//! - `*_ccd`: coplanarity-event tests. The four points are coplanar where the cubic
//!   `((b-a) x (c-a)) . (p-a)` vanishes; at each root (found by [`super::cubic`]) the static
//!   distance must be `<= eta`. Exact crossing times; `eta` is only an inside tolerance.
//!   Motion that stays coplanar (including parallel edges and zero-area triangles) makes the
//!   cubic vanish identically and falls back to the thickness test.
//! - `*_ccd_thick`: report the earliest `t` at which the distance is `<= eta` (conservative
//!   advancement, [`super::sweep`]): no false negatives, rare false positives within
//!   `THICK_ACCEPT_REL`/`SLACK_REL` of the threshold.
//!
//! Every test first rejects on swept bounding boxes inflated by `eta`. All tolerances add a
//! numerical slack of `SLACK_REL` times the largest absolute coordinate, so touching contacts
//! at exactly `t = 0`, `t = 1`, on edges and vertices are reported.

use super::closest::{point_triangle_closest, segment_segment_closest};
use super::cubic::{self, Cubic};
use super::sweep::earliest_within;
use crate::Vec3;

/// Numerical slack on distances, relative to the largest absolute coordinate involved.
pub const SLACK_REL: f64 = 1e-12;
/// Thick tests stop at the first time the distance is within `eta (1 + THICK_ACCEPT_REL) + slack`.
pub const THICK_ACCEPT_REL: f64 = 1e-6;

/// A vertex-triangle contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VtHit {
    /// Time of impact in `[0, 1]`.
    pub t: f64,
    /// Barycentric coordinates of the contact point on the triangle at `t` (sum to 1).
    pub bary: [f64; 3],
    /// Unit contact normal pointing from the triangle towards the side the vertex came from.
    pub normal: Vec3,
}

/// An edge-edge contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EeHit {
    /// Time of impact in `[0, 1]`.
    pub t: f64,
    /// Parameter on edge `p` (`p[0] + s (p[1] - p[0])`) at `t`.
    pub s: f64,
    /// Parameter on edge `q` at `t`.
    pub u: f64,
    /// Unit contact normal pointing from edge `q` towards the side edge `p` came from.
    pub normal: Vec3,
}

#[inline]
fn lerp(x0: Vec3, x1: Vec3, t: f64) -> Vec3 {
    if t >= 1.0 {
        x1
    } else {
        x0 + (x1 - x0) * t
    }
}

#[inline]
fn bounds(pts: &[Vec3]) -> (Vec3, Vec3) {
    pts.iter()
        .fold((pts[0], pts[0]), |(lo, hi), &x| (lo.min(x), hi.max(x)))
}

/// Scale numbers of one query: `(slack, extent, max_abs_coordinate)` and the box overlap verdict.
struct Scale {
    slack: f64,
    extent: f64,
    coord: f64,
    overlap: bool,
}

#[inline]
fn scale_and_overlap(a: &[Vec3], b: &[Vec3], eta: f64) -> Scale {
    let (lo_a, hi_a) = bounds(a);
    let (lo_b, hi_b) = bounds(b);
    let coord = lo_a
        .abs()
        .max(hi_a.abs())
        .max(lo_b.abs())
        .max(hi_b.abs())
        .max_element();
    let extent = (hi_a.max(hi_b) - lo_a.min(lo_b)).max_element();
    let slack = SLACK_REL * coord;
    let m = Vec3::splat(eta + slack);
    let overlap = !((lo_a - m).cmpgt(hi_b).any() || (lo_b - m).cmpgt(hi_a).any());
    Scale {
        slack,
        extent,
        coord,
        overlap,
    }
}

/// [`scale_and_overlap`] of a point path and a moving triangle; `None` when their boxes are
/// farther apart than `eta`.
fn vt_scale(p0: Vec3, p1: Vec3, tri0: [Vec3; 3], tri1: [Vec3; 3], eta: f64) -> Option<Scale> {
    let s = scale_and_overlap(
        &[p0, p1],
        &[tri0[0], tri0[1], tri0[2], tri1[0], tri1[1], tri1[2]],
        eta,
    );
    s.overlap.then_some(s)
}

/// [`scale_and_overlap`] of two moving edges; `None` when their boxes are farther apart than `eta`.
fn ee_scale(p0: [Vec3; 2], p1: [Vec3; 2], q0: [Vec3; 2], q1: [Vec3; 2], eta: f64) -> Option<Scale> {
    let s = scale_and_overlap(
        &[p0[0], p0[1], p1[0], p1[1]],
        &[q0[0], q0[1], q1[0], q1[1]],
        eta,
    );
    s.overlap.then_some(s)
}

/// Coefficients of `(A(t) x B(t)) . C(t)` for `X(t) = X0 + t Xv`.
#[inline]
fn triple_cubic(a0: Vec3, av: Vec3, b0: Vec3, bv: Vec3, c0: Vec3, cv: Vec3) -> Cubic {
    let n0 = a0.cross(b0);
    let n1 = av.cross(b0) + a0.cross(bv);
    let n2 = av.cross(bv);
    [
        n0.dot(c0),
        n1.dot(c0) + n0.dot(cv),
        n2.dot(c0) + n1.dot(cv),
        n2.dot(cv),
    ]
}

/// Rounding bound on the cubic: its terms are products of three relative vectors of length
/// at most `extent`, each carrying an absolute error of a few ulps of `coord`.
#[inline]
fn cubic_tol(s: &Scale) -> f64 {
    32.0 * f64::EPSILON * s.extent * s.extent * (s.extent + s.coord)
}

fn unit_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let l = v.length();
    if l > f64::MIN_POSITIVE && l.is_finite() {
        v / l
    } else {
        fallback
    }
}

/// Contact normal: the separation direction if the contact has a meaningful gap, else the
/// plane normal `n` oriented towards the starting separation `sep0` (or against the relative
/// velocity `rel_v`); for a degenerate plane, `sep0`, `-rel_v`, or `perp`.
fn contact_normal(gap: Vec3, min_gap: f64, n: Vec3, sep0: Vec3, rel_v: Vec3, perp: Vec3) -> Vec3 {
    if gap.length() > min_gap {
        return unit_or(gap, perp);
    }
    let fallback = unit_or(sep0, unit_or(-rel_v, perp));
    let n = unit_or(n, Vec3::ZERO);
    if n == Vec3::ZERO {
        return fallback;
    }
    let side = n.dot(sep0);
    let side = if side != 0.0 { side } else { -n.dot(rel_v) };
    if side < 0.0 {
        -n
    } else {
        n
    }
}

fn vt_hit(p: [Vec3; 2], t0: [Vec3; 3], t1: [Vec3; 3], t: f64, min_gap: f64) -> VtHit {
    let pt = lerp(p[0], p[1], t);
    let [a, b, c] = [0, 1, 2].map(|i| lerp(t0[i], t1[i], t));
    let (q, bary) = point_triangle_closest(pt, a, b, c);
    let at = |tri: [Vec3; 3]| tri[0] * bary[0] + tri[1] * bary[1] + tri[2] * bary[2];
    let (q0, q1) = (at(t0), at(t1));
    let normal = contact_normal(
        pt - q,
        min_gap,
        (b - a).cross(c - a),
        p[0] - q0,
        (p[1] - p[0]) - (q1 - q0),
        (b - a).any_orthonormal_vector(),
    );
    VtHit { t, bary, normal }
}

fn ee_hit(p: [[Vec3; 2]; 2], q: [[Vec3; 2]; 2], t: f64, min_gap: f64) -> EeHit {
    let [pa, pb, qa, qb] = [(0, 0), (0, 1), (1, 0), (1, 1)].map(|(e, i)| {
        let x = if e == 0 { p } else { q };
        lerp(x[0][i], x[1][i], t)
    });
    let (s, u, cp, cq) = segment_segment_closest(pa, pb, qa, qb);
    // Closest at an end of either edge, the contact is that end point's with the other
    // segment: its separation is the normal wherever it is meaningful (over half the gap). The
    // plane normal of the two edges is not: a cloth column draped over a rod axis at one
    // vertex gets opposite normals from its two edges there, and the feature passes would push
    // that vertex centimetres back and forth within a substep however short, until it blows up
    // (drape_bot's forearm lifting a towel at its velocity limit); a cloth edge millimetres
    // above a box corner (the end of a box edge), its plane normal with that edge nearly
    // horizontal, reads a far smaller gap along it and would be pushed sideways every substep
    // (a cloth resting on drape_bot's palm). Where the closest points lie inside both edges the
    // two normals agree.
    let min_gap = if s <= 0.0 || s >= 1.0 || u <= 0.0 || u >= 1.0 {
        0.5 * min_gap
    } else {
        min_gap
    };
    let on = |e: [Vec3; 2], w: f64| e[0] + (e[1] - e[0]) * w;
    let sep0 = on(p[0], s) - on(q[0], u);
    let sep1 = on(p[1], s) - on(q[1], u);
    let normal = contact_normal(
        cp - cq,
        min_gap,
        (pb - pa).cross(qb - qa),
        sep0,
        sep1 - sep0,
        unit_or(pb - pa, Vec3::X).any_orthonormal_vector(),
    );
    EeHit { t, s, u, normal }
}

/// Earliest coplanarity event of point `p` (at `p0` then `p1`) with triangle `tri0 -> tri1`
/// at which the point is within `eta` of the triangle.
///
/// `tri0`/`tri1` are the triangle's vertices at `t = 0` and `t = 1`. Coplanar-throughout
/// motion (and zero-area triangles) defers to [`vertex_triangle_ccd_thick`].
pub fn vertex_triangle_ccd(
    p0: Vec3,
    p1: Vec3,
    tri0: [Vec3; 3],
    tri1: [Vec3; 3],
    eta: f64,
) -> Option<VtHit> {
    let s = vt_scale(p0, p1, tri0, tri1, eta)?;
    let (a0, a1) = (tri0[0], tri1[0]);
    let (e0, e1) = (tri0[1] - a0, tri1[1] - a1);
    let (f0, f1) = (tri0[2] - a0, tri1[2] - a1);
    let (g0, g1) = (p0 - a0, p1 - a1);
    let cubic = triple_cubic(e0, e1 - e0, f0, f1 - f0, g0, g1 - g0);
    let ftol = cubic_tol(&s);
    if cubic.iter().all(|k| k.abs() <= 4.0 * ftol) {
        return vertex_triangle_ccd_thick(p0, p1, tri0, tri1, eta);
    }
    let (times, n) = cubic::candidate_times(&cubic, ftol);
    let limit = eta + s.slack;
    times[..n].iter().find_map(|&t| {
        let pt = lerp(p0, p1, t);
        let [a, b, c] = [0, 1, 2].map(|i| lerp(tri0[i], tri1[i], t));
        let (q, _) = point_triangle_closest(pt, a, b, c);
        (pt.distance(q) <= limit).then(|| vt_hit([p0, p1], tri0, tri1, t, limit.max(0.5 * eta)))
    })
}

/// Earliest `t` in `[0, 1]` at which point `p` is within `eta` of the moving triangle.
///
/// Never misses a contact (up to `SLACK_REL` rounding). The reported time is the first at which
/// the distance is within `eta (1 + THICK_ACCEPT_REL) + slack` (or up to `TIME_TOL` earlier), so
/// a distance that only comes that close to `eta` is a (harmless) false positive.
pub fn vertex_triangle_ccd_thick(
    p0: Vec3,
    p1: Vec3,
    tri0: [Vec3; 3],
    tri1: [Vec3; 3],
    eta: f64,
) -> Option<VtHit> {
    let s = vt_scale(p0, p1, tri0, tri1, eta)?;
    let vp = p1 - p0;
    let lip = (0..3)
        .map(|i| (vp - (tri1[i] - tri0[i])).length())
        .fold(0.0, f64::max)
        * (1.0 + 1e-12);
    let limit = eta + s.slack;
    let dist = |t: f64| {
        let pt = lerp(p0, p1, t);
        let [a, b, c] = [0, 1, 2].map(|i| lerp(tri0[i], tri1[i], t));
        point_triangle_closest(pt, a, b, c).0.distance(pt)
    };
    let t = earliest_within(dist, lip, eta, limit + THICK_ACCEPT_REL * eta)?;
    Some(vt_hit([p0, p1], tri0, tri1, t, limit.max(0.5 * eta)))
}

/// Earliest coplanarity event of edge `p` (`p0` at `t = 0`, `p1` at `t = 1`, each the two
/// endpoints) with edge `q` at which the edges are within `eta` of each other.
///
/// Coplanar-throughout motion (parallel or collinear edges, edges in a common moving plane)
/// defers to [`edge_edge_ccd_thick`].
pub fn edge_edge_ccd(
    p0: [Vec3; 2],
    p1: [Vec3; 2],
    q0: [Vec3; 2],
    q1: [Vec3; 2],
    eta: f64,
) -> Option<EeHit> {
    let s = ee_scale(p0, p1, q0, q1, eta)?;
    let (e0, e1) = (p0[1] - p0[0], p1[1] - p1[0]);
    let (f0, f1) = (q0[1] - q0[0], q1[1] - q1[0]);
    let (g0, g1) = (q0[0] - p0[0], q1[0] - p1[0]);
    let cubic = triple_cubic(e0, e1 - e0, f0, f1 - f0, g0, g1 - g0);
    let ftol = cubic_tol(&s);
    if cubic.iter().all(|k| k.abs() <= 4.0 * ftol) {
        return edge_edge_ccd_thick(p0, p1, q0, q1, eta);
    }
    let (times, n) = cubic::candidate_times(&cubic, ftol);
    let limit = eta + s.slack;
    times[..n].iter().find_map(|&t| {
        let (_, _, cp, cq) = segment_segment_closest(
            lerp(p0[0], p1[0], t),
            lerp(p0[1], p1[1], t),
            lerp(q0[0], q1[0], t),
            lerp(q0[1], q1[1], t),
        );
        (cp.distance(cq) <= limit).then(|| ee_hit([p0, p1], [q0, q1], t, limit.max(0.5 * eta)))
    })
}

/// Earliest `t` in `[0, 1]` at which edges `p` and `q` come within `eta` of each other.
/// Same guarantees as [`vertex_triangle_ccd_thick`].
pub fn edge_edge_ccd_thick(
    p0: [Vec3; 2],
    p1: [Vec3; 2],
    q0: [Vec3; 2],
    q1: [Vec3; 2],
    eta: f64,
) -> Option<EeHit> {
    let s = ee_scale(p0, p1, q0, q1, eta)?;
    let vp = [p1[0] - p0[0], p1[1] - p0[1]];
    let vq = [q1[0] - q0[0], q1[1] - q0[1]];
    let lip = vp
        .iter()
        .flat_map(|a| vq.iter().map(move |b| (*a - *b).length()))
        .fold(0.0, f64::max)
        * (1.0 + 1e-12);
    let limit = eta + s.slack;
    let dist = |t: f64| {
        let (_, _, cp, cq) = segment_segment_closest(
            lerp(p0[0], p1[0], t),
            lerp(p0[1], p1[1], t),
            lerp(q0[0], q1[0], t),
            lerp(q0[1], q1[1], t),
        );
        cp.distance(cq)
    };
    let t = earliest_within(dist, lip, eta, limit + THICK_ACCEPT_REL * eta)?;
    Some(ee_hit([p0, p1], [q0, q1], t, limit.max(0.5 * eta)))
}
