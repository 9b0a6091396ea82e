//! Point queries of an obstacle in its local frame, in f64: the closest surface point (with
//! the side of two-sided surfaces), the inside test and the first crossing of a segment.

use super::cuboid::{cuboid_cast, cuboid_closest};
use super::shape::{Geom, Obstacle};
use super::surface::{SurfaceHit, SurfacePoint};
use crate::Vec3;
use parry3d::query::{PointProjection, Ray};

/// Depth (m) below which a vertex lies on a solid's surface, not inside it: cloth laid exactly on
/// a face (robot_cape's hem on drape_bot's base box, z = 0.4 - 0.3 against 0.05 + 0.05) lands a
/// rounding error on either side, and would be reported inside at "0.0 mm" and led out on every
/// run of that scene. A micrometre: above the rounding of parry's f32 shapes
/// (cylinders, meshes: about 1e-7 m at a metre), far below any cloth's thickness.
pub(crate) const ON_SURFACE: f64 = 1e-6;

/// A point this share of the thickness inside the layer is on its edge (where a push or the
/// implicit filter left it), not in it.
const LAYER_TOLERANCE: f64 = 1e-3;

/// Cosine with the surface normal below which a direction leads into a solid: a vertex beside a
/// box's side face (normal across `dir`) may follow a patch leaving upwards, one under its bottom
/// face may not.
const INTO: f64 = 0.2;

impl Obstacle {
    /// Closest surface point to local point `p`; `hint` (local) orients the normal of two-sided
    /// surfaces when `p` lies on them.
    pub(crate) fn closest_local(&self, p: Vec3, hint: Vec3) -> SurfacePoint {
        match self.geom {
            Geom::Ball { radius } => {
                let d = p.length();
                let n = if d > 1e-12 {
                    p / d
                } else {
                    hint.normalize_or(Vec3::Y)
                };
                SurfacePoint {
                    point: n * radius,
                    normal: n,
                    signed_distance: d - radius,
                }
            }
            Geom::HalfSpace { normal } => {
                let s = normal.dot(p);
                SurfacePoint {
                    point: p - normal * s,
                    normal,
                    signed_distance: s,
                }
            }
            Geom::Cuboid { half } => cuboid_closest(half, p),
            Geom::Capsule {
                radius,
                half_height,
            } => {
                let axis = Vec3::new(0.0, p.y.clamp(-half_height, half_height), 0.0);
                let d = p - axis;
                let len = d.length();
                let n = if len > 1e-12 {
                    d / len
                } else {
                    (hint - axis).normalize_or(Vec3::X)
                };
                SurfacePoint {
                    point: axis + n * radius,
                    normal: n,
                    signed_distance: len - radius,
                }
            }
            Geom::Solid | Geom::Surface => {
                let proj = self.shape.project_local_point(p.as_vec3(), false);
                self.surface_point(p, hint, proj)
            }
        }
    }

    /// [`Obstacle::closest_local`] when the surface is within `max_dist` of `p`, else `None`.
    /// Meshes prune their BVH with the bound, which makes the common "no contact" answer cheap.
    pub(crate) fn closest_local_within(
        &self,
        p: Vec3,
        hint: Vec3,
        max_dist: f64,
    ) -> Option<SurfacePoint> {
        if matches!(self.geom, Geom::Surface) {
            // f32 slack so the pruning never drops what the f64 test below would keep.
            let bound = (max_dist * (1.0 + 1e-4) + 1e-6) as f32;
            let proj = self
                .shape
                .project_local_point_with_max_dist(p.as_vec3(), false, bound)?;
            let sp = self.surface_point(p, hint, proj);
            return (sp.signed_distance <= max_dist).then_some(sp);
        }
        let sp = self.closest_local(p, hint);
        (sp.signed_distance <= max_dist).then_some(sp)
    }

    /// Surface point of a mesh or convex solid from parry's projection of local point `p`.
    fn surface_point(&self, p: Vec3, hint: Vec3, proj: PointProjection) -> SurfacePoint {
        let q = proj.point.as_dvec3();
        let diff = p - q;
        let d = diff.length();
        let inside = proj.is_inside && matches!(self.geom, Geom::Solid);
        let scale = (self.local_max - self.local_min).max_element();
        let n = if d > 1e-6 * scale {
            if inside {
                -diff / d
            } else {
                diff / d
            }
        } else {
            self.feature_normal(p, hint)
        };
        SurfacePoint {
            point: q,
            normal: n,
            signed_distance: if inside { -d } else { d },
        }
    }

    /// Normal of the surface feature nearest `p`, oriented towards `hint` for two-sided surfaces.
    fn feature_normal(&self, p: Vec3, hint: Vec3) -> Vec3 {
        let (proj, feature) = self.shape.project_local_point_and_get_feature(p.as_vec3());
        let n = self
            .shape
            .feature_normal_at_point(proj.subshape, feature, proj.point)
            .map(|n| n.as_dvec3())
            .unwrap_or(Vec3::ZERO);
        let n = if n == Vec3::ZERO {
            (hint - proj.point.as_dvec3()).normalize_or(Vec3::Y)
        } else {
            n
        };
        if matches!(self.geom, Geom::Surface) && n.dot(hint - proj.point.as_dvec3()) < 0.0 {
            -n
        } else {
            n
        }
    }

