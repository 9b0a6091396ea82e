//! What crosses between the node's two threads, and what the simulation side counts: the
//! [`Command`]s the DDS side sends, the [`Output`]s it publishes, and the running totals
//! ([`LoopStats`], [`DroppedInputs`]) that `/diagnostics` reports. Plain data, no logic that
//! needs the simulation, so both sides and the message builders depend on this file alone.

use crate::robot::JointInput;
use crate::ros::msg::{DiagnosticArray, Marker, MarkerArray, PointCloud2};
use crate::scene::SceneError;
use std::sync::Arc;

/// Something for the simulation thread to do.
#[derive(Debug, Clone)]
pub enum Command {
    /// A joint state: its header stamp (0: unstamped) and content.
    Joints {
        stamp_ns: i64,
        input: JointInput,
    },
    /// A URDF (e.g. from `/robot_description`): rebuild the scene with this robot.
    RobotDescription(String),
    /// Simulated clock time (s) from `/clock`; ignored on the wall clock.
    Clock(f64),
    /// Restore the initial cloth; answered by [`Output::ResetDone`] with the same id.
    Reset {
        id: u64,
    },
    Pause(bool),
    PublishRate(f64),
    /// New constant wind velocity (m/s) for a scene that names wind; kept across resets.
    Wind([f64; 3]),
    Stop,
}

/// Log severity of an [`Output::Log`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    Info,
    Warn,
    Error,
}

/// Something for the DDS side to publish.
#[derive(Debug, Clone)]
pub enum Output {
    Frame {
        mesh: Box<Marker>,
        points: Box<PointCloud2>,
    },
    Obstacles(MarkerArray),
    Diagnostics(DiagnosticArray),
    Log {
        level: Level,
        text: String,
    },
    /// The reset's outcome; the DDS side turns an error's chain into the reply's message.
    ResetDone {
        id: u64,
        result: Result<String, Arc<SceneError>>,
    },
}

/// Why joint states were dropped, counted per reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DroppedInputs {
    pub non_finite: u64,
    pub wrong_length: u64,
    pub unknown_joint: u64,
    pub out_of_order: u64,
    /// Duplicate names, free joints, or no robot in the scene.
    pub other: u64,
}

impl DroppedInputs {
    pub fn total(&self) -> u64 {
        self.non_finite + self.wrong_length + self.unknown_joint + self.out_of_order + self.other
    }
}

/// Running totals since start.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoopStats {
    pub steps: u64,
    pub frames: u64,
    pub joint_states: u64,
    pub dropped: DroppedInputs,
    pub divergences: u64,
    pub descriptions_loaded: u64,
    pub description_failures: u64,
    pub resets: u64,
}
