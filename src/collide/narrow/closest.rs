//! Static closest-point queries: point-segment, point-triangle, segment-segment.
//!
//! All functions are total: degenerate inputs (zero-length segments, zero-area
//! triangles, parallel segments) return a valid closest pair instead of NaN.

use crate::Vec3;

/// Relative threshold below which a triangle counts as zero-area:
/// `|ab x ac| <= DEGENERATE_SIN * max_edge^2`, i.e. its smallest angle is below ~1e-12 rad.
pub(crate) const DEGENERATE_SIN: f64 = 1e-12;

/// Closest point to `p` on segment `a b`: returns `(s, point)` with `point = a + s (b - a)`, `s` in `[0, 1]`.
#[inline]
pub fn point_segment_closest(p: Vec3, a: Vec3, b: Vec3) -> (f64, Vec3) {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= f64::MIN_POSITIVE {
        return (0.0, a);
    }
    let s = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    (s, a + ab * s)
}

/// Closest point to `p` on the closed triangle `a b c`, with its barycentric coordinates
/// `[wa, wb, wc]` (non-negative, summing to 1, `closest = wa a + wb b + wc c`).
///
/// Voronoi-region walk (Ericson, Real-Time Collision Detection 5.1.5); zero-area triangles
/// are treated as the union of their three edges, so no division by a vanishing area occurs.
#[inline]
pub fn point_triangle_closest(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, [f64; 3]) {
    let ab = b - a;
    let ac = c - a;
    let bc = c - b;
    let max_edge2 = ab
        .length_squared()
        .max(ac.length_squared())
        .max(bc.length_squared());
    if ab.cross(ac).length() <= DEGENERATE_SIN * max_edge2 {
        return degenerate_triangle_closest(p, a, b, c);
    }
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        // d1 - d3 = |ab|^2 > 0 for a non-degenerate triangle.
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + bc * w, [0.0, 1.0 - w, w]);
    }
    // Inside the face region: va + vb + vc = |ab x ac|^2 > 0.
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Zero-area triangle: the closest point lies on one of its edges.
fn degenerate_triangle_closest(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, [f64; 3]) {
    let (s_ab, q_ab) = point_segment_closest(p, a, b);
    let (s_bc, q_bc) = point_segment_closest(p, b, c);
    let (s_ca, q_ca) = point_segment_closest(p, c, a);
    let d_ab = p.distance_squared(q_ab);
    let d_bc = p.distance_squared(q_bc);
    let d_ca = p.distance_squared(q_ca);
    if d_ab <= d_bc && d_ab <= d_ca {
        (q_ab, [1.0 - s_ab, s_ab, 0.0])
    } else if d_bc <= d_ca {
        (q_bc, [0.0, 1.0 - s_bc, s_bc])
    } else {
        (q_ca, [s_ca, 0.0, 1.0 - s_ca])
    }
}