    /// True when local point `p` is strictly inside a solid (never for surfaces).
    pub(crate) fn contains_local(&self, p: Vec3) -> bool {
        match self.geom {
            Geom::Ball { radius } => p.length_squared() < radius * radius,
            Geom::HalfSpace { normal } => normal.dot(p) < 0.0,
            Geom::Cuboid { half } => p.abs().cmplt(half).all(),
            Geom::Capsule { .. } => self.closest_local(p, p).signed_distance < 0.0,
            Geom::Solid => self.shape.contains_local_point(p.as_vec3()),
            Geom::Surface => false,
        }
    }

    /// The outward normal and depth (`th` minus the distance) of local point `p` when it lies
    /// outside a solid (or on its surface, within [`ON_SURFACE`]) but inside its contact layer of
    /// thickness `th`; `None` when clear, inside, or not a solid. On the surface counts: cloth
    /// laid along drape_bot's closed fingers lies on both faces where they meet, and read as in
    /// neither layer, it would be left to the vertex pass, which pushes it out of one finger
    /// through the other, millimetres across the cloth in one pass.
    pub(crate) fn in_layer(&self, p: Vec3, th: f64) -> Option<(Vec3, f64)> {
        if matches!(self.geom, Geom::Surface) {
            return None;
        }
        let sp = self.closest_local(p, p);
        if self.contains_local(p) && -sp.signed_distance > ON_SURFACE {
            return None;
        }
        let gap = th - sp.signed_distance;
        (gap > th * LAYER_TOLERANCE).then_some((sp.normal, gap))
    }

    /// How far local point `p`, in the contact layer (see [`Self::in_layer`]), moves along unit
    /// `dir` in one go to clear it: its depth in the layer (exact along the surface normal,
    /// repeated elsewhere); `None` when it is not in the layer or `dir` leads into the solid
    /// (more than [`INTO`] against the surface normal).
    pub(crate) fn layer_step(&self, p: Vec3, dir: Vec3, th: f64) -> Option<f64> {
        let (normal, gap) = self.in_layer(p, th)?;
        (normal.dot(dir) >= -INTO).then_some(gap)
    }

    /// How far local point `p`, inside a solid, must travel along unit `dir` to leave it (the
    /// farthest crossing of the ray: a concave mesh solid is left for good); `None` when `p` is
    /// not inside or the ray never leaves (a half-space `dir` points into).
    pub(crate) fn exit_along(&self, p: Vec3, dir: Vec3) -> Option<f64> {
        if !self.contains_local(p) {
            return None;
        }
        if let Geom::HalfSpace { normal } = self.geom {
            let along = normal.dot(dir);
            return (along > 1e-9).then(|| -normal.dot(p) / along);
        }
        // From beyond the bounding box back to `p`: the first crossing from outside.
        let reach = (self.local_max - self.local_min).length() + (p - self.local_min).length();
        let far = p + dir * (2.0 * reach + 1.0);
        // A ray from outside to a point inside crosses the surface; it is missed only by rounding
        // at a point on the surface (depth 0). Read as "no way out", such a vertex on drape_bot's
        // forearm would fall to the nearest-face push: millimetres in one pass, stretching its
        // edges.
        Some(
            self.cast_local(far, p)
                .map_or(0.0, |hit| (hit.point - p).dot(dir).max(0.0)),
        )
    }

