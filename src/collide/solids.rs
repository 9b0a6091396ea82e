//! Inside tests of the obstacles, independent of the contact stage: where a point is inside an
//! obstacle's solid and how deep. A triangle mesh is a two-sided surface to the contact stage,
//! with no inside; here a point is inside a mesh where the mesh's generalised winding number
//! about it exceeds one half (Jacobson et al. 2013: robust to meshes that are not closed or whose
//! faces are wound inconsistently, as shipped collision meshes often are, where parry's
//! pseudo-normals answer "inside" half a metre away). Primitives answer by parry's projection.

use super::CollisionStage;
use crate::{Pose, Vec3};
use parry3d::shape::SharedShape;

/// Per obstacle of a stage, its mesh's winding test (`None`: a primitive, tested by parry).
#[derive(Debug, Clone)]
pub struct Solids(Vec<Option<Winding>>);

/// A mesh's triangles (local frame) and bounding box, for its winding number.
#[derive(Debug, Clone)]
struct Winding {
    triangles: Vec<[Vec3; 3]>,
    lo: Vec3,
    hi: Vec3,
}

impl Winding {
    fn of(shape: &SharedShape) -> Option<Self> {
        let m = shape.as_trimesh()?;
        let v: Vec<Vec3> = m.vertices().iter().map(|p| p.as_dvec3()).collect();
        let triangles: Vec<[Vec3; 3]> = (m.indices().iter())
            .map(|t| t.map(|i| v[i as usize]))
            .collect();
        let lo = v.iter().fold(Vec3::splat(f64::INFINITY), |a, p| a.min(*p));
        let hi = v
            .iter()
            .fold(Vec3::splat(f64::NEG_INFINITY), |a, p| a.max(*p));
        Some(Self { triangles, lo, hi })
    }

    /// True when local point `p` is inside (winding number above one half).
    fn contains(&self, p: Vec3) -> bool {
        if p.cmplt(self.lo).any() || p.cmpgt(self.hi).any() {
            return false;
        }
        // Each triangle's solid angle (Van Oosterom and Strackee 1983).
        let angle: f64 = (self.triangles.iter())
            .map(|t| {
                let (a, b, c) = (t[0] - p, t[1] - p, t[2] - p);
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
                2.0 * a.dot(b.cross(c)).atan2(den)
            })
            .sum();
        (angle / (4.0 * std::f64::consts::PI)).abs() > 0.5
    }
}

impl Solids {
    /// The inside tests of `stage`'s obstacles (a mesh's triangles are copied once).
    pub fn of(stage: &CollisionStage) -> Self {
        Self(
            (stage.obstacles().iter())
                .map(|o| Winding::of(&o.shape))
                .collect(),
        )
    }

    /// Whether these are the tests of `stage`'s obstacles (one per obstacle).
    pub fn covers(&self, stage: &CollisionStage) -> bool {
        self.0.len() == stage.obstacles().len()
    }

    /// Whether obstacle `k` is a mesh (tested by its winding number).
    pub fn is_mesh(&self, k: usize) -> bool {
        self.0.get(k).is_some_and(Option::is_some)
    }

    /// How deep world point `p` is inside obstacle `k` of `stage` at its current pose (m: its
    /// distance to the surface; 0 outside).
    pub fn depth_in(&self, stage: &CollisionStage, k: usize, p: Vec3) -> f64 {
        match stage.obstacles().get(k) {
            Some(o) => self.depth_at(stage, k, &o.pose, p),
            None => 0.0,
        }
    }

    /// How deep world point `p` is inside obstacle `k` of `stage` were the obstacle at `pose`
    /// (m; 0 outside): the inside test of a pose the obstacle takes later, e.g. a robot link's
    /// along its trajectory.
    pub fn depth_at(&self, stage: &CollisionStage, k: usize, pose: &Pose, p: Vec3) -> f64 {
        let (Some(o), Some(winding)) = (stage.obstacles().get(k), self.0.get(k)) else {
            return 0.0;
        };
        let local = pose.inverse_transform_point(p);
        // The cheap test first: most points are outside most obstacles' boxes.
        let inside = match winding {
            Some(w) => w.contains(local),
            None => o.shape.contains_local_point(local.as_vec3()),
        };
        if !inside {
            return 0.0;
        }
        let proj = o.shape.project_local_point(local.as_vec3(), false);
        local.distance(proj.point.as_dvec3())
    }

    /// How deep world point `p` is inside the deepest of `stage`'s obstacles at their current
    /// poses (m; 0 when it is inside none).
    pub fn depth(&self, stage: &CollisionStage, p: Vec3) -> f64 {
        (0..self.0.len())
            .map(|k| self.depth_in(stage, k, p))
            .fold(0.0, f64::max)
    }
}
