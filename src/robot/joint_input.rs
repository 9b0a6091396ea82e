//! Joint commands from outside (ROS `JointState`, scene-file trajectories), validated before
//! they touch the robot state: a bad message is rejected whole and the state stays as it was.

use super::kinematics::{JointKind, JointPositions, Kinematics};
use crate::Pose;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// One named joint update, e.g. a `sensor_msgs/JointState`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointInput {
    pub names: Vec<String>,
    pub positions: Vec<f64>,
    pub velocities: Option<Vec<f64>>,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JointInputError {
    #[error("joint input is empty")]
    Empty,
    #[error("joint input has {names} names but {values} {what}")]
    LengthMismatch {
        names: usize,
        values: usize,
        what: &'static str,
    },
    #[error("unknown joint `{0}`")]
    UnknownJoint(String),
    #[error("joint `{0}` appears twice")]
    Duplicate(String),
    #[error("joint `{0}` is not a floating or planar joint")]
    NotFree(String),
    #[error("joint `{0}`: pose is not finite")]
    NonFinitePose(String),
    #[error("joint `{name}`: {what} {value} is not finite")]
    NotFinite {
        name: String,
        what: &'static str,
        value: f64,
    },
}

impl JointInput {
    /// Checks the whole message, then writes positions of the named joints into `q`.
    /// Names of mimic, fixed or free joints are accepted (joint_states often lists them) but
    /// their values are not used: mimics follow their source.
    pub fn apply(&self, kin: &Kinematics, q: &mut JointPositions) -> Result<(), JointInputError> {
        self.validate(kin)?;
        if q.positions.len() < kin.joints().len() {
            q.positions.resize(kin.joints().len(), 0.0);
        }
        for (name, &p) in self.names.iter().zip(&self.positions) {
            if let Some(ji) = kin.joint_index(name) {
                q.positions[ji] = p;
            }
        }
        Ok(())
    }

    /// All checks of [`JointInput::apply`] without writing anything.
    pub fn validate(&self, kin: &Kinematics) -> Result<(), JointInputError> {
        if self.names.is_empty() && self.positions.is_empty() {
            return Err(JointInputError::Empty);
        }
        if self.names.len() != self.positions.len() {
            return Err(JointInputError::LengthMismatch {
                names: self.names.len(),
                values: self.positions.len(),
                what: "positions",
            });
        }
        if let Some(v) = &self.velocities {
            // ROS allows an empty velocity array meaning "not provided".
            if !v.is_empty() && v.len() != self.names.len() {
                return Err(JointInputError::LengthMismatch {
                    names: self.names.len(),
                    values: v.len(),
                    what: "velocities",
                });
            }
        }
        for (i, name) in self.names.iter().enumerate() {
            if kin.joint_index(name).is_none() {
                return Err(JointInputError::UnknownJoint(name.clone()));
            }
            if self.names[..i].contains(name) {
                return Err(JointInputError::Duplicate(name.clone()));
            }
            let p = self.positions[i];
            if !p.is_finite() {
                return Err(JointInputError::NotFinite {
                    name: name.clone(),
                    what: "position",
                    value: p,
                });
            }
            if let Some(&v) = self.velocities.as_ref().and_then(|v| v.get(i)) {
                if !v.is_finite() {
                    return Err(JointInputError::NotFinite {
                        name: name.clone(),
                        what: "velocity",
                        value: v,
                    });
                }
            }
        }
        Ok(())
    }
}

/// Sets the motion of floating/planar joints from a name -> pose map (e.g. a tracked base),
/// after checking every entry; on error nothing is written.
pub fn apply_free_poses(
    kin: &Kinematics,
    poses: &HashMap<String, Pose>,
    q: &mut JointPositions,
) -> Result<(), JointInputError> {
    for (name, pose) in poses {
        let ji = kin
            .joint_index(name)
            .ok_or_else(|| JointInputError::UnknownJoint(name.clone()))?;
        if !matches!(
            kin.joints()[ji].kind,
            JointKind::Floating | JointKind::Planar
        ) {
            return Err(JointInputError::NotFree(name.clone()));
        }
        if !pose.is_finite() {
            return Err(JointInputError::NonFinitePose(name.clone()));
        }
    }
    if q.free_poses.len() < kin.joints().len() {
        q.free_poses.resize(kin.joints().len(), None);
    }
    for (name, pose) in poses {
        if let Some(ji) = kin.joint_index(name) {
            q.free_poses[ji] = Some(*pose);
        }
    }
    Ok(())
}

/// A scripted joint motion for the scene file:
/// `joints: {names: [...], points: [{t: 0.0, positions: [...]}, ...]}`.
/// Positions are interpolated linearly between points and held before the first / after
/// the last.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointTrajectory {
    pub names: Vec<String>,
    pub points: Vec<TrajectoryPoint>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectoryPoint {
    /// Seconds from the start of the simulation.
    pub t: f64,
    pub positions: Vec<f64>,
}

