//! Rigid obstacles: a parry shape plus previous/current pose (the sweep over one step), and the
//! f64 point queries the collision stage needs (closest surface point, first surface crossing).
//!
//! Axis conventions (parry's): capsule and cylinder are along the local y axis, centred at the
//! origin; a box is centred with `half_extents`; a plane passes through the local origin with the
//! given outward normal (the free side). Spheres, planes, boxes and capsules are evaluated analytically
//! in f64; cylinders and meshes go through parry (f32, in the obstacle's local frame, so the rounding is relative
//! to the obstacle's size, ~1e-7 m for a 1 m object). Meshes are treated as two-sided surfaces of
//! zero thickness (cloth keeps to the side it came from; the cloth thickness gives the gap), so
//! open meshes work as well as closed ones.

use super::motion::Motion;
use crate::{Pose, Vec3};
use parry3d::query::{PointProjection, Ray};
use parry3d::shape::{SharedShape, TriMesh, TriMeshFlags};

#[derive(Debug, thiserror::Error)]
pub enum ObstacleError {
    #[error("obstacle '{name}': invalid mesh: {reason}")]
    BadMesh { name: String, reason: String },
    #[error("obstacle '{name}': {what} must be finite and > 0 (got {value})")]
    BadDimension {
        name: String,
        what: &'static str,
        value: f64,
    },
    #[error("obstacle '{name}': plane normal must be finite and non-zero")]
    BadNormal { name: String },
}

/// Which query path a shape uses.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Geom {
    Ball {
        radius: f64,
    },
    HalfSpace {
        normal: Vec3,
    },
    Cuboid {
        half: Vec3,
    },
    /// Segment from -half_height to +half_height on local y, inflated by radius.
    Capsule {
        radius: f64,
        half_height: f64,
    },
    /// Parry solid (cylinder): has an inside.
    Solid,
    /// Parry triangle mesh: a two-sided surface.
    Surface,
}

/// Closest point on the obstacle surface in the obstacle's local frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SurfacePoint {
    pub point: Vec3,
    /// Outward unit normal (for surfaces: pointing towards the query point's side).
    pub normal: Vec3,
    /// Distance to the surface, negative inside a solid.
    pub signed_distance: f64,
}

/// First crossing of the surface along a local segment.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SurfaceHit {
    pub point: Vec3,
    /// Unit normal facing the segment's start.
    pub normal: Vec3,
}

#[derive(Clone)]
pub struct Obstacle {
    pub name: String,
    pub shape: SharedShape,
    /// Pose at the start of the current step.
    pub pose_prev: Pose,
    /// Pose at the end of the current step.
    pub pose: Pose,
    /// Overrides the cloth's per-vertex friction coefficient when set.
    pub friction: Option<f64>,
    pub motion: Motion,
    /// Pose at t = 0, the reference for scripted `Motion::Velocity`.
    pub initial_pose: Pose,
    pub(crate) geom: Geom,
    /// Local-frame bounding box of the shape (planes: unbounded).
    pub(crate) local_min: Vec3,
    pub(crate) local_max: Vec3,
}

impl std::fmt::Debug for Obstacle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Obstacle")
            .field("name", &self.name)
            .field("shape", &self.shape.shape_type())
            .field("pose", &self.pose)
            .field("motion", &self.motion)
            .finish()
    }
}

fn positive(name: &str, what: &'static str, value: f64) -> Result<f32, ObstacleError> {
    if value.is_finite() && value > 0.0 {
        Ok(value as f32)
    } else {
        Err(ObstacleError::BadDimension {
            name: name.to_string(),
            what,
            value,
        })
    }
}

impl Obstacle {
    fn from_shape(name: &str, shape: SharedShape, geom: Geom, pose: Pose) -> Self {
        let (local_min, local_max) = match geom {
            Geom::HalfSpace { .. } => (Vec3::splat(f64::NEG_INFINITY), Vec3::splat(f64::INFINITY)),
            _ => {
                let aabb = shape.compute_local_aabb();
                (aabb.mins.as_dvec3(), aabb.maxs.as_dvec3())
            }
        };
        Self {
            name: name.to_string(),
            shape,
            pose_prev: pose,
            pose,
            friction: None,
            motion: Motion::Static,
            initial_pose: pose,
            geom,
            local_min,
            local_max,
        }
    }

    pub fn sphere(name: &str, radius: f64, pose: Pose) -> Result<Self, ObstacleError> {
        let r = positive(name, "radius", radius)?;
        Ok(Self::from_shape(
            name,
            SharedShape::ball(r),
            Geom::Ball { radius },
            pose,
        ))
    }

    /// Box centred at the local origin.
    pub fn cuboid(name: &str, half_extents: Vec3, pose: Pose) -> Result<Self, ObstacleError> {
        let hx = positive(name, "half_extents.x", half_extents.x)?;
        let hy = positive(name, "half_extents.y", half_extents.y)?;
        let hz = positive(name, "half_extents.z", half_extents.z)?;
        Ok(Self::from_shape(
            name,
            SharedShape::cuboid(hx, hy, hz),
            Geom::Cuboid { half: half_extents },
            pose,
        ))
    }

