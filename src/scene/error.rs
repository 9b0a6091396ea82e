//! [`SceneError`]: everything that can be wrong with a scene, from reading its file to building
//! it, as variants with fields (the file, the key path, the name or value at fault) and the
//! lower layer's error as `source()`; the command line prints the chain.

use super::problem::Problem;
use crate::collide::{BuildError, ObstacleError, StageError};
use crate::robot::{GraspError, TrajectoryError};

// Sources are boxed: the error stays small on the `Ok` path of every build.

/// What kind of thing a scene named that does not exist ([`SceneError::UnknownName`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameKind {
    Frame,
    RobotLink,
    RobotJoint,
    Cloth,
}

impl std::fmt::Display for NameKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NameKind::Frame => "frame",
            NameKind::RobotLink => "robot link",
            NameKind::RobotJoint => "robot joint",
            NameKind::Cloth => "cloth",
        })
    }
}

/// A scene that could not be read or makes no sense. Every message starts with the scene's
/// file (or the origin given to [`Scene::from_yaml`]), then the key path; the cause, if any, is
/// the error's `source()`, printed once by the command line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The file could not be read (missing, not a regular file, too large, not UTF-8).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    /// Not YAML, or not a scene (unknown key, wrong type); the YAML error gives the place.
    #[error("{origin}: not a valid scene")]
    Parse {
        origin: String,
        #[source]
        source: serde_yaml_ng::Error,
    },
    /// Flow collections nested deeper than the parser can take in linear time.
    #[error("{origin}: line {line}: YAML nested deeper than {max} levels")]
    TooDeep {
        origin: String,
        line: usize,
        max: usize,
    },
    /// A value that makes the run meaningless or unbounded.
    #[error("{origin}: {key}: {problem}")]
    Value {
        origin: String,
        key: String,
        problem: Box<Problem>,
    },
    /// A name the scene refers to that does not exist (a frame, a robot link or joint, a cloth).
    #[error("{origin}: {key}: no {kind} named '{name}'")]
    UnknownName {
        origin: String,
        key: String,
        kind: NameKind,
        name: String,
    },
    /// A selection that picks no vertex of its cloth.
    #[error("{origin}: {key}: selects no vertex of cloth '{cloth}'")]
    EmptySelection {
        origin: String,
        key: String,
        cloth: String,
    },
    /// The robot's scripted trajectory does not fit the robot (key: the name or value at fault).
    #[error("{origin}: {key}")]
    Trajectory {
        origin: String,
        key: String,
        #[source]
        source: Box<TrajectoryError>,
    },
    /// A grasp rule that cannot be made (thresholds, pads, fingers).
    #[error("{origin}: {key}")]
    Grasp {
        origin: String,
        key: String,
        #[source]
        source: Box<GraspError>,
    },
    /// A pose with a non-finite component.
    #[error("{origin}: {key}: pose must be finite")]
    NonFinitePose { origin: String, key: String },
    /// A scripted obstacle that cannot be made (its shape, or its mesh file).
    #[error("{origin}: {key}")]
    Obstacle {
        origin: String,
        key: String,
        #[source]
        source: Box<BuildError>,
    },
    /// A robot link's collision shape that cannot be made into an obstacle.
    #[error("{origin}: robot.urdf: link `{link}`")]
    LinkObstacle {
        origin: String,
        link: String,
        #[source]
        source: Box<ObstacleError>,
    },
    /// The collision stage cannot be built for this cloth and these obstacles.
    #[error("{origin}: collision")]
    Collision {
        origin: String,
        #[source]
        source: Box<StageError>,
    },
    /// The scene's garments could not be dressed (key: the garment's value at fault, or
    /// `garments` when the sewing of them all failed).
    #[error("{origin}: {key}")]
    Garment {
        origin: String,
        key: String,
        #[source]
        source: Box<crate::garment::GarmentError>,
    },
    /// The scene's robot could not be loaded.
    #[error("{origin}: robot.urdf")]
    Robot {
        origin: String,
        #[source]
        source: Box<crate::robot::RobotError>,
    },
}

impl SceneError {
    /// The key path of the value at fault, if the error has one.
    pub fn key(&self) -> Option<&str> {
        match self {
            SceneError::Value { key, .. }
            | SceneError::UnknownName { key, .. }
            | SceneError::EmptySelection { key, .. }
            | SceneError::Trajectory { key, .. }
            | SceneError::Grasp { key, .. }
            | SceneError::NonFinitePose { key, .. }
            | SceneError::Obstacle { key, .. }
            | SceneError::Garment { key, .. } => Some(key),
            SceneError::LinkObstacle { .. } => Some("robot.urdf"),
            SceneError::Collision { .. } => Some("collision"),
            SceneError::Robot { .. } => Some("robot.urdf"),
            _ => None,
        }
    }
}
