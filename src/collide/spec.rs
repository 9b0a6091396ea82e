//! Scene-file (YAML) description of obstacles and collision settings, with validation that
//! names the offending key path.
//!
//! Axis conventions: capsule and cylinder lie along the obstacle's local **y** axis, centred at
//! its origin (parry's convention); `box.half_extents` are local x/y/z half sizes; `plane.normal`
//! is the local outward normal of the free side through the local origin; `pose.rpy` is URDF
//! roll/pitch/yaw (fixed axes x, then y, then z), radians.

use super::motion::Motion;
use super::obstacle::{Obstacle, ObstacleError};
use super::settings::{CollisionSettings, DetectionMode, ResponseMode};
use crate::{Pose, Vec3};
use serde::{Deserialize, Serialize};

/// `shape: { type: sphere, radius: 0.3 }` etc.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeSpec {
    Sphere {
        radius: f64,
    },
    Box {
        half_extents: [f64; 3],
    },
    Capsule {
        radius: f64,
        half_height: f64,
    },
    Cylinder {
        radius: f64,
        half_height: f64,
    },
    Mesh {
        path: String,
        #[serde(default = "one3")]
        scale: [f64; 3],
    },
    Plane {
        normal: [f64; 3],
    },
}

fn one3() -> [f64; 3] {
    [1.0; 3]
}

#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    #[serde(default)]
    pub xyz: [f64; 3],
    #[serde(default)]
    pub rpy: [f64; 3],
}

impl PoseSpec {
    pub fn to_pose(&self) -> Pose {
        Pose::from_xyz_rpy(self.xyz, self.rpy)
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaypointSpec {
    pub t: f64,
    pub pose: PoseSpec,
}

/// `motion: { type: velocity, linear: [..], angular: [..] }`,
/// `{ type: waypoints, points: [ { t, pose }, .. ] }`, `{ type: static }` or `{ type: external }`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum MotionSpec {
    #[default]
    Static,
    /// m/s and rad/s in world axes.
    Velocity {
        linear: [f64; 3],
        angular: [f64; 3],
    },
    Waypoints {
        points: Vec<WaypointSpec>,
    },
    /// Driven by a robot link (the scene attaches it).
    External,
}

impl MotionSpec {
    pub fn to_motion(&self) -> Motion {
        match self {
            MotionSpec::Static => Motion::Static,
            MotionSpec::Velocity { linear, angular } => Motion::Velocity {
                linear: Vec3::from(*linear),
                angular: Vec3::from(*angular),
            },
            MotionSpec::Waypoints { points: w } => {
                Motion::Waypoints(w.iter().map(|w| (w.t, w.pose.to_pose())).collect())
            }
            MotionSpec::External => Motion::External,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    pub name: String,
    pub shape: ShapeSpec,
    #[serde(default)]
    pub pose: PoseSpec,
    #[serde(default)]
    pub motion: MotionSpec,
    /// Overrides the cloth's friction coefficient on this obstacle.
    #[serde(default)]
    pub friction: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionSpec {
    #[serde(default = "default_mode")]
    pub mode: DetectionMode,
    #[serde(default)]
    pub self_collision: bool,
    #[serde(default = "default_response")]
    pub response: ResponseMode,
    /// Cloth-cloth CCD passes before the impact-zone fail-safe.
    #[serde(default = "default_self_iterations")]
    pub self_iterations: usize,
    /// Impact-zone passes before the last-resort freeze of still-colliding vertices.
    #[serde(default = "default_zone_iterations")]
    pub zone_iterations: usize,
    /// Count exact triangle-triangle intersections every step (costly; for metrics).
    #[serde(default)]
    pub count_self_intersections: bool,
}

fn default_mode() -> DetectionMode {
    DetectionMode::Continuous
}
fn default_response() -> ResponseMode {
    ResponseMode::Both
}
fn default_self_iterations() -> usize {
    8
}
fn default_zone_iterations() -> usize {
    16
}

impl Default for CollisionSpec {
    fn default() -> Self {
        Self {
            mode: default_mode(),
            self_collision: false,
            response: default_response(),
            self_iterations: default_self_iterations(),
            zone_iterations: default_zone_iterations(),
            count_self_intersections: false,
        }
    }
}

/// A validation failure: the key path of the offending value and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {problem}")]
pub struct SpecError {
    pub path: String,
    pub problem: SpecProblem,
}

/// What is wrong with an obstacle or collision value (the key path is in [`SpecError`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SpecProblem {
    #[error("must be > 0, got {value}")]
    NotPositive { value: f64 },
    #[error("must be finite, got {values:?}")]
    NotFinite { values: Vec<f64> },
    #[error("must not be empty")]
    Empty,
    #[error("must be non-zero")]
    ZeroNormal,
    #[error("must be >= 0, got {value}")]
    Negative { value: f64 },
    #[error("times must increase ({previous} then {value})")]
    TimesNotIncreasing { previous: f64, value: f64 },
    #[error("duplicate obstacle name '{name}'")]
    DuplicateName { name: String },
    #[error("must be >= 1 for continuous self-collision")]
    NoSelfIterations,
}

fn err(path: String, problem: SpecProblem) -> SpecError {
    SpecError { path, problem }
}

fn check_pos(path: String, v: f64) -> Result<(), SpecError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(err(path, SpecProblem::NotPositive { value: v }))
    }
}

fn check_finite(path: String, v: &[f64]) -> Result<(), SpecError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(err(path, SpecProblem::NotFinite { values: v.to_vec() }))
    }
}

