//! Scripted obstacle motion: static, constant twist, or pose waypoints.

use crate::{Pose, Vec3};
use glam::DQuat;
use serde::{Deserialize, Serialize};

/// How an obstacle moves over time. `External` obstacles (robot links) get their poses from
/// `CollisionStage::set_obstacle_pose`; the others are evaluated by `pose_at`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Motion {
    #[default]
    Static,
    /// Constant linear velocity (m/s, world) and angular velocity (rad/s, world axis through the
    /// obstacle origin), starting from the initial pose at t = 0.
    Velocity {
        linear: Vec3,
        angular: Vec3,
    },
    /// `(time_s, pose)` pairs sorted by time: linear translation / slerp rotation between them,
    /// clamped to the first/last pose outside the range.
    Waypoints(Vec<(f64, Pose)>),
    External,
}

impl Motion {
    /// Pose at time `t` for an obstacle whose pose at t = 0 is `initial`. `Static` and `External`
    /// return `initial` (external poses are set by the caller).
    pub fn pose_at(&self, initial: &Pose, t: f64) -> Pose {
        match self {
            Motion::Static | Motion::External => *initial,
            Motion::Velocity { linear, angular } => {
                let angle = angular.length() * t;
                let rot = if angle > 0.0 {
                    DQuat::from_axis_angle(angular.normalize(), angle)
                } else {
                    DQuat::IDENTITY
                };
                Pose::new(
                    initial.translation + *linear * t,
                    (rot * initial.rotation).normalize(),
                )
            }
            Motion::Waypoints(w) => match w.len() {
                0 => *initial,
                _ => {
                    if t <= w[0].0 {
                        return w[0].1;
                    }
                    for pair in w.windows(2) {
                        let (ta, pa) = pair[0];
                        let (tb, pb) = pair[1];
                        if t <= tb {
                            let s = if tb > ta { (t - ta) / (tb - ta) } else { 1.0 };
                            return pa.lerp(&pb, s);
                        }
                    }
                    w[w.len() - 1].1
                }
            },
        }
    }

    pub fn is_scripted(&self) -> bool {
        !matches!(self, Motion::External)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waypoints_interpolate_and_clamp() {
        let a = Pose::from_translation(Vec3::ZERO);
        let b = Pose::from_xyz_rpy([2.0, 0.0, 0.0], [0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let m = Motion::Waypoints(vec![(1.0, a), (3.0, b)]);
        assert_eq!(m.pose_at(&Pose::IDENTITY, 0.0), a);
        assert_eq!(m.pose_at(&Pose::IDENTITY, 5.0), b);
        let mid = m.pose_at(&Pose::IDENTITY, 2.0);
        assert!((mid.translation - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-12);
        let x = mid.transform_vector(Vec3::X);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((x - Vec3::new(h, h, 0.0)).length() < 1e-12, "{x}");
    }

    #[test]
    fn velocity_motion_rotates_about_origin() {
        let init = Pose::from_translation(Vec3::new(0.0, 0.0, 1.0));
        let m = Motion::Velocity {
            linear: Vec3::new(1.0, 0.0, 0.0),
            angular: Vec3::new(0.0, 0.0, std::f64::consts::PI),
        };
        let p = m.pose_at(&init, 0.5);
        assert!((p.translation - Vec3::new(0.5, 0.0, 1.0)).length() < 1e-12);
        assert!((p.transform_vector(Vec3::X) - Vec3::Y).length() < 1e-12);
    }
}
