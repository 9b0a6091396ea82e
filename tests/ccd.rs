//! CCD tests: analytic times of impact, literature edge cases, and randomized sweeps against a
//! brute-force time-sampling reference (no false negatives allowed).

use drape::collide::narrow::{
    edge_edge_ccd, edge_edge_ccd_thick, point_triangle_closest, segment_segment_closest,
    vertex_triangle_ccd, vertex_triangle_ccd_thick, EeHit, VtHit, THICK_ACCEPT_REL,
};
use drape::Vec3;

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

const TRI: [Vec3; 3] = [
    Vec3::new(0., 0., 0.),
    Vec3::new(1., 0., 0.),
    Vec3::new(0., 1., 0.),
];

/// Time tolerance of the thickness test (conservative advancement) plus rounding.
const T_TOL: f64 = 1e-9;

fn vt_both(p0: Vec3, p1: Vec3, t0: [Vec3; 3], t1: [Vec3; 3], eta: f64) -> Option<VtHit> {
    let hit = vertex_triangle_ccd(p0, p1, t0, t1, eta);
    // The thickness test must never report later than a coplanarity contact.
    if let Some(h) = hit {
        let th = vertex_triangle_ccd_thick(p0, p1, t0, t1, eta)
            .unwrap_or_else(|| panic!("thick test missed a coplanar contact at {}", h.t));
        assert!(
            th.t <= h.t + T_TOL,
            "thick {} later than cubic {}",
            th.t,
            h.t
        );
    }
    hit
}

fn assert_vt(hit: Option<VtHit>, t: f64, bary: [f64; 3], normal: Vec3, tol: f64) {
    let h = hit.expect("expected a hit");
    assert!((h.t - t).abs() <= tol, "t = {} want {t}", h.t);
    for i in 0..3 {
        assert!(
            (h.bary[i] - bary[i]).abs() <= 1e-6,
            "bary {:?} want {bary:?}",
            h.bary
        );
    }
    assert!(
        h.normal.distance(normal) < 1e-6,
        "normal {} want {normal}",
        h.normal
    );
}

// ---------------------------------------------------------------- analytic cases

#[test]
fn point_through_static_triangle() {
    let hit = vt_both(v(0.2, 0.2, 1.), v(0.2, 0.2, -1.), TRI, TRI, 0.0);
    assert_vt(hit, 0.5, [0.6, 0.2, 0.2], Vec3::Z, 1e-14);
    // From below: normal flips to the side the point came from.
    let hit = vt_both(v(0.2, 0.2, -1.), v(0.2, 0.2, 3.), TRI, TRI, 0.0);
    assert_vt(hit, 0.25, [0.6, 0.2, 0.2], -Vec3::Z, 1e-14);
}

#[test]
fn triangle_onto_static_point() {
    let down = TRI.map(|x| x - Vec3::Z);
    let up = TRI.map(|x| x + 0.5 * Vec3::Z);
    let hit = vt_both(v(0.25, 0.25, 0.), v(0.25, 0.25, 0.), down, up, 0.0);
    assert_vt(hit, 2.0 / 3.0, [0.5, 0.25, 0.25], Vec3::Z, 1e-14);
}

#[test]
fn both_moving() {
    let t0 = TRI.map(|x| x - 0.5 * Vec3::Z);
    let t1 = TRI.map(|x| x + 0.5 * Vec3::Z + v(0.1, 0., 0.));
    // p z = 1 - 2t, triangle z = -0.5 + t: meet at t = 0.5 where the triangle has moved 0.05 in x.
    let hit = vt_both(v(0.3, 0.1, 1.), v(0.3, 0.1, -1.), t0, t1, 0.0);
    assert_vt(hit, 0.5, [0.65, 0.25, 0.1], Vec3::Z, 1e-14);
}