    /// First time the local segment `a -> b` crosses the surface from outside (t in [0, 1]).
    pub(crate) fn cast_local(&self, a: Vec3, b: Vec3) -> Option<SurfaceHit> {
        let d = b - a;
        match self.geom {
            Geom::Ball { radius } => {
                // |a + t d|^2 = r^2, entering root.
                let qa = d.length_squared();
                let qb = 2.0 * a.dot(d);
                let qc = a.length_squared() - radius * radius;
                if qa <= 0.0 || qc < 0.0 {
                    return None;
                }
                let disc = qb * qb - 4.0 * qa * qc;
                if disc < 0.0 {
                    return None;
                }
                let t = (-qb - disc.sqrt()) / (2.0 * qa);
                if !(0.0..=1.0).contains(&t) {
                    return None;
                }
                let point = a + d * t;
                Some(SurfaceHit {
                    point,
                    normal: point.normalize_or(Vec3::Y),
                })
            }
            Geom::HalfSpace { normal } => {
                let da = normal.dot(a);
                let db = normal.dot(b);
                if da >= 0.0 && db < 0.0 {
                    let t = da / (da - db);
                    Some(SurfaceHit {
                        point: a + d * t,
                        normal,
                    })
                } else {
                    None
                }
            }
            Geom::Cuboid { half } => cuboid_cast(half, a, d),
            Geom::Solid | Geom::Surface | Geom::Capsule { .. } => {
                if d.length_squared() == 0.0 {
                    return None;
                }
                let ray = Ray::new(a.as_vec3(), d.as_vec3());
                let solid = !matches!(self.geom, Geom::Surface);
                let hit = self.shape.cast_local_ray_and_get_normal(&ray, 1.0, solid)?;
                let t = f64::from(hit.time_of_impact);
                let mut normal = hit.normal.as_dvec3().normalize_or_zero();
                if normal == Vec3::ZERO {
                    normal = -d.normalize();
                }
                if normal.dot(d) > 0.0 {
                    normal = -normal;
                }
                Some(SurfaceHit {
                    point: a + d * t,
                    normal,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Pose;

    fn rnd(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// The f64 analytic paths agree with parry's (f32) on random points and segments; tolerance
    /// from f32 rounding at these ~1 m coordinates (~1e-7) with margin.
    #[test]
    fn analytic_shapes_match_parry() {
        let obstacles = [
            Obstacle::sphere("s", 0.3, Pose::IDENTITY).unwrap(),
            Obstacle::cuboid("b", Vec3::new(0.2, 0.05, 0.4), Pose::IDENTITY).unwrap(),
            Obstacle::capsule("c", 0.1, 0.25, Pose::IDENTITY).unwrap(),
        ];
        let mut seed = 7u64;
        let mut hits = 0;
        for o in &obstacles {
            for _ in 0..2000 {
                let p = Vec3::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.6;
                let proj = o.shape.project_local_point(p.as_vec3(), false);
                let d_ref =
                    (p - proj.point.as_dvec3()).length() * if proj.is_inside { -1.0 } else { 1.0 };
                let sp = o.closest_local(p, p);
                assert!(
                    (sp.signed_distance - d_ref).abs() < 1e-5,
                    "{} at {p}: {} vs {d_ref}",
                    o.name,
                    sp.signed_distance
                );
                assert!((sp.point - proj.point.as_dvec3()).length() < 1e-5);
                if d_ref.abs() > 1e-6 {
                    assert_eq!(o.contains_local(p), d_ref < 0.0, "{} at {p}", o.name);
                }
                let q = Vec3::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.6;
                if o.contains_local(p) {
                    continue;
                }
                let ray = Ray::new(p.as_vec3(), (q - p).as_vec3());
                let r = o.shape.cast_local_ray_and_get_normal(&ray, 1.0, true);
                let mine = o.cast_local(p, q);
                match (r, mine) {
                    (Some(r), Some(m)) => {
                        hits += 1;
                        let pt = p + (q - p) * f64::from(r.time_of_impact);
                        assert!(
                            (pt - m.point).length() < 1e-5,
                            "{}: {pt} vs {}",
                            o.name,
                            m.point
                        );
                        assert!((r.normal.as_dvec3() - m.normal).length() < 1e-3);
                    }
                    (None, None) => {}
                    (r, m) => {
                        // Only grazing cases may disagree.
                        let t = r.map(|r| f64::from(r.time_of_impact)).unwrap_or(0.0);
                        let pt = m.map(|m| m.point).unwrap_or(p + (q - p) * t);
                        assert!(
                            o.closest_local(pt, pt).signed_distance.abs() < 1e-5,
                            "{}: {p} -> {q}",
                            o.name
                        );
                    }
                }
            }
        }
        assert!(hits > 500);
    }

    /// A point on a solid's surface up to rounding (inside by nanometres, which parry's f32 ray
    /// cannot resolve) has a way out of depth about 0, and is in the contact layer: cloth led out
    /// of drape_bot's forearm falls to the nearest-face push when either reads "none"
    /// (millimetres in one pass), and cloth on the shared face of its closed fingers is pushed
    /// out of one through the other.
    #[test]
    fn a_point_on_the_surface_has_a_way_out_and_a_layer() {
        let obstacles = [
            Obstacle::cuboid("b", Vec3::new(0.2, 0.05, 0.4), Pose::IDENTITY).unwrap(),
            Obstacle::capsule("c", 0.04, 0.2, Pose::IDENTITY).unwrap(),
            Obstacle::cylinder("y", 0.04, 0.2, Pose::IDENTITY).unwrap(),
        ];
        let th = 0.008;
        let mut seed = 11u64;
        for o in &obstacles {
            let mut tested = 0;
            for _ in 0..4000 {
                let q = Vec3::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.5;
                let sp = o.closest_local(q, q);
                let depth = 10f64.powf(-12.0 + 6.0 * (rnd(&mut seed) + 1.0) / 2.0);
                let p = sp.point - sp.normal * depth;
                if !o.contains_local(p) {
                    continue;
                }
                tested += 1;
                let dir = (sp.normal
                    + Vec3::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.3)
                    .normalize();
                let way = o.exit_along(p, dir);
                assert!(
                    way.is_some_and(|w| w < 1e-3),
                    "{}: {p} inside by {depth:e}, way out along {dir}: {way:?}",
                    o.name
                );
                if depth <= 0.1 * ON_SURFACE {
                    assert!(
                        o.in_layer(p, th).is_some(),
                        "{}: {p} on the surface",
                        o.name
                    );
                }
            }
            assert!(tested > 1000, "{}: {tested}", o.name);
        }
    }
}
