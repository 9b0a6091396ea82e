//! Moving frames that kinematic vertices attach to (scripted, or robot links moved from
//! outside), and the world target of a kinematic vertex at a fraction of the frame step.

use crate::cloth::Kinematic;
use crate::{Pose, Vec3};

/// A frame's pose as a function of time.
pub type FrameScript = Box<dyn Fn(f64) -> Pose + Send + Sync>;

/// Moving frames that kinematic vertices attach to. A frame step moves each frame from `start`
/// to `end`; substeps see poses interpolated between the two, so fast motion is not a jump.
#[derive(Default)]
pub struct Frames {
    pub names: Vec<String>,
    start: Vec<Pose>,
    end: Vec<Pose>,
    /// Scripted frames know their pose at any time; the others are moved from outside
    /// (robot links) through [`super::Simulation::set_frame_target`].
    script: Vec<Option<FrameScript>>,
}

impl Frames {
    /// Adds a frame moved from outside.
    pub fn add(&mut self, name: &str, pose: Pose) -> usize {
        self.names.push(name.to_string());
        self.start.push(pose);
        self.end.push(pose);
        self.script.push(None);
        self.names.len() - 1
    }

    /// Adds a frame that follows a script.
    pub fn add_scripted(&mut self, name: &str, script: FrameScript) -> usize {
        let i = self.add(name, script(0.0));
        self.script[i] = Some(script);
        i
    }

    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Pose at fraction `s` of the current frame step.
    pub fn at(&self, frame: usize, s: f64) -> Pose {
        self.start[frame].lerp(&self.end[frame], s)
    }

    /// Current (end-of-step) pose.
    pub fn pose(&self, frame: usize) -> Pose {
        self.end[frame]
    }

    /// Pose at the simulation's current time, even after a target for the next step was set.
    pub fn pose_now(&self, frame: usize) -> Pose {
        self.start[frame]
    }

    /// Sets where a frame will be at the end of the next frame step.
    pub(super) fn set_target(&mut self, frame: usize, pose: Pose) {
        self.end[frame] = pose;
    }

    /// Scripted frames get their end-of-step pose at time `t_end`.
    pub(super) fn script_targets(&mut self, t_end: f64) {
        for f in 0..self.len() {
            if let Some(script) = &self.script[f] {
                self.end[f] = script(t_end);
            }
        }
    }

    /// The frame step is done: every frame starts the next one where this one ended.
    pub(super) fn finish_step(&mut self) {
        for f in 0..self.len() {
            self.start[f] = self.end[f];
        }
    }

    /// Scripted frames back at their t = 0 pose (the clock restarts).
    pub(super) fn restart(&mut self) {
        for f in 0..self.len() {
            if let Some(script) = &self.script[f] {
                let p = script(0.0);
                self.start[f] = p;
                self.end[f] = p;
            }
        }
    }

    /// World position of a kinematic vertex at fraction `s` of the frame step.
    pub(super) fn target(&self, k: &Kinematic, s: f64) -> Vec3 {
        match *k {
            Kinematic::Pinned(p) => p,
            Kinematic::Attached { frame, local } => self.at(frame, s).transform_point(local),
        }
    }
}