#[test]
fn tilting_triangle_known_root() {
    // c swings from below to above the x axis: plane z = y (2t - 1). The point follows
    // z = 0.3 - 0.2 t at y = 0.5, so 0.3 - 0.2 t = t - 0.5 gives t = 2/3, where
    // c = (0, 1, 1/3) and the point sits at barycentrics (0.3, 0.2, 0.5).
    let t0 = [TRI[0], TRI[1], v(0., 1., -1.)];
    let t1 = [TRI[0], TRI[1], v(0., 1., 1.)];
    let hit = vt_both(v(0.2, 0.5, 0.3), v(0.2, 0.5, 0.1), t0, t1, 0.0).expect("hit");
    assert!((hit.t - 2.0 / 3.0).abs() < 1e-14, "{}", hit.t);
    for (got, want) in hit.bary.iter().zip([0.3, 0.2, 0.5]) {
        assert!((got - want).abs() < 1e-12);
    }
    // Plane normal at t = 2/3 is (0, -1/3, 1)/|.|, oriented towards where the point started (above).
    let n = v(0., -1. / 3., 1.).normalize();
    assert!(hit.normal.distance(n) < 1e-12, "{}", hit.normal);
}

#[test]
fn edge_edge_analytic() {
    // p along x at height 1 - 2t, q along y at height 0: cross at t = 0.5, midpoints.
    let p0 = [v(-1., 0., 1.), v(1., 0., 1.)];
    let p1 = [v(-1., 0., -1.), v(1., 0., -1.)];
    let q = [v(0., -1., 0.), v(0., 1., 0.)];
    let h = edge_edge_ccd(p0, p1, q, q, 0.0).expect("hit");
    assert!((h.t - 0.5).abs() < 1e-14 && (h.s - 0.5).abs() < 1e-12 && (h.u - 0.5).abs() < 1e-12);
    assert!(h.normal.distance(Vec3::Z) < 1e-12);
    // Shift q past the end of p: miss.
    let q_far = q.map(|x| x + v(1.5, 0., 0.));
    assert!(edge_edge_ccd(p0, p1, q_far, q_far, 0.0).is_none());
    assert!(edge_edge_ccd_thick(p0, p1, q_far, q_far, 0.4).is_none());
    // ... but within thickness 0.6 of it (gap 0.5 at t = 0.5, first reaches 0.6 earlier).
    let h = edge_edge_ccd_thick(p0, p1, q_far, q_far, 0.6).expect("thick hit");
    let d = |t: f64| (0.5f64.powi(2) + (1.0 - 2.0 * t).powi(2)).sqrt();
    // Stops within the documented acceptance band above eta, never past the first contact.
    let t_star = (1.0 - (0.6f64.powi(2) - 0.25).sqrt()) / 2.0;
    assert!(h.t <= t_star + 1e-12, "t {} > {t_star}", h.t);
    assert!(
        d(h.t) <= 0.6 * (1.0 + THICK_ACCEPT_REL) + 1e-12,
        "t {} d {}",
        h.t,
        d(h.t)
    );
}

/// A cloth edge 8 mm above a box corner, the end of a box edge that leaves the corner down and
/// sideways: the contact is the corner's with the cloth edge, and its normal the separation
/// (up), not the two edges' plane normal (45 degrees off, along which the gap reads 5.7 mm and a
/// push moved the cloth sideways).
#[test]
fn edge_edge_closest_at_an_end_of_the_second_edge_takes_the_separation() {
    let p = [v(0.0, -0.01, 0.008), v(0.0, 0.01, 0.008)];
    let q = [v(0.0, 0.0, 0.0), v(0.1, 0.0, -0.1)];
    let h = edge_edge_ccd_thick(p, p, q, q, 0.0081).expect("within the contact distance");
    assert!(h.u.abs() < 1e-12, "u {}", h.u);
    assert!(h.normal.distance(Vec3::Z) < 1e-9, "normal {:?}", h.normal);
}