    /// Capsule along local y: segment from -half_height to +half_height, inflated by radius.
    pub fn capsule(
        name: &str,
        radius: f64,
        half_height: f64,
        pose: Pose,
    ) -> Result<Self, ObstacleError> {
        let r = positive(name, "radius", radius)?;
        let hh = positive(name, "half_height", half_height)?;
        Ok(Self::from_shape(
            name,
            SharedShape::capsule_y(hh, r),
            Geom::Capsule {
                radius,
                half_height,
            },
            pose,
        ))
    }

    /// Cylinder along local y, caps at +-half_height.
    pub fn cylinder(
        name: &str,
        radius: f64,
        half_height: f64,
        pose: Pose,
    ) -> Result<Self, ObstacleError> {
        let r = positive(name, "radius", radius)?;
        let hh = positive(name, "half_height", half_height)?;
        Ok(Self::from_shape(
            name,
            SharedShape::cylinder(hh, r),
            Geom::Solid,
            pose,
        ))
    }

    /// Plane through the local origin; `normal` (local) points to the free side.
    pub fn plane(name: &str, normal: Vec3, pose: Pose) -> Result<Self, ObstacleError> {
        let n = normal.normalize_or_zero();
        if !n.is_finite() || n == Vec3::ZERO {
            return Err(ObstacleError::BadNormal {
                name: name.to_string(),
            });
        }
        let shape = SharedShape::halfspace(n.as_vec3());
        Ok(Self::from_shape(
            name,
            shape,
            Geom::HalfSpace { normal: n },
            pose,
        ))
    }

    /// Triangle mesh (vertices in the local frame, already scaled). Uses parry's BVH.
    pub fn mesh(
        name: &str,
        vertices: &[Vec3],
        indices: &[[u32; 3]],
        pose: Pose,
    ) -> Result<Self, ObstacleError> {
        let bad = |reason: String| ObstacleError::BadMesh {
            name: name.to_string(),
            reason,
        };
        if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!("vertex {i} is not finite")));
        }
        if let Some(k) = indices
            .iter()
            .position(|t| t.iter().any(|&i| i as usize >= vertices.len()))
        {
            return Err(bad(format!(
                "triangle {k} references a vertex >= {}",
                vertices.len()
            )));
        }
        let verts = vertices.iter().map(|v| v.as_vec3()).collect();
        let flags =
            TriMeshFlags::DELETE_DEGENERATE_TRIANGLES | TriMeshFlags::MERGE_DUPLICATE_VERTICES;
        let mesh =
            TriMesh::with_flags(verts, indices.to_vec(), flags).map_err(|e| bad(e.to_string()))?;
        Ok(Self::from_shape(
            name,
            SharedShape::new(mesh),
            Geom::Surface,
            pose,
        ))
    }

    pub fn with_motion(mut self, motion: Motion) -> Self {
        self.motion = motion;
        self
    }

    pub fn with_friction(mut self, mu: Option<f64>) -> Self {
        self.friction = mu;
        self
    }

    /// World AABB of the shape swept from `pose_prev` to `pose` (corners of the local box at both
    /// poses; a rotation in between can bulge past it, so `margin` should cover that).
    pub(crate) fn swept_aabb(&self, margin: f64) -> (Vec3, Vec3) {
        if matches!(self.geom, Geom::HalfSpace { .. }) {
            return (Vec3::splat(f64::NEG_INFINITY), Vec3::splat(f64::INFINITY));
        }
        let mut lo = Vec3::splat(f64::INFINITY);
        let mut hi = Vec3::splat(f64::NEG_INFINITY);
        let c = (self.local_min + self.local_max) * 0.5;
        let half = (self.local_max - self.local_min) * 0.5;
        for pose in [&self.pose_prev, &self.pose] {
            let centre = pose.transform_point(c);
            let m = pose.rotation_matrix();
            let ext = Vec3::new(
                m.row(0).abs().dot(half),
                m.row(1).abs().dot(half),
                m.row(2).abs().dot(half),
            );
            lo = lo.min(centre - ext);
            hi = hi.max(centre + ext);
        }
        // A rotation between the poses sweeps corners along arcs: the chord-to-arc bulge is at most
        // r (1 - cos(angle/2)) <= r * angle^2 / 8.
        let angle = self.pose_prev.rotation.angle_between(self.pose.rotation);
        let bulge = half.length() * angle * angle / 8.0;
        (
            lo - Vec3::splat(margin + bulge),
            hi + Vec3::splat(margin + bulge),
        )
    }

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

/// Closest point on the surface of the box `[-half, half]` (f64, exact).
fn cuboid_closest(half: Vec3, p: Vec3) -> SurfacePoint {
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
fn cuboid_cast(half: Vec3, a: Vec3, d: Vec3) -> Option<SurfaceHit> {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
