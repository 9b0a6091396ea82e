//! Grasp and release: a gripper link holds the cloth vertices between its finger pads while its
//! finger joints are closed.
//!
//! Holding cloth through contact forces alone fails in practice (vertices squeeze out between
//! the fingers, or the squeeze explodes), so a grasp is a rule: when the fingers' opening drops
//! below `close_below`, every free cloth vertex inside the pad box becomes attached to the
//! gripper link with its current offset; when the opening rises above `open_above` they are
//! released with the gripper's point velocity. The gap between the two thresholds is a
//! hysteresis band, so fingers that hover near one threshold do not grab and drop every step.

use super::{JointPositions, Kinematics};
use crate::{Pose, Vec3};

/// A grasp rule that makes no sense; names the culprit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GraspError {
    #[error("close_below ({close_below}) must be finite and below open_above ({open_above})")]
    Thresholds { close_below: f64, open_above: f64 },
    #[error("pad half extents {0:?} must be finite and > 0")]
    Pads([f64; 3]),
    #[error("a grasp needs at least one finger joint")]
    NoFingers,
    #[error("finger joint index {0} is out of range")]
    BadJoint(usize),
}

/// What a grasp does on a change of the finger opening.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GraspEvent {
    Close,
    Open,
}

/// Two-threshold switch on the finger opening: closes below `close_below`, opens above
/// `open_above`, keeps its state in between.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    close_below: f64,
    open_above: f64,
    closed: bool,
}

impl Hysteresis {
    /// Starts open.
    pub fn new(close_below: f64, open_above: f64) -> Result<Self, GraspError> {
        if !(close_below.is_finite() && open_above.is_finite() && close_below < open_above) {
            return Err(GraspError::Thresholds {
                close_below,
                open_above,
            });
        }
        Ok(Self {
            close_below,
            open_above,
            closed: false,
        })
    }

    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// Feeds the current opening; returns the event when the state changes. A non-finite
    /// opening changes nothing.
    pub fn update(&mut self, opening: f64) -> Option<GraspEvent> {
        if !self.closed && opening < self.close_below {
            self.closed = true;
            Some(GraspEvent::Close)
        } else if self.closed && opening > self.open_above {
            self.closed = false;
            Some(GraspEvent::Open)
        } else {
            None
        }
    }
}

/// The region between the finger pads: a box in the gripper link frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PadBox {
    /// Box centre and orientation in the link frame.
    pub pose: Pose,
    pub half_extents: Vec3,
}

impl PadBox {
    pub fn new(pose: Pose, half_extents: Vec3) -> Result<Self, GraspError> {
        if !(half_extents.is_finite() && half_extents.cmpgt(Vec3::ZERO).all()) {
            return Err(GraspError::Pads(half_extents.to_array()));
        }
        Ok(Self { pose, half_extents })
    }

    /// World point `p` in box coordinates, with the link at `link_pose`.
    pub fn box_coordinates(&self, link_pose: &Pose, p: Vec3) -> Vec3 {
        self.pose
            .inverse_transform_point(link_pose.inverse_transform_point(p))
    }

    /// How far `p` is outside the box along its worst axis (<= 0 inside).
    pub fn excess(&self, link_pose: &Pose, p: Vec3) -> f64 {
        (self.box_coordinates(link_pose, p).abs() - self.half_extents).max_element()
    }

    pub fn contains(&self, link_pose: &Pose, p: Vec3) -> bool {
        self.excess(link_pose, p) <= 0.0
    }
}

/// A gripper's grasp rule and what it holds.
#[derive(Debug, Clone)]
pub struct Grasp {
    /// Gripper link index (the robot's link order).
    pub link: usize,
    /// Simulation frame following the link.
    pub frame: usize,
    /// Finger joints; the opening is the largest of their positions (mimic joints resolved).
    pub fingers: Vec<usize>,
    pub pads: PadBox,
    /// Cloth vertices the rule may take (a piece's range, or all).
    pub candidates: std::ops::Range<usize>,
    state: Hysteresis,
    held: Vec<u32>,
}

impl Grasp {
    pub fn new(
        link: usize,
        frame: usize,
        fingers: Vec<usize>,
        state: Hysteresis,
        pads: PadBox,
        candidates: std::ops::Range<usize>,
    ) -> Result<Self, GraspError> {
        if fingers.is_empty() {
            return Err(GraspError::NoFingers);
        }
        Ok(Self {
            link,
            frame,
            fingers,
            pads,
            candidates,
            state,
            held: Vec::new(),
        })
    }

