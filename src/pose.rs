//! Rigid poses in f64, shared by obstacles, robot links and attachments.

use crate::Vec3;
use glam::{DMat3, DQuat};
use serde::{Deserialize, Serialize};

/// A rigid transform `x -> rotation * x + translation` (child frame expressed in parent frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub rotation: DQuat,
    pub translation: Vec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        rotation: DQuat::IDENTITY,
        translation: Vec3::ZERO,
    };

    pub fn new(translation: Vec3, rotation: DQuat) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    pub fn from_translation(translation: Vec3) -> Self {
        Self::new(translation, DQuat::IDENTITY)
    }

    /// URDF convention: roll about x, then pitch about y, then yaw about z (fixed axes),
    /// i.e. `R = Rz(yaw) * Ry(pitch) * Rx(roll)`.
    pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Self {
        let rot = DQuat::from_rotation_z(rpy[2])
            * DQuat::from_rotation_y(rpy[1])
            * DQuat::from_rotation_x(rpy[0]);
        Self::new(Vec3::from(xyz), rot)
    }

    /// The URDF roll, pitch and yaw of the rotation ([`Pose::from_xyz_rpy`]'s inverse), pitch in
    /// [-π/2, π/2]; at a pitch of ±π/2 the roll is 0 and the yaw carries the rest.
    pub fn rpy(&self) -> [f64; 3] {
        let m = DMat3::from_quat(self.rotation);
        let (c0, c1, c2) = (m.col(0), m.col(1), m.col(2));
        // atan2 rather than asin: exact near a pitch of ±π/2, where asin loses half the digits.
        let pitch = (-c0.z).atan2(c0.x.hypot(c0.y));
        if c0.x.hypot(c0.y) > 1e-12 {
            [c1.z.atan2(c2.z), pitch, c0.y.atan2(c0.x)]
        } else {
            [0.0, pitch, (-c1.x).atan2(c1.y)]
        }
    }

    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }

    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }

    pub fn inverse_transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation.inverse() * (p - self.translation)
    }

    pub fn inverse(&self) -> Pose {
        let inv = self.rotation.inverse();
        Pose::new(-(inv * self.translation), inv)
    }

    /// `self * other`: apply `other` first, then `self`.
    pub fn mul(&self, other: &Pose) -> Pose {
        Pose::new(
            self.rotation * other.translation + self.translation,
            (self.rotation * other.rotation).normalize(),
        )
    }

    pub fn rotation_matrix(&self) -> DMat3 {
        DMat3::from_quat(self.rotation)
    }

    /// Interpolates between two poses (linear translation, slerp rotation); `s` in [0, 1].
    /// Used to move obstacles smoothly across the substeps between two pose updates. The ends
    /// are exact: a link that stopped must compare equal to its last target, or the next frame
    /// sees it moving by round-off and treats it as a moving obstacle (fast-contact tests,
    /// moving-contact stiffness).
    pub fn lerp(&self, other: &Pose, s: f64) -> Pose {
        if s >= 1.0 {
            return *other;
        }
        if s <= 0.0 {
            return *self;
        }
        Pose::new(
            self.translation.lerp(other.translation, s),
            self.rotation.slerp(other.rotation, s).normalize(),
        )
    }

    /// Velocity of the material point currently at world position `p`, for a frame moving from
    /// `self` to `next` over `dt` seconds (finite rotation converted to an angular velocity).
    pub fn point_velocity(&self, next: &Pose, p: Vec3, dt: f64) -> Vec3 {
        if dt <= 0.0 {
            return Vec3::ZERO;
        }
        let local = self.inverse_transform_point(p);
        (next.transform_point(local) - p) / dt
    }

    pub fn is_finite(&self) -> bool {
        self.translation.is_finite() && self.rotation.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_inverts_from_xyz_rpy() {
        for rpy in [
            [0.4, -0.7, 1.9],
            [-3.0, 1.2, -2.5],
            [0.0, 0.0, 0.0],
            [1.0, std::f64::consts::FRAC_PI_2, 0.3],
        ] {
            let p = Pose::from_xyz_rpy([0.0; 3], rpy);
            let back = Pose::from_xyz_rpy([0.0; 3], p.rpy());
            assert!(
                p.rotation.angle_between(back.rotation) < 1e-9,
                "{rpy:?} -> {:?}",
                p.rpy()
            );
        }
        let r = Pose::from_xyz_rpy([0.0; 3], [0.4, -0.7, 1.9]).rpy();
        assert!(
            (r[0] - 0.4).abs() < 1e-12 && (r[1] + 0.7).abs() < 1e-12 && (r[2] - 1.9).abs() < 1e-12
        );
    }

    #[test]
    fn lerp_ends_exactly_on_its_poses() {
        let a = Pose::from_xyz_rpy([0.3, -1.0, 2.0], [0.4, -0.7, 1.9]);
        let b = Pose::from_xyz_rpy([0.1, 0.7, -0.2], [-1.1, 0.2, 0.3]);
        assert_eq!(a.lerp(&b, 1.0), b);
        assert_eq!(a.lerp(&b, 0.0), a);
        assert_eq!(b.lerp(&b, 1.0), b);
    }

    #[test]
    fn inverse_composes_to_identity() {
        let p = Pose::from_xyz_rpy([0.3, -1.0, 2.0], [0.4, -0.7, 1.9]);
        let q = p.mul(&p.inverse());
        assert!(q.translation.length() < 1e-12);
        assert!(q.rotation.angle_between(DQuat::IDENTITY) < 1e-9);
    }

    #[test]
    fn rpy_matches_urdf_convention() {
        // yaw 90 degrees maps x to y.
        let p = Pose::from_xyz_rpy([0.0; 3], [0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let v = p.transform_vector(Vec3::X);
        assert!((v - Vec3::Y).length() < 1e-12);
        // roll then pitch: R = Ry(pi/2) Rx(pi/2); z -> Rx: -y -> Ry: -y
        let p = Pose::from_xyz_rpy(
            [0.0; 3],
            [
                std::f64::consts::FRAC_PI_2,
                std::f64::consts::FRAC_PI_2,
                0.0,
            ],
        );
        let v = p.transform_vector(Vec3::Z);
        assert!((v - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-12, "{v}");
    }
}