#[test]
fn thick_vertex_triangle_first_time_of_approach() {
    // Point descending above the face: distance 1 - 2t reaches eta = 0.1 at t = 0.45.
    let h =
        vertex_triangle_ccd_thick(v(0.2, 0.2, 1.), v(0.2, 0.2, -1.), TRI, TRI, 0.1).expect("hit");
    assert!((h.t - 0.45).abs() < T_TOL && h.t <= 0.45 + 1e-15, "{}", h.t);
    assert!(h.normal.distance(Vec3::Z) < 1e-12);
    // Passing beside the triangle at 0.05 from vertex b: thick sees it, cubic does not.
    let (p0, p1) = (v(1.05, 0., 1.), v(1.05, 0., -1.));
    assert!(vertex_triangle_ccd(p0, p1, TRI, TRI, 0.01).is_none());
    assert!(vertex_triangle_ccd_thick(p0, p1, TRI, TRI, 0.01).is_none());
    let h = vertex_triangle_ccd_thick(p0, p1, TRI, TRI, 0.1).expect("hit");
    assert_eq!(h.bary, [0., 1., 0.]);
    // Gap sqrt(0.05^2 + z^2) = 0.1 first at z = sqrt(0.0075); the hit may stop early within
    // the acceptance band (gap at most 0.1 (1 + THICK_ACCEPT_REL)).
    let t_star = (1.0 - 0.0075_f64.sqrt()) / 2.0;
    let gap = (0.05f64.powi(2) + (1.0 - 2.0 * h.t).powi(2)).sqrt();
    assert!(
        h.t <= t_star + 1e-12 && gap <= 0.1 * (1.0 + THICK_ACCEPT_REL) + 1e-12,
        "{}",
        h.t
    );
}

// ---------------------------------------------------------------- literature edge cases

#[test]
fn zero_area_triangle() {
    let needle = [v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.)];
    let h = vt_both(v(1.5, 0., 1.), v(1.5, 0., -1.), needle, needle, 0.0).expect("hit");
    assert!((h.t - 0.5).abs() < T_TOL, "{}", h.t);
    assert!(
        (h.bary[1] - 0.5).abs() < 1e-6 && (h.bary[2] - 0.5).abs() < 1e-6,
        "{:?}",
        h.bary
    );
    assert!(vt_both(v(1.5, 0.1, 1.), v(1.5, 0.1, -1.), needle, needle, 0.0).is_none());
    let point_tri = [v(0.5, 0.5, 0.5); 3];
    assert!(vt_both(v(0., 0., 0.), v(1., 1., 1.), point_tri, point_tri, 0.0).is_some());
}

#[test]
fn parallel_edges() {
    let p0 = [v(0., 0., 1.), v(2., 0., 1.)];
    let p1 = [v(0., 0., -1.), v(2., 0., -1.)];
    let q = [v(1., 0., 0.), v(3., 0., 0.)];
    let h = edge_edge_ccd(p0, p1, q, q, 0.0).expect("overlapping parallel edges collide");
    assert!((h.t - 0.5).abs() < T_TOL, "{}", h.t);
    let q_far = q.map(|x| x + v(1.5, 0., 0.));
    assert!(edge_edge_ccd(p0, p1, q_far, q_far, 0.0).is_none());
    // Parallel at constant distance 1e-3: inside eta = 2e-3 from the start, never with 5e-4.
    let r = q.map(|x| x + v(0., 1e-3, 0.));
    assert_eq!(
        edge_edge_ccd_thick(p0, p1, r, r, 2e-3).map(|h| h.t > 0.0),
        Some(true)
    );
    let r0 = p0.map(|x| x + v(0., 1e-3, 0.));
    let r1 = p1.map(|x| x + v(0., 1e-3, 0.));
    assert!(edge_edge_ccd(p0, p1, r0, r1, 5e-4).is_none());
    assert_eq!(edge_edge_ccd(p0, p1, r0, r1, 2e-3).map(|h| h.t), Some(0.0));
}

#[test]
fn near_parallel_edges() {
    let e = 1e-9;
    let p0 = [v(-1., -e, 1.), v(1., e, 1.)];
    let p1 = [v(-1., -e, -1.), v(1., e, -1.)];
    let q = [v(-1., e, 0.), v(1., -e, 0.)];
    let h = edge_edge_ccd(p0, p1, q, q, 0.0).expect("near-parallel crossing");
    assert!(
        (h.t - 0.5).abs() < 1e-9 && (h.s - 0.5).abs() < 1e-6,
        "{h:?}"
    );
}

