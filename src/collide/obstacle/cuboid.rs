//! The box `[-half, half]`: exact closest surface point and entering slab cast (f64).

use super::surface::{SurfaceHit, SurfacePoint};
use crate::Vec3;

/// Closest point on the surface of the box `[-half, half]` (f64, exact).
pub(super) fn cuboid_closest(half: Vec3, p: Vec3) -> SurfacePoint {
    let q = p.clamp(-half, half);
    let d = p - q;
    let len = d.length();
    if len > 0.0 {
        return SurfacePoint {
            point: q,
            normal: d / len,
            signed_distance: len,
        };
    }
    // Inside: leave through the nearest face.
    let gap = half - p.abs();
    let axis = if gap.x <= gap.y && gap.x <= gap.z {
        0
    } else if gap.y <= gap.z {
        1
    } else {
        2
    };
    let mut n = Vec3::ZERO;
    n[axis] = if p[axis] >= 0.0 { 1.0 } else { -1.0 };
    let mut point = p;
    point[axis] = n[axis] * half[axis];
    SurfacePoint {
        point,
        normal: n,
        signed_distance: -gap[axis],
    }
}

/// Entering hit of `a + t d`, t in [0, 1], with the box `[-half, half]` (slab method).
pub(super) fn cuboid_cast(half: Vec3, a: Vec3, d: Vec3) -> Option<SurfaceHit> {
    let mut t_enter = f64::NEG_INFINITY;
    let mut t_exit = f64::INFINITY;
    let mut axis = 0;
    for k in 0..3 {
        if d[k] == 0.0 {
            if a[k].abs() > half[k] {
                return None;
            }
            continue;
        }
        let t1 = (-half[k] - a[k]) / d[k];
        let t2 = (half[k] - a[k]) / d[k];
        let (lo, hi) = if t1 < t2 { (t1, t2) } else { (t2, t1) };
        if lo > t_enter {
            t_enter = lo;
            axis = k;
        }
        t_exit = t_exit.min(hi);
    }
    if t_enter > t_exit || !(0.0..=1.0).contains(&t_enter) {
        return None;
    }
    let mut normal = Vec3::ZERO;
    normal[axis] = if d[axis] > 0.0 { -1.0 } else { 1.0 };
    Some(SurfaceHit {
        point: a + d * t_enter,
        normal,
    })
}
