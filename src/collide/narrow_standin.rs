//! TEMPORARY stand-in for `crate::collide::narrow` (written by another helper in parallel).
//! Same signatures as the agreed API so the stage compiles and is testable now; the lead deletes
//! this file at merge and replaces `use narrow_standin as narrow` with `pub mod narrow;` in mod.rs.

use crate::Vec3;

#[derive(Debug, Clone, Copy)]
#[allow(dead_code)]
pub struct VtHit {
    pub t: f64,
    pub bary: [f64; 3],
    pub normal: Vec3,
}

#[derive(Debug, Clone, Copy)]
#[allow(dead_code)]
pub struct EeHit {
    pub t: f64,
    pub s: f64,
    pub u: f64,
    pub normal: Vec3,
}

/// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
pub fn point_triangle_closest(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, [f64; 3]) {
    let ab = b - a;
    let ac = c - a;
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
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if denom.abs() < 1e-300 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let v = vb / denom;
    let w = vc / denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Closest points between segments pq and rs (Ericson 5.1.9): (s, u, point on pq, point on rs).
pub fn segment_segment_closest(p: Vec3, q: Vec3, r: Vec3, s: Vec3) -> (f64, f64, Vec3, Vec3) {
    let d1 = q - p;
    let d2 = s - r;
    let rr = p - r;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(rr);
    let eps = 1e-30;
    let (sc, tc);
    if a <= eps && e <= eps {
        return (0.0, 0.0, p, r);
    }
    if a <= eps {
        sc = 0.0;
        tc = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(rr);
        if e <= eps {
            tc = 0.0;
            sc = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            sc = s0;
            tc = t0;
        }
    }
    (sc, tc, p + d1 * sc, r + d2 * tc)
}

/// Roots in [0, 1] of the cubic `c[0] + c[1] t + c[2] t^2 + c[3] t^3`, ascending, found by bisection
/// on the monotone pieces between critical points; endpoints where the value vanishes count too.
#[allow(clippy::needless_range_loop)]
fn cubic_roots_01(c: [f64; 4]) -> ([f64; 3], usize) {
    let f = |t: f64| ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
    let mut knots = [0.0f64; 4];
    let mut nk = 0;
    knots[nk] = 0.0;
    nk += 1;
    // f'(t) = 3 c3 t^2 + 2 c2 t + c1
    let (qa, qb, qc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    let mut crit = [f64::NAN; 2];
    if qa.abs() > 1e-300 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            crit = [(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)];
        }
    } else if qb.abs() > 1e-300 {
        crit[0] = -qc / qb;
    }
    if crit[0] > crit[1] {
        crit.swap(0, 1);
    }
    for t in crit {
        if t > 0.0 && t < 1.0 {
            knots[nk] = t;
            nk += 1;
        }
    }
    let mut out = [0.0; 3];
    let mut n = 0;
    let mut lo = 0.0;
    let mut flo = f(lo);
    let scale = c.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    for i in 1..=nk {
        let hi = if i < nk { knots[i] } else { 1.0 };
        let fhi = f(hi);
        if flo.abs() <= 1e-14 * scale {
            if n == 0 || (out[n - 1] - lo).abs() > 1e-12 {
                out[n.min(2)] = lo;
                n = (n + 1).min(3);
            }
        } else if flo * fhi < 0.0 {
            let (mut a, mut b, mut fa) = (lo, hi, flo);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                let fm = f(m);
                if fm * fa <= 0.0 {
                    b = m;
                } else {
                    a = m;
                    fa = fm;
                }
            }
            out[n.min(2)] = 0.5 * (a + b);
            n = (n + 1).min(3);
        }
        lo = hi;
        flo = fhi;
    }
    if flo.abs() <= 1e-14 * scale && (n == 0 || (out[n - 1] - 1.0).abs() > 1e-12) && n < 3 {
        out[n] = 1.0;
        n += 1;
    }
    (out, n)
}