#[test]
fn coplanar_throughout_motion() {
    // Point sliding in the triangle's plane into its edge at x = 0.
    let h = vt_both(v(-1., 0.2, 0.), v(1., 0.2, 0.), TRI, TRI, 0.0).expect("in-plane entry");
    assert!((h.t - 0.5).abs() < T_TOL, "{}", h.t);
    assert!(h.bary[0] > 0.79 && h.bary[2] > 0.19);
    assert!(vt_both(v(-1., 1.2, 0.), v(1., 1.2, 0.), TRI, TRI, 0.0).is_none());
    // Two edges in the z = 0 plane: a vertical edge sliding along x across a horizontal one.
    let p0 = [v(-1., -1., 0.), v(-1., 1., 0.)];
    let p1 = [v(1., -1., 0.), v(1., 1., 0.)];
    let q = [v(0., 0., 0.), v(0.5, 0., 0.)];
    let h = edge_edge_ccd(p0, p1, q, q, 0.0).expect("in-plane edge crossing");
    assert!(
        (h.t - 0.5).abs() < T_TOL && (h.s - 0.5).abs() < 1e-6,
        "{h:?}"
    );
}

#[test]
fn grazing_contacts() {
    // Passing exactly through edge ab, then 1e-9 outside it.
    let h = vt_both(v(0.5, 0., 1.), v(0.5, 0., -1.), TRI, TRI, 0.0).expect("edge graze");
    assert!((h.t - 0.5).abs() < 1e-14 && h.bary[2].abs() < 1e-12);
    assert!(vt_both(v(0.5, -1e-9, 1.), v(0.5, -1e-9, -1.), TRI, TRI, 0.0).is_none());
    assert!(vt_both(v(0.5, -1e-9, 1.), v(0.5, -1e-9, -1.), TRI, TRI, 2e-9).is_some());
    // Double root: the tilting plane (z = y (2t - 1)) touches the point at t = 0.5 without
    // crossing it, f(t) = 0.8 (t - 0.5)^2.
    let t0 = [TRI[0], TRI[1], v(0., 1., -1.)];
    let t1 = [TRI[0], TRI[1], v(0., 1., 1.)];
    let h = vt_both(v(0.2, 0.7, -0.5), v(0.2, 0.3, 0.5), t0, t1, 0.0).expect("tangential touch");
    assert!((h.t - 0.5).abs() < 1e-6, "{}", h.t);
}

#[test]
fn through_vertex_and_edge_midpoint() {
    let h = vt_both(v(0., 0., 1.), v(0., 0., -1.), TRI, TRI, 0.0).expect("through vertex a");
    assert!((h.t - 0.5).abs() < 1e-14 && (h.bary[0] - 1.0).abs() < 1e-12);
    let h = vt_both(v(0.5, 0.5, 1.), v(0.5, 0.5, -1.), TRI, TRI, 0.0).expect("through bc midpoint");
    assert!((h.bary[1] - 0.5).abs() < 1e-12 && (h.bary[2] - 0.5).abs() < 1e-12);
    // Edge through an edge endpoint (a vertex-vertex event between two edges).
    let p0 = [v(0., 0., 1.), v(1., 1., 1.)];
    let p1 = [v(0., 0., -1.), v(1., 1., -1.)];
    let q = [v(0., 0., 0.), v(-1., 1., 0.)];
    let h = edge_edge_ccd(p0, p1, q, q, 0.0).expect("endpoint touch");
    assert!(
        (h.t - 0.5).abs() < 1e-14 && h.s.abs() < 1e-12 && h.u.abs() < 1e-12,
        "{h:?}"
    );
}

#[test]
fn contact_at_exactly_t0_and_t1() {
    // On the face at t = 0, moving away.
    let h = vt_both(v(0.2, 0.2, 0.), v(0.2, 0.2, 1.), TRI, TRI, 0.0).expect("t = 0");
    assert_eq!(h.t, 0.0);
    // Arriving on the face at exactly t = 1.
    let h = vt_both(v(0.2, 0.2, 1.), v(0.2, 0.2, 0.), TRI, TRI, 0.0).expect("t = 1");
    assert_eq!(h.t, 1.0);
    assert!(h.normal.distance(Vec3::Z) < 1e-12);
    // Edges touching at t = 1 and at t = 0.
    let q = [v(0., -1., 0.), v(0., 1., 0.)];
    let p_top = [v(-1., 0., 1.), v(1., 0., 1.)];
    let p_on = [v(-1., 0., 0.), v(1., 0., 0.)];
    assert_eq!(
        edge_edge_ccd(p_top, p_on, q, q, 0.0).map(|h| h.t),
        Some(1.0)
    );
    assert_eq!(
        edge_edge_ccd(p_on, p_top, q, q, 0.0).map(|h| h.t),
        Some(0.0)
    );
    assert_eq!(
        edge_edge_ccd_thick(p_on, p_top, q, q, 0.0).map(|h| h.t),
        Some(0.0)
    );
    // Thick: gap exactly eta at t = 1.
    let h = vertex_triangle_ccd_thick(v(0.2, 0.2, 1.), v(0.2, 0.2, 0.1), TRI, TRI, 0.1)
        .expect("t = 1 thick");
    assert!((h.t - 1.0).abs() < T_TOL);
}