impl CollisionSpec {
    /// `prefix` is this spec's key path in the scene file (e.g. "collision").
    pub fn validate(&self, prefix: &str) -> Result<(), SpecError> {
        if self.self_collision
            && self.mode == DetectionMode::Continuous
            && self.self_iterations == 0
        {
            return Err(err(
                format!("{prefix}.self_iterations"),
                SpecProblem::NoSelfIterations,
            ));
        }
        Ok(())
    }

    pub fn settings(&self) -> CollisionSettings {
        CollisionSettings {
            mode: self.mode,
            self_collision: self.self_collision,
            response: self.response,
            self_iterations: self.self_iterations,
            zone_iterations: self.zone_iterations,
            count_self_intersections: self.count_self_intersections,
        }
    }
}

impl ObstacleSpec {
    /// `prefix` is this obstacle's key path, e.g. "obstacles[2]".
    pub fn validate(&self, prefix: &str) -> Result<(), SpecError> {
        if self.name.trim().is_empty() {
            return Err(err(format!("{prefix}.name"), SpecProblem::Empty));
        }
        let s = format!("{prefix}.shape");
        match &self.shape {
            ShapeSpec::Sphere { radius } => check_pos(format!("{s}.radius"), *radius)?,
            ShapeSpec::Box { half_extents } => {
                for (i, v) in half_extents.iter().enumerate() {
                    check_pos(format!("{s}.half_extents[{i}]"), *v)?;
                }
            }
            ShapeSpec::Capsule {
                radius,
                half_height,
            }
            | ShapeSpec::Cylinder {
                radius,
                half_height,
            } => {
                check_pos(format!("{s}.radius"), *radius)?;
                check_pos(format!("{s}.half_height"), *half_height)?;
            }
            ShapeSpec::Mesh { path, scale } => {
                if path.trim().is_empty() {
                    return Err(err(format!("{s}.path"), SpecProblem::Empty));
                }
                for (i, v) in scale.iter().enumerate() {
                    check_pos(format!("{s}.scale[{i}]"), *v)?;
                }
            }
            ShapeSpec::Plane { normal } => {
                check_finite(format!("{s}.normal"), normal)?;
                if Vec3::from(*normal).length() < 1e-12 {
                    return Err(err(format!("{s}.normal"), SpecProblem::ZeroNormal));
                }
            }
        }
        check_finite(format!("{prefix}.pose.xyz"), &self.pose.xyz)?;
        check_finite(format!("{prefix}.pose.rpy"), &self.pose.rpy)?;
        if let Some(mu) = self.friction {
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(err(
                    format!("{prefix}.friction"),
                    SpecProblem::Negative { value: mu },
                ));
            }
        }
        match &self.motion {
            MotionSpec::Velocity { linear, angular } => {
                check_finite(format!("{prefix}.motion.linear"), linear)?;
                check_finite(format!("{prefix}.motion.angular"), angular)?;
            }
            MotionSpec::Waypoints { points: w } => {
                if w.is_empty() {
                    return Err(err(format!("{prefix}.motion.points"), SpecProblem::Empty));
                }
                for (i, wp) in w.iter().enumerate() {
                    let p = format!("{prefix}.motion.points[{i}]");
                    check_finite(format!("{p}.t"), &[wp.t])?;
                    if i > 0 && wp.t <= w[i - 1].t {
                        return Err(err(
                            format!("{p}.t"),
                            SpecProblem::TimesNotIncreasing {
                                previous: w[i - 1].t,
                                value: wp.t,
                            },
                        ));
                    }
                    check_finite(format!("{p}.pose.xyz"), &wp.pose.xyz)?;
                    check_finite(format!("{p}.pose.rpy"), &wp.pose.rpy)?;
                }
            }
            MotionSpec::Static | MotionSpec::External => {}
        }
        Ok(())
    }

    /// Builds the obstacle. Mesh shapes need their triangles: `load_mesh` maps the (scene-relative)
    /// path to vertices/indices (the scene passes `crate::mesh::load_mesh`); they are scaled here.
    pub fn build<F, E>(&self, load_mesh: F) -> Result<Obstacle, BuildError>
    where
        F: FnOnce(&str) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), E>,
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        let pose = self.pose.to_pose();
        let n = &self.name;
        let obstacle = match &self.shape {
            ShapeSpec::Sphere { radius } => Obstacle::sphere(n, *radius, pose)?,
            ShapeSpec::Box { half_extents } => {
                Obstacle::cuboid(n, Vec3::from(*half_extents), pose)?
            }
            ShapeSpec::Capsule {
                radius,
                half_height,
            } => Obstacle::capsule(n, *radius, *half_height, pose)?,
            ShapeSpec::Cylinder {
                radius,
                half_height,
            } => Obstacle::cylinder(n, *radius, *half_height, pose)?,
            ShapeSpec::Plane { normal } => Obstacle::plane(n, Vec3::from(*normal), pose)?,
            ShapeSpec::Mesh { path, scale } => {
                let (v, i) = load_mesh(path).map_err(|e| BuildError::Mesh {
                    name: n.clone(),
                    path: path.clone(),
                    source: e.into(),
                })?;
                let s = Vec3::from(*scale);
                let v: Vec<Vec3> = v.iter().map(|p| *p * s).collect();
                Obstacle::mesh(n, &v, &i, pose)?
            }
        };
        Ok(obstacle
            .with_motion(self.motion.to_motion())
            .with_friction(self.friction))
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    #[error("obstacle '{name}': cannot load mesh '{path}'")]
    Mesh {
        name: String,
        path: String,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    #[error(transparent)]
    Obstacle(#[from] ObstacleError),
}

/// Validates a list of obstacles, giving paths like `obstacles[2].shape.radius`; names must be unique.
pub fn validate_obstacles(specs: &[ObstacleSpec], prefix: &str) -> Result<(), SpecError> {
    for (i, s) in specs.iter().enumerate() {
        let p = format!("{prefix}[{i}]");
        s.validate(&p)?;
        if specs[..i].iter().any(|o| o.name == s.name) {
            return Err(err(
                format!("{p}.name"),
                SpecProblem::DuplicateName {
                    name: s.name.clone(),
                },
            ));
        }
    }
    Ok(())
}