    pub fn is_closed(&self) -> bool {
        self.state.is_closed()
    }

    /// Vertices held now.
    pub fn held(&self) -> &[u32] {
        &self.held
    }

    /// The fingers' opening at `q`: the largest finger joint position.
    pub fn opening(&self, kin: &Kinematics, q: &JointPositions) -> f64 {
        self.fingers
            .iter()
            .map(|&j| joint_value(kin, q, j))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Feeds the opening; returns the event to act on.
    pub fn update(&mut self, opening: f64) -> Option<GraspEvent> {
        self.state.update(opening)
    }

    /// Candidates inside the pads with the link at `link_pose`, skipping `skip`ped vertices.
    pub fn between_pads(
        &self,
        x: &[Vec3],
        link_pose: &Pose,
        skip: impl Fn(u32) -> bool,
    ) -> Vec<u32> {
        let end = self.candidates.end.min(x.len());
        (self.candidates.start..end)
            .filter(|&i| self.pads.contains(link_pose, x[i]))
            .map(|i| i as u32)
            .filter(|&i| !skip(i))
            .collect()
    }

    pub(crate) fn set_held(&mut self, held: Vec<u32>) {
        self.held = held;
    }

    pub(crate) fn take_held(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.held)
    }
}

/// Position of joint `j` at `q`, following a mimic joint to its source.
pub fn joint_value(kin: &Kinematics, q: &JointPositions, j: usize) -> f64 {
    let joint = &kin.joints()[j];
    match joint.mimic {
        Some(m) => m.multiplier * q.positions[m.joint] + m.offset,
        None => q.positions[j],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn hysteresis_switches_only_past_the_thresholds() {
        let mut h = Hysteresis::new(0.01, 0.02).unwrap();
        // Closing: nothing until the opening drops below 0.01.
        let closing = [0.04, 0.03, 0.02, 0.015, 0.0101];
        assert!(closing.iter().all(|&o| h.update(o).is_none()));
        assert_eq!(h.update(0.0099), Some(GraspEvent::Close));
        // Inside the band and at the thresholds themselves it stays closed.
        for o in [0.0, 0.005, 0.01, 0.015, 0.02, f64::NAN] {
            assert_eq!(h.update(o), None, "{o}");
            assert!(h.is_closed());
        }
        assert_eq!(h.update(0.0201), Some(GraspEvent::Open));
        // Back inside the band it stays open.
        for o in [0.02, 0.015, 0.01] {
            assert_eq!(h.update(o), None, "{o}");
            assert!(!h.is_closed());
        }
        assert_eq!(h.update(0.0), Some(GraspEvent::Close));
    }

    #[test]
    fn bad_rules_are_refused() {
        assert!(Hysteresis::new(0.02, 0.02).is_err());
        assert!(Hysteresis::new(f64::NAN, 0.02).is_err());
        assert!(PadBox::new(Pose::IDENTITY, Vec3::new(0.01, 0.0, 0.01)).is_err());
        let h = Hysteresis::new(0.0, 1.0).unwrap();
        let pads = PadBox::new(Pose::IDENTITY, Vec3::ONE).unwrap();
        assert_eq!(
            Grasp::new(0, 0, vec![], h, pads, 0..1).unwrap_err(),
            GraspError::NoFingers
        );
    }

    #[test]
    fn pad_box_is_in_the_link_frame() {
        let pads = PadBox::new(
            Pose::from_translation(Vec3::new(0.0, 0.0, -0.1)),
            Vec3::new(0.01, 0.02, 0.03),
        )
        .unwrap();
        let link = Pose::new(
            Vec3::new(1.0, 2.0, 3.0),
            DQuat::from_rotation_x(std::f64::consts::PI),
        );
        // The link is upside down: its local -z is world +z.
        assert!(pads.contains(&link, Vec3::new(1.0, 2.0, 3.1)));
        assert!(!pads.contains(&link, Vec3::new(1.0, 2.0, 2.9)));
        assert!((pads.excess(&link, Vec3::new(1.0, 2.05, 3.1)) - 0.03).abs() < 1e-12);
    }
}