#[test]
fn tiny_motion_and_large_coordinates() {
    for offset in [Vec3::ZERO, v(1e3, -1e3, 1e3)] {
        let tri = TRI.map(|x| x + offset);
        // 2e-9 of motion across the plane.
        let h = vt_both(
            v(0.2, 0.2, 1e-9) + offset,
            v(0.2, 0.2, -1e-9) + offset,
            tri,
            tri,
            0.0,
        )
        .unwrap_or_else(|| panic!("tiny motion missed at offset {offset}"));
        assert!((h.t - 0.5).abs() < 1e-3, "{}", h.t);
        // A 1e-9 motion that stays 1e-6 above: no contact.
        let above = v(0.2, 0.2, 1e-6) + offset;
        assert!(vt_both(above, above + v(0., 0., -1e-9), tri, tri, 0.0).is_none());
        // Edge-edge at the same scales.
        let q = [v(0., -1., 0.) + offset, v(0., 1., 0.) + offset];
        let p0 = [v(-1., 0., 1e-9) + offset, v(1., 0., 1e-9) + offset];
        let p1 = [v(-1., 0., -1e-9) + offset, v(1., 0., -1e-9) + offset];
        let h = edge_edge_ccd(p0, p1, q, q, 0.0).expect("tiny ee");
        assert!((h.t - 0.5).abs() < 1e-3, "{}", h.t);
    }
    // Large everything: triangle of size 1e3 crossed by a point moving 2e3.
    let big = TRI.map(|x| x * 1e3);
    let h = vt_both(v(200., 200., 1e3), v(200., 200., -1e3), big, big, 0.0).expect("large");
    assert!((h.t - 0.5).abs() < 1e-12);
}

#[test]
fn swept_box_early_out_respects_eta() {
    let (p0, p1) = (v(0.2, 0.2, 0.3), v(0.2, 0.2, 0.25));
    assert!(vertex_triangle_ccd_thick(p0, p1, TRI, TRI, 0.2).is_none());
    assert!(vertex_triangle_ccd_thick(p0, p1, TRI, TRI, 0.26).is_some());
}

// ---------------------------------------------------------------- randomized sweeps

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn s(&mut self) -> f64 {
        2.0 * self.f() - 1.0
    }
    fn vec(&mut self, r: f64) -> Vec3 {
        v(self.s(), self.s(), self.s()) * r
    }
}

const SAMPLES: usize = 2000;

fn lerp(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    a + (b - a) * t
}

/// Brute-force reference over sampled times.
struct Reference {
    /// First sample time where the distance is below `eta - margin`.
    first_thick: Option<f64>,
    /// First sign change of the coplanarity volume (refined by bisection) where the distance
    /// at the crossing is below `eta - margin`.
    first_cross: Option<f64>,
    /// Minimum distance (sampled, then refined by golden section around the best sample).
    min_dist: f64,
    /// Minimum distance at any crossing.
    min_cross_dist: f64,
}