/// A trajectory segment faster than a joint's URDF velocity limit
/// ([`JointTrajectory::overspeed`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Overspeed {
    pub joint: String,
    pub from_t: f64,
    pub to_t: f64,
    /// The joint's speed over the segment, in multiples of its limit (> 1).
    pub factor: f64,
    /// The limit (rad/s or m/s).
    pub limit: f64,
}

impl std::fmt::Display for Overspeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "joint `{}` moves at {:.3} times its URDF velocity limit ({}) between t = {} s and \
             {} s",
            self.joint, self.factor, self.limit, self.from_t, self.to_t
        )
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrajectoryError {
    #[error("trajectory has no points")]
    NoPoints,
    #[error("trajectory point {index}: {found} positions for {expected} joint names")]
    Length {
        index: usize,
        expected: usize,
        found: usize,
    },
    #[error("trajectory point {index}: time {t} is not finite or not after the previous point")]
    Time { index: usize, t: f64 },
    #[error("trajectory point {index}: {source}")]
    Input {
        index: usize,
        #[source]
        source: JointInputError,
    },
}

impl JointTrajectory {
    /// Checks times (finite, strictly increasing), lengths, names and values against `kin`.
    pub fn validate(&self, kin: &Kinematics) -> Result<(), TrajectoryError> {
        if self.points.is_empty() {
            return Err(TrajectoryError::NoPoints);
        }
        let mut prev = f64::NEG_INFINITY;
        for (index, p) in self.points.iter().enumerate() {
            if p.positions.len() != self.names.len() {
                return Err(TrajectoryError::Length {
                    index,
                    expected: self.names.len(),
                    found: p.positions.len(),
                });
            }
            if !p.t.is_finite() || p.t <= prev {
                return Err(TrajectoryError::Time { index, t: p.t });
            }
            prev = p.t;
            self.input(p.positions.clone())
                .validate(kin)
                .map_err(|source| TrajectoryError::Input { index, source })?;
        }
        Ok(())
    }

    /// Interpolated positions at time `t` (same order as `names`); empty if there are no points.
    pub fn positions_at(&self, t: f64) -> Vec<f64> {
        let pts = &self.points;
        let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
            return Vec::new();
        };
        if t <= first.t {
            return first.positions.clone();
        }
        if t >= last.t {
            return last.positions.clone();
        }
        // First point with time > t; t is strictly inside (first.t, last.t).
        let k = pts.partition_point(|p| p.t <= t).clamp(1, pts.len() - 1);
        let (a, b) = (&pts[k - 1], &pts[k]);
        let s = (t - a.t) / (b.t - a.t);
        a.positions
            .iter()
            .zip(&b.positions)
            .map(|(x, y)| x + (y - x) * s)
            .collect()
    }

    /// The segment where a joint moves fastest against its URDF velocity limit, when one moves
    /// faster than it (the cloth then sees a motion the robot cannot make). Call after
    /// [`JointTrajectory::validate`].
    pub fn overspeed(&self, kin: &Kinematics) -> Option<Overspeed> {
        let at = |p: &TrajectoryPoint| {
            let mut q = kin.zero_positions();
            let applied = self.input(p.positions.clone()).apply(kin, &mut q);
            applied.ok().map(|()| q)
        };
        let mut worst: Option<Overspeed> = None;
        for w in self.points.windows(2) {
            let (Some(a), Some(b)) = (at(&w[0]), at(&w[1])) else {
                continue;
            };
            let Some((ji, t)) = kin.slowest_joint(&a, &b) else {
                continue;
            };
            let factor = t / (w[1].t - w[0].t);
            // A millionth over: a trajectory written at exactly the limit (the hard cases'
            // swings) is over by rounding of its times and positions.
            if factor > 1.0 + 1e-6 && worst.as_ref().is_none_or(|o| factor > o.factor) {
                let j = &kin.joints()[ji];
                worst = Some(Overspeed {
                    joint: j.name.clone(),
                    from_t: w[0].t,
                    to_t: w[1].t,
                    factor,
                    limit: j.velocity_limit.unwrap_or(0.0),
                });
            }
        }
        worst
    }

    /// The trajectory sampled at `t` as a [`JointInput`].
    pub fn input_at(&self, t: f64) -> JointInput {
        self.input(self.positions_at(t))
    }

    /// `positions` (in the order of `names`) as a [`JointInput`].
    fn input(&self, positions: Vec<f64>) -> JointInput {
        JointInput {
            names: self.names.clone(),
            positions,
            velocities: None,
        }
    }
}