/// Closest points between segments `p q` and `r s`.
///
/// Returns `(s1, s2, c1, c2)` with `c1 = p + s1 (q - p)`, `c2 = r + s2 (s - r)`, both parameters
/// in `[0, 1]`. The minimum is either interior to both segments (solved with the cross-product
/// form, which has no `a e - b^2` cancellation) or involves an endpoint, so the best of those five
/// candidates is exact; parallel and zero-length segments fall out of the endpoint candidates.
#[inline]
pub fn segment_segment_closest(p: Vec3, q: Vec3, r: Vec3, s: Vec3) -> (f64, f64, Vec3, Vec3) {
    let d1 = q - p;
    let d2 = s - r;
    let n = d1.cross(d2);
    let nn = n.length_squared();
    if nn > f64::MIN_POSITIVE {
        let w = r - p;
        let s1 = w.cross(d2).dot(n) / nn;
        let s2 = w.cross(d1).dot(n) / nn;
        if (0.0..=1.0).contains(&s1) && (0.0..=1.0).contains(&s2) {
            let c1 = p + d1 * s1;
            let c2 = r + d2 * s2;
            // Interior stationary point of a convex function: the global minimum.
            return (s1, s2, c1, c2);
        }
    }
    let mut best = (0.0, 0.0, p, r);
    let mut best_d = f64::INFINITY;
    let mut consider = |s1: f64, s2: f64, c1: Vec3, c2: Vec3| {
        let d = c1.distance_squared(c2);
        if d < best_d {
            best_d = d;
            best = (s1, s2, c1, c2);
        }
    };
    let (t, c) = point_segment_closest(p, r, s);
    consider(0.0, t, p, c);
    let (t, c) = point_segment_closest(q, r, s);
    consider(1.0, t, q, c);
    let (t, c) = point_segment_closest(r, p, q);
    consider(t, 0.0, c, r);
    let (t, c) = point_segment_closest(s, p, q);
    consider(t, 1.0, c, s);
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// Tiny deterministic RNG so tests need no extra dependency.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn vec(&mut self) -> Vec3 {
            v(
                self.next() * 2.0 - 1.0,
                self.next() * 2.0 - 1.0,
                self.next() * 2.0 - 1.0,
            )
        }
    }

    #[test]
    fn point_triangle_every_voronoi_region() {
        let (a, b, c) = (v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.));
        let cases = [
            (v(0.2, 0.2, 1.0), v(0.2, 0.2, 0.0)),  // face
            (v(-1.0, -1.0, 0.5), a),               // vertex a
            (v(2.0, -0.5, 0.0), b),                // vertex b
            (v(-0.5, 2.0, -3.0), c),               // vertex c
            (v(0.5, -1.0, 0.0), v(0.5, 0.0, 0.0)), // edge ab
            (v(-1.0, 0.5, 2.0), v(0.0, 0.5, 0.0)), // edge ca
            (v(1.0, 1.0, 0.0), v(0.5, 0.5, 0.0)),  // edge bc
        ];
        for (p, want) in cases {
            let (q, w) = point_triangle_closest(p, a, b, c);
            assert!(q.distance(want) < 1e-15, "{p} -> {q}, want {want}");
            let recon = a * w[0] + b * w[1] + c * w[2];
            assert!(recon.distance(q) < 1e-15);
        }
    }

    #[test]
    fn point_triangle_matches_dense_sampling() {
        // Brute force: the sampled minimum can only be above the true one, by at most the
        // sample spacing times the edge length.
        let mut rng = Rng(7);
        for _ in 0..200 {
            let (a, b, c, p) = (rng.vec(), rng.vec(), rng.vec(), rng.vec() * 2.0);
            let (q, w) = point_triangle_closest(p, a, b, c);
            assert!(w.iter().all(|&x| (-1e-12..=1.0 + 1e-12).contains(&x)));
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            let d = p.distance(q);
            let n = 200;
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, vv) = (i as f64 / n as f64, j as f64 / n as f64);
                    best = best.min(p.distance(a + (b - a) * u + (c - a) * vv));
                }
            }
            let h = (b - a).length().max((c - a).length()) / n as f64;
            assert!(d <= best + 1e-12, "not minimal: {d} > {best}");
            assert!(d >= best - 2.0 * h, "too small: {d} < {best}");
        }
    }

    #[test]
    fn point_triangle_degenerate_is_finite_and_correct() {
        // Collinear triangle along x from 0 to 2 and a point triangle.
        let (q, w) =
            point_triangle_closest(v(1.5, 1.0, 0.), v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.));
        assert!(q.distance(v(1.5, 0., 0.)) < 1e-15 && w.iter().all(|x| x.is_finite()));
        let z = v(3., 3., 3.);
        let (q, w) = point_triangle_closest(v(0., 0., 0.), z, z, z);
        assert_eq!(q, z);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn segments_crossing_parallel_and_degenerate() {
        // Crossing skew segments at distance 1.
        let (s, t, c1, c2) =
            segment_segment_closest(v(-1., 0., 0.), v(1., 0., 0.), v(0., -1., 1.), v(0., 1., 1.));
        assert!((s - 0.5).abs() < 1e-15 && (t - 0.5).abs() < 1e-15);
        assert!((c1.distance(c2) - 1.0).abs() < 1e-15);
        // Parallel overlapping segments at distance 2.
        let (_, _, c1, c2) =
            segment_segment_closest(v(0., 0., 0.), v(2., 0., 0.), v(1., 2., 0.), v(3., 2., 0.));
        assert!((c1.distance(c2) - 2.0).abs() < 1e-15);
        // Parallel, disjoint along the axis: endpoints.
        let (_, _, c1, c2) =
            segment_segment_closest(v(0., 0., 0.), v(1., 0., 0.), v(3., 1., 0.), v(4., 1., 0.));
        assert!((c1.distance(c2) - 5f64.sqrt()).abs() < 1e-15);
        // Both degenerate.
        let (_, _, c1, c2) =
            segment_segment_closest(v(0., 0., 0.), v(0., 0., 0.), v(0., 3., 4.), v(0., 3., 4.));
        assert!((c1.distance(c2) - 5.0).abs() < 1e-15);
        // Nearly parallel segments crossing at their midpoints: distance must be ~0, not ~1e-7.
        let eps = 1e-9;
        let (_, _, c1, c2) = segment_segment_closest(
            v(-1., -eps, 0.),
            v(1., eps, 0.),
            v(-1., eps, 0.),
            v(1., -eps, 0.),
        );
        assert!(c1.distance(c2) < 1e-15, "{}", c1.distance(c2));
    }

    #[test]
    fn segments_match_dense_sampling() {
        let mut rng = Rng(11);
        for _ in 0..300 {
            let (p, q, r, s) = (rng.vec(), rng.vec(), rng.vec(), rng.vec());
            let (s1, s2, c1, c2) = segment_segment_closest(p, q, r, s);
            assert!((0.0..=1.0).contains(&s1) && (0.0..=1.0).contains(&s2));
            assert!(c1.distance(p + (q - p) * s1) < 1e-14);
            let d = c1.distance(c2);
            let n = 400;
            let mut best = f64::INFINITY;
            for i in 0..=n {
                let x = p + (q - p) * (i as f64 / n as f64);
                best = best.min(point_segment_closest(x, r, s).1.distance(x));
            }
            let h = (q - p).length() / n as f64;
            assert!(d <= best + 1e-12 && d >= best - h, "{d} vs {best}");
        }
    }
}
