//! Static triangle-triangle intersection test for the "self-intersecting pairs" metric.
//!
//! Two closed triangles intersect iff an edge of one meets the other: their intersection is
//! a convex set whose extreme points lie on the boundary of one of them. Each edge test uses
//! signed plane distances with a tolerance of `TOUCH_REL` times the problem scale, so touching
//! (vertex on face, shared edge, coplanar overlap) counts as intersecting.
//!
//! Callers counting self-intersections of one mesh must skip pairs that share a vertex or an
//! edge: those always "touch" and would be counted otherwise.

use super::closest::{point_triangle_closest, segment_segment_closest, DEGENERATE_SIN};
use crate::Vec3;

/// Contact tolerance relative to the scale `max |coordinate| + max edge length`.
pub const TOUCH_REL: f64 = 1e-12;

/// Unit normal, or `None` for a (numerically) zero-area triangle.
fn unit_normal(t: &[Vec3; 3]) -> Option<Vec3> {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let max_edge2 = (t[1] - t[0])
        .length_squared()
        .max((t[2] - t[0]).length_squared())
        .max((t[2] - t[1]).length_squared());
    let len = n.length();
    (len > DEGENERATE_SIN * max_edge2).then(|| n / len)
}

fn segment_near_edges(a: Vec3, b: Vec3, t: &[Vec3; 3], tol: f64) -> bool {
    (0..3).any(|i| {
        let (_, _, c1, c2) = segment_segment_closest(a, b, t[i], t[(i + 1) % 3]);
        c1.distance(c2) <= tol
    })
}

fn point_near_triangle(x: Vec3, t: &[Vec3; 3], tol: f64) -> bool {
    point_triangle_closest(x, t[0], t[1], t[2]).0.distance(x) <= tol
}

/// Does the closed segment `a b` meet the closed triangle `t` (within `tol`)?
fn segment_meets_triangle(a: Vec3, b: Vec3, t: &[Vec3; 3], n: Option<Vec3>, tol: f64) -> bool {
    let Some(n) = n else {
        // Zero-area triangle: the union of its edges.
        return segment_near_edges(a, b, t, tol);
    };
    let da = n.dot(a - t[0]);
    let db = n.dot(b - t[0]);
    if (da > tol && db > tol) || (da < -tol && db < -tol) {
        return false;
    }
    let a_on = da.abs() <= tol;
    let b_on = db.abs() <= tol;
    if a_on && b_on {
        // Coplanar segment: an endpoint inside, or it crosses the boundary.
        return point_near_triangle(a, t, 2.0 * tol)
            || point_near_triangle(b, t, 2.0 * tol)
            || segment_near_edges(a, b, t, 2.0 * tol);
    }
    let x = if a_on {
        a
    } else if b_on {
        b
    } else {
        a + (b - a) * (da / (da - db))
    };
    point_near_triangle(x, t, 2.0 * tol)
}

fn all_strictly_one_side(t: &[Vec3; 3], plane_pt: Vec3, n: Vec3, tol: f64) -> bool {
    let d = t.map(|x| n.dot(x - plane_pt));
    d.iter().all(|&x| x > tol) || d.iter().all(|&x| x < -tol)
}

