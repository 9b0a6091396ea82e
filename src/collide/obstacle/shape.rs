//! The rigid obstacle: a parry shape with its pose at the start and end of the step, built from
//! validated dimensions; its swept bounding box.

use crate::collide::motion::Motion;
use crate::{Pose, Vec3};
use parry3d::shape::{SharedShape, TriMesh, TriMeshBuilderError, TriMeshFlags};

#[derive(Debug, thiserror::Error)]
pub enum ObstacleError {
    #[error("obstacle '{name}': invalid mesh: vertex {vertex} is not finite")]
    NonFiniteVertex { name: String, vertex: usize },
    #[error(
        "obstacle '{name}': invalid mesh: triangle {triangle} references a vertex >= {vertices}"
    )]
    IndexOutOfRange {
        name: String,
        triangle: usize,
        vertices: usize,
    },
    #[error("obstacle '{name}': invalid mesh: {source}")]
    Mesh {
        name: String,
        #[source]
        source: TriMeshBuilderError,
    },
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
        if let Some(vertex) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(ObstacleError::NonFiniteVertex {
                name: name.to_string(),
                vertex,
            });
        }
        if let Some(triangle) = indices
            .iter()
            .position(|t| t.iter().any(|&i| i as usize >= vertices.len()))
        {
            return Err(ObstacleError::IndexOutOfRange {
                name: name.to_string(),
                triangle,
                vertices: vertices.len(),
            });
        }
        let verts = vertices.iter().map(|v| v.as_vec3()).collect();
        let flags =
            TriMeshFlags::DELETE_DEGENERATE_TRIANGLES | TriMeshFlags::MERGE_DUPLICATE_VERTICES;
        let mesh = TriMesh::with_flags(verts, indices.to_vec(), flags).map_err(|source| {
            ObstacleError::Mesh {
                name: name.to_string(),
                source,
            }
        })?;
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

    /// The shape's local bounding box (infinite for a plane).
    pub(crate) fn local_bounds(&self) -> (Vec3, Vec3) {
        (self.local_min, self.local_max)
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
}