fn reference(
    dist: impl Fn(f64) -> f64,
    vol: impl Fn(f64) -> f64,
    eta: f64,
    margin: f64,
) -> Reference {
    let h = 1.0 / SAMPLES as f64;
    let mut r = Reference {
        first_thick: None,
        first_cross: None,
        min_dist: f64::MAX,
        min_cross_dist: f64::MAX,
    };
    let mut best_i = 0;
    let mut prev_vol = vol(0.0);
    for i in 0..=SAMPLES {
        let t = i as f64 * h;
        let d = dist(t);
        if d < r.min_dist {
            r.min_dist = d;
            best_i = i;
        }
        if d < eta - margin && r.first_thick.is_none() {
            r.first_thick = Some(t);
        }
        let f = vol(t);
        if i > 0 && (f < 0.0) != (prev_vol < 0.0) {
            let (mut lo, mut hi) = (t - h, t);
            let lo_neg = prev_vol < 0.0;
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                if (vol(m) < 0.0) == lo_neg {
                    lo = m
                } else {
                    hi = m
                }
            }
            let dc = dist(hi).min(dist(lo));
            r.min_cross_dist = r.min_cross_dist.min(dc);
            if dc < eta - margin && r.first_cross.is_none() {
                r.first_cross = Some(hi);
            }
        }
        prev_vol = f;
    }
    // Golden-section refinement of the sampled minimum.
    let (mut a, mut b) = ((best_i as f64 - 1.0) * h, (best_i as f64 + 1.0) * h);
    a = a.max(0.0);
    b = b.min(1.0);
    for _ in 0..60 {
        let m1 = a + 0.382 * (b - a);
        let m2 = a + 0.618 * (b - a);
        if dist(m1) < dist(m2) {
            b = m2
        } else {
            a = m1
        }
    }
    r.min_dist = r.min_dist.min(dist(0.5 * (a + b)));
    r
}

#[derive(Default, Debug)]
struct Tally {
    cases: usize,
    ref_thick_hits: usize,
    ref_cross_hits: usize,
    thick_fp: usize,
    cross_fp: usize,
}

/// Checks one case against the reference; panics on a false negative or a late hit.
fn check(
    tally: &mut Tally,
    label: &str,
    r: &Reference,
    eta: f64,
    margin: f64,
    cubic_t: Option<f64>,
    thick_t: Option<f64>,
) {
    let h = 1.0 / SAMPLES as f64;
    tally.cases += 1;
    if let Some(tr) = r.first_thick {
        tally.ref_thick_hits += 1;
        let t = thick_t.unwrap_or_else(|| panic!("{label}: thick false negative (ref t = {tr})"));
        assert!(
            t <= tr + h,
            "{label}: thick hit {t} later than reference {tr}"
        );
    } else if thick_t.is_some() && r.min_dist > eta + margin {
        tally.thick_fp += 1;
    }
    if let Some(tr) = r.first_cross {
        tally.ref_cross_hits += 1;
        let t = cubic_t
            .unwrap_or_else(|| panic!("{label}: cubic false negative (ref crossing t = {tr})"));
        assert!(
            t <= tr + h,
            "{label}: cubic hit {t} later than reference {tr}"
        );
    } else if cubic_t.is_some() && r.min_cross_dist > eta + margin && r.min_dist > eta + margin {
        tally.cross_fp += 1;
    }
}

#[test]
fn random_vertex_triangle_no_false_negatives() {
    let mut rng = Rng(2021);
    let mut tally = Tally::default();
    for case in 0..3000 {
        let scale = if case % 5 == 0 { 1e3 } else { 1.0 };
        let offset = rng.vec(scale);
        let t0 = [rng.vec(1.0), rng.vec(1.0), rng.vec(1.0)].map(|x| x + offset);
        let t1 = t0.map(|x| x + rng.vec(0.3));
        // Aim the point at a random spot of the triangle at a random time, plus a miss offset.
        let tm = rng.f();
        let w = [rng.f(), rng.f(), rng.f()];
        let sw: f64 = w.iter().sum();
        let target = (0..3)
            .map(|i| lerp(t0[i], t1[i], tm) * (w[i] / sw))
            .sum::<Vec3>()
            + rng.vec(0.05);
        let vp = rng.vec(1.0);
        let (p0, p1) = (target - vp * tm, target + vp * (1.0 - tm));
        let eta = [0.0, 1e-3, 1e-2][case % 3];
        let margin = 1e-9 * scale;
        let tri_at = |t: f64| [0, 1, 2].map(|i| lerp(t0[i], t1[i], t));
        let dist = |t: f64| {
            let [a, b, c] = tri_at(t);
            let p = lerp(p0, p1, t);
            point_triangle_closest(p, a, b, c).0.distance(p)
        };
        let vol = |t: f64| {
            let [a, b, c] = tri_at(t);
            (b - a).cross(c - a).dot(lerp(p0, p1, t) - a)
        };
        let r = reference(dist, vol, eta, margin);
        let cubic = vertex_triangle_ccd(p0, p1, t0, t1, eta).map(|h| h.t);
        let thick = vertex_triangle_ccd_thick(p0, p1, t0, t1, eta).map(|h| h.t);
        check(
            &mut tally,
            &format!("vt case {case}"),
            &r,
            eta,
            margin,
            cubic,
            thick,
        );
    }
    println!("vertex-triangle sweep: {tally:?}");
    assert!(
        tally.ref_thick_hits > 300 && tally.ref_cross_hits > 300,
        "sample too easy: {tally:?}"
    );
    assert!(
        tally.thick_fp * 100 <= tally.cases,
        "thick false positives: {tally:?}"
    );
    assert!(
        tally.cross_fp * 100 <= tally.cases,
        "cubic false positives: {tally:?}"
    );
}