/// Coefficients of the coplanarity cubic `det[x1(t)-x0(t), x2(t)-x0(t), x3(t)-x0(t)]` for linear motion.
fn coplanarity_cubic(x0: [Vec3; 4], x1: [Vec3; 4]) -> [f64; 4] {
    let f = |t: f64| {
        let p: [Vec3; 4] = std::array::from_fn(|i| x0[i].lerp(x1[i], t));
        (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]))
    };
    // Exact interpolation of the cubic through 4 samples.
    let (f0, f1, f2, f3) = (f(0.0), f(1.0 / 3.0), f(2.0 / 3.0), f(1.0));
    let c0 = f0;
    let c1 = (-11.0 * f0 + 18.0 * f1 - 9.0 * f2 + 2.0 * f3) / 2.0;
    let c2 = (18.0 * f0 - 45.0 * f1 + 36.0 * f2 - 9.0 * f3) / 2.0;
    let c3 = (-9.0 * f0 + 27.0 * f1 - 27.0 * f2 + 9.0 * f3) / 2.0;
    [c0, c1, c2, c3]
}

#[allow(clippy::too_many_arguments)]
pub fn vertex_triangle_ccd(
    p0: Vec3,
    p1: Vec3,
    a0: Vec3,
    a1: Vec3,
    b0: Vec3,
    b1: Vec3,
    c0: Vec3,
    c1: Vec3,
    eta: f64,
) -> Option<VtHit> {
    let (roots, n) = coplanarity_cubic_roots([p0, a0, b0, c0], [p1, a1, b1, c1]);
    for &t in &roots[..n] {
        let (p, a, b, c) = (
            p0.lerp(p1, t),
            a0.lerp(a1, t),
            b0.lerp(b1, t),
            c0.lerp(c1, t),
        );
        let (q, bary) = point_triangle_closest(p, a, b, c);
        if (p - q).length() <= eta {
            let mut nrm = (b - a).cross(c - a).normalize_or_zero();
            if nrm.dot(p0 - (a0 * bary[0] + b0 * bary[1] + c0 * bary[2])) < 0.0 {
                nrm = -nrm;
            }
            return Some(VtHit {
                t,
                bary,
                normal: nrm,
            });
        }
    }
    None
}

fn coplanarity_cubic_roots(x0: [Vec3; 4], x1: [Vec3; 4]) -> ([f64; 3], usize) {
    cubic_roots_01(coplanarity_cubic(x0, x1))
}

pub fn edge_edge_ccd(
    p0: [Vec3; 2],
    p1: [Vec3; 2],
    q0: [Vec3; 2],
    q1: [Vec3; 2],
    eta: f64,
) -> Option<EeHit> {
    let (roots, n) =
        coplanarity_cubic_roots([p0[0], p0[1], q0[0], q0[1]], [p1[0], p1[1], q1[0], q1[1]]);
    for &t in &roots[..n] {
        let pa = p0[0].lerp(p1[0], t);
        let pb = p0[1].lerp(p1[1], t);
        let qa = q0[0].lerp(q1[0], t);
        let qb = q0[1].lerp(q1[1], t);
        let (s, u, x, y) = segment_segment_closest(pa, pb, qa, qb);
        if (x - y).length() <= eta {
            let mut nrm = (pb - pa).cross(qb - qa).normalize_or_zero();
            let start = p0[0].lerp(p0[1], s) - q0[0].lerp(q0[1], u);
            if nrm == Vec3::ZERO {
                nrm = start.normalize_or_zero();
            }
            if nrm.dot(start) < 0.0 {
                nrm = -nrm;
            }
            return Some(EeHit {
                t,
                s,
                u,
                normal: nrm,
            });
        }
    }
    None
}

/// Static triangle-triangle intersection: any edge of one triangle crosses the other triangle.
/// (Coplanar overlaps are not detected by this stand-in.)
pub fn triangles_intersect(t1: [Vec3; 3], t2: [Vec3; 3]) -> bool {
    fn seg_tri(p: Vec3, q: Vec3, t: [Vec3; 3]) -> bool {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let dp = n.dot(p - t[0]);
        let dq = n.dot(q - t[0]);
        if dp * dq > 0.0 || dp == dq {
            return false;
        }
        let s = dp / (dp - dq);
        let x = p + (q - p) * s;
        let c0 = (t[1] - t[0]).cross(x - t[0]).dot(n);
        let c1 = (t[2] - t[1]).cross(x - t[1]).dot(n);
        let c2 = (t[0] - t[2]).cross(x - t[2]).dot(n);
        (c0 >= 0.0 && c1 >= 0.0 && c2 >= 0.0) || (c0 <= 0.0 && c1 <= 0.0 && c2 <= 0.0)
    }
    (0..3).any(|i| seg_tri(t1[i], t1[(i + 1) % 3], t2) || seg_tri(t2[i], t2[(i + 1) % 3], t1))
}