/// Do the closed triangles `t1` and `t2` intersect or touch (within `TOUCH_REL` of the scale)?
///
/// Robust for coplanar, touching and zero-area triangles. Pairs sharing a vertex or edge
/// always return `true`; exclude them before calling when counting self-intersections.
pub fn triangles_intersect(t1: [Vec3; 3], t2: [Vec3; 3]) -> bool {
    let mut lo1 = t1[0].min(t1[1]).min(t1[2]);
    let mut hi1 = t1[0].max(t1[1]).max(t1[2]);
    let lo2 = t2[0].min(t2[1]).min(t2[2]);
    let hi2 = t2[0].max(t2[1]).max(t2[2]);
    let coord = lo1
        .abs()
        .max(hi1.abs())
        .max(lo2.abs())
        .max(hi2.abs())
        .max_element();
    let extent = (hi1 - lo1).max(hi2 - lo2).max_element();
    let tol = TOUCH_REL * (coord + extent);
    lo1 -= Vec3::splat(tol);
    hi1 += Vec3::splat(tol);
    if lo1.cmpgt(hi2).any() || lo2.cmpgt(hi1).any() {
        return false;
    }
    let n1 = unit_normal(&t1);
    let n2 = unit_normal(&t2);
    if n2.is_some_and(|n| all_strictly_one_side(&t1, t2[0], n, tol))
        || n1.is_some_and(|n| all_strictly_one_side(&t2, t1[0], n, tol))
    {
        return false;
    }
    (0..3).any(|i| segment_meets_triangle(t1[i], t1[(i + 1) % 3], &t2, n2, tol))
        || (0..3).any(|i| segment_meets_triangle(t2[i], t2[(i + 1) % 3], &t1, n1, tol))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    const BASE: [Vec3; 3] = [
        Vec3::new(0., 0., 0.),
        Vec3::new(1., 0., 0.),
        Vec3::new(0., 1., 0.),
    ];

    fn both_orders(a: [Vec3; 3], b: [Vec3; 3]) -> bool {
        let r = triangles_intersect(a, b);
        assert_eq!(r, triangles_intersect(b, a), "asymmetric result");
        let rot = [b[1], b[2], b[0]];
        assert_eq!(r, triangles_intersect(a, rot), "depends on vertex order");
        r
    }

    #[test]
    fn crossing_and_separated() {
        // Vertical triangle piercing the base face.
        assert!(both_orders(
            BASE,
            [v(0.2, 0.2, -1.), v(0.2, 0.2, 1.), v(0.3, 0.25, 1.)]
        ));
        // Same, lifted above.
        assert!(!both_orders(
            BASE,
            [v(0.2, 0.2, 0.1), v(0.2, 0.2, 1.), v(0.3, 0.25, 1.)]
        ));
        // Crosses the plane but outside the base triangle.
        assert!(!both_orders(
            BASE,
            [v(0.8, 0.8, -1.), v(0.8, 0.8, 1.), v(2., 2., 0.)]
        ));
        // Two triangles whose planes cross inside both bounding boxes but whose intervals
        // on the intersection line do not overlap.
        assert!(!both_orders(
            BASE,
            [v(0.6, 0.6, -1.), v(0.6, 0.6, 1.), v(1.5, 0.5, 0.)]
        ));
    }

    #[test]
    fn touching_counts() {
        // Vertex on the face.
        assert!(both_orders(
            BASE,
            [v(0.2, 0.2, 0.), v(0.2, 0.2, 1.), v(0.3, 0.25, 1.)]
        ));
        // Edge on edge, perpendicular planes.
        assert!(both_orders(
            BASE,
            [v(0., 0., 0.), v(1., 0., 0.), v(0.5, 0., 1.)]
        ));
        // Edge crossing an edge at a single point.
        assert!(both_orders(
            BASE,
            [v(0.5, -1., 0.), v(0.5, 1., 0.), v(0.5, 0., 1.)].map(|x| x - v(0., 0.5, 0.))
        ));
        // Just separated by 1e-9.
        assert!(!both_orders(
            BASE,
            [v(0.2, 0.2, 1e-9), v(0.2, 0.2, 1.), v(0.3, 0.25, 1.)]
        ));
    }

    #[test]
    fn coplanar_cases() {
        // Overlapping.
        assert!(both_orders(
            BASE,
            [v(0.5, 0.5, 0.), v(-0.5, 0.2, 0.), v(0.2, -0.5, 0.)]
        ));
        // Contained.
        assert!(both_orders(
            BASE,
            [v(0.1, 0.1, 0.), v(0.2, 0.1, 0.), v(0.1, 0.2, 0.)]
        ));
        // Disjoint.
        assert!(!both_orders(
            BASE,
            [v(1., 1., 0.), v(2., 1., 0.), v(1., 2., 0.)]
        ));
        // Sharing an edge (adjacent mesh triangles): touching.
        assert!(both_orders(
            BASE,
            [v(1., 0., 0.), v(0., 1., 0.), v(1., 1., 0.)]
        ));
    }

    #[test]
    fn degenerate_triangles() {
        // Needle (collinear) piercing the face.
        assert!(both_orders(
            BASE,
            [v(0.2, 0.2, -1.), v(0.2, 0.2, 0.), v(0.2, 0.2, 1.)]
        ));
        // Point triangle on the face and above it.
        let p = v(0.3, 0.3, 0.);
        assert!(both_orders(BASE, [p, p, p]));
        let q = v(0.3, 0.3, 0.5);
        assert!(!both_orders(BASE, [q, q, q]));
        // Two crossing needles in the same plane.
        assert!(both_orders(
            [v(-1., 0., 0.), v(0., 0., 0.), v(1., 0., 0.)],
            [v(0., -1., 0.), v(0., 0.5, 0.), v(0., 1., 0.)]
        ));
    }

    /// Separating-axis reference (independent method): triangles are disjoint iff one of the
    /// normals, the 9 edge cross products or the 6 in-plane edge normals separates them.
    fn sat_separated(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
        let ea = [a[1] - a[0], a[2] - a[1], a[0] - a[2]];
        let eb = [b[1] - b[0], b[2] - b[1], b[0] - b[2]];
        let na = ea[0].cross(ea[1]);
        let nb = eb[0].cross(eb[1]);
        let mut axes = vec![na, nb];
        for x in ea {
            for y in eb {
                axes.push(x.cross(y));
            }
            axes.push(na.cross(x));
        }
        for y in eb {
            axes.push(nb.cross(y));
        }
        axes.iter()
            .filter(|ax| ax.length_squared() > 1e-20)
            .any(|ax| {
                let pa = a.map(|x| x.dot(*ax));
                let pb = b.map(|x| x.dot(*ax));
                let (amin, amax) = (
                    pa.iter().cloned().fold(f64::MAX, f64::min),
                    pa.iter().cloned().fold(f64::MIN, f64::max),
                );
                let (bmin, bmax) = (
                    pb.iter().cloned().fold(f64::MAX, f64::min),
                    pb.iter().cloned().fold(f64::MIN, f64::max),
                );
                amax < bmin || bmax < amin
            })
    }

    #[test]
    fn random_pairs_agree_with_separating_axis_reference() {
        let mut s: u64 = 12345;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let (mut hits, n) = (0, 20_000);
        for i in 0..n {
            let a = [0; 3].map(|_| v(rnd(), rnd(), rnd()));
            let off = v(rnd(), rnd(), rnd()) * 0.8;
            let b = [0; 3].map(|_| v(rnd(), rnd(), rnd()) * 0.7 + off);
            // Every 4th pair coplanar (z = 0): exercises the 2D branch.
            let (a, b) = if i % 4 == 0 {
                (a.map(|x| v(x.x, x.y, 0.)), b.map(|x| v(x.x, x.y, 0.)))
            } else {
                (a, b)
            };
            let got = triangles_intersect(a, b);
            assert_eq!(got, !sat_separated(&a, &b), "case {i}: {a:?} {b:?}");
            hits += got as usize;
        }
        assert!(
            hits > n / 10 && hits < n * 9 / 10,
            "unbalanced sample: {hits}"
        );
    }
}