#[test]
fn random_edge_edge_no_false_negatives() {
    let mut rng = Rng(42);
    let mut tally = Tally::default();
    for case in 0..3000 {
        let scale = if case % 5 == 0 { 1e3 } else { 1.0 };
        let offset = rng.vec(scale);
        let q0 = [rng.vec(1.0), rng.vec(1.0)].map(|x| x + offset);
        let q1 = q0.map(|x| x + rng.vec(0.3));
        let tm = rng.f();
        let (qa, qb) = (lerp(q0[0], q1[0], tm), lerp(q0[1], q1[1], tm));
        let target = lerp(qa, qb, rng.f()) + rng.vec(0.05);
        // Edge p through the target at time tm, with a per-vertex motion (rotation-like);
        // every 7th case starts parallel to q at the aimed time.
        let dir = if case % 7 == 0 {
            (qb - qa).normalize()
        } else {
            rng.vec(1.0)
        };
        let s = rng.f();
        let pa = target - dir * s;
        let pb = target + dir * (1.0 - s);
        let (va, vb) = (rng.vec(1.0), rng.vec(1.0));
        let p0 = [pa - va * tm, pb - vb * tm];
        let p1 = [pa + va * (1.0 - tm), pb + vb * (1.0 - tm)];
        let eta = [0.0, 1e-3, 1e-2][case % 3];
        let margin = 1e-9 * scale;
        let edges = |t: f64| {
            (
                lerp(p0[0], p1[0], t),
                lerp(p0[1], p1[1], t),
                lerp(q0[0], q1[0], t),
                lerp(q0[1], q1[1], t),
            )
        };
        let dist = |t: f64| {
            let (a, b, c, d) = edges(t);
            let (_, _, x, y) = segment_segment_closest(a, b, c, d);
            x.distance(y)
        };
        let vol = |t: f64| {
            let (a, b, c, d) = edges(t);
            (b - a).cross(d - c).dot(c - a)
        };
        let r = reference(dist, vol, eta, margin);
        let cubic: Option<EeHit> = edge_edge_ccd(p0, p1, q0, q1, eta);
        let thick = edge_edge_ccd_thick(p0, p1, q0, q1, eta).map(|h| h.t);
        check(
            &mut tally,
            &format!("ee case {case}"),
            &r,
            eta,
            margin,
            cubic.map(|h| h.t),
            thick,
        );
    }
    println!("edge-edge sweep: {tally:?}");
    assert!(
        tally.ref_thick_hits > 300 && tally.ref_cross_hits > 300,
        "sample too easy: {tally:?}"
    );
    assert!(
        tally.thick_fp * 100 <= tally.cases,
        "thick false positives: {tally:?}"
    );
    assert!(
        tally.cross_fp * 100 <= tally.cases,
        "cubic false positives: {tally:?}"
    );
}

/// Coplanar-throughout motion (all in z = 0) and zero-area triangles make the cubic vanish
/// identically; both variants must then behave like the thickness test.
#[test]
fn random_coplanar_and_degenerate_no_false_negatives() {
    let mut rng = Rng(7);
    let h = 1.0 / SAMPLES as f64;
    let flat = |x: Vec3| v(x.x, x.y, 0.0);
    let (mut hits, mut fp) = (0, 0);
    for case in 0..3000 {
        let eta = [0.0, 1e-3, 1e-2][case % 3];
        let margin = 1e-9;
        let kind = (case / 3) % 3;
        let (dist_fn, cubic_t, thick_t): (Box<dyn Fn(f64) -> f64>, _, _) = if kind == 2 {
            // Two edges sliding in the plane z = 0.
            let q0 = [rng.vec(1.0), rng.vec(1.0)].map(flat);
            let q1 = q0.map(|x| x + flat(rng.vec(0.3)));
            let p0 = [rng.vec(1.0), rng.vec(1.0)].map(flat);
            let p1 = p0.map(|x| x + flat(rng.vec(1.0)));
            let d = move |t: f64| {
                let (_, _, x, y) = segment_segment_closest(
                    lerp(p0[0], p1[0], t),
                    lerp(p0[1], p1[1], t),
                    lerp(q0[0], q1[0], t),
                    lerp(q0[1], q1[1], t),
                );
                x.distance(y)
            };
            let cubic = edge_edge_ccd(p0, p1, q0, q1, eta).map(|h| h.t);
            let thick = edge_edge_ccd_thick(p0, p1, q0, q1, eta).map(|h| h.t);
            (Box::new(d), cubic, thick)
        } else if kind == 0 {
            // Point and triangle sliding in the plane z = 0.
            let t0 = [rng.vec(1.0), rng.vec(1.0), rng.vec(1.0)].map(flat);
            let t1 = t0.map(|x| x + flat(rng.vec(0.3)));
            let (p0, p1) = (flat(rng.vec(1.5)), flat(rng.vec(1.5)));
            let d = move |t: f64| {
                let [a, b, c] = [0, 1, 2].map(|i| lerp(t0[i], t1[i], t));
                let p = lerp(p0, p1, t);
                point_triangle_closest(p, a, b, c).0.distance(p)
            };
            let cubic = vertex_triangle_ccd(p0, p1, t0, t1, eta).map(|h| h.t);
            let thick = vertex_triangle_ccd_thick(p0, p1, t0, t1, eta).map(|h| h.t);
            (Box::new(d), cubic, thick)
        } else {
            // Zero-area triangle (c on segment ab) in general 3D motion.
            let (a0, b0, a1, b1) = (rng.vec(1.0), rng.vec(1.0), rng.vec(1.0), rng.vec(1.0));
            let w = rng.f();
            let t0 = [a0, b0, lerp(a0, b0, w)];
            let t1 = [a1, b1, lerp(a1, b1, w)];
            let target = lerp(lerp(a0, a1, 0.5), lerp(b0, b1, 0.5), rng.f()) + rng.vec(0.05);
            let vp = rng.vec(1.0);
            let (p0, p1) = (target - vp * 0.5, target + vp * 0.5);
            let d = move |t: f64| {
                let [a, b, c] = [0, 1, 2].map(|i| lerp(t0[i], t1[i], t));
                let p = lerp(p0, p1, t);
                point_triangle_closest(p, a, b, c).0.distance(p)
            };
            let cubic = vertex_triangle_ccd(p0, p1, t0, t1, eta).map(|h| h.t);
            let thick = vertex_triangle_ccd_thick(p0, p1, t0, t1, eta).map(|h| h.t);
            (Box::new(d), cubic, thick)
        };
        let r = reference(&dist_fn, |_| 0.0, eta, margin);
        if let Some(tr) = r.first_thick {
            hits += 1;
            for (name, got) in [("cubic", cubic_t), ("thick", thick_t)] {
                let t = got.unwrap_or_else(|| panic!("case {case}: {name} false negative at {tr}"));
                assert!(t <= tr + h, "case {case}: {name} hit {t} later than {tr}");
            }
        } else if thick_t.is_some() && r.min_dist > eta + margin {
            fp += 1;
        }
    }
    println!("coplanar/degenerate sweep: {hits} reference hits, {fp} thick false positives");
    assert!(hits > 200, "sample too easy: {hits}");
    assert!(fp * 100 <= 3000, "false positives: {fp}");
}
