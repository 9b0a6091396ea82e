//! How the simulation loop runs: its publishing rates, frame and colour, and how low it may
//! take the solver's quality to hold real time ([`LoopConfig`]).

use super::quality::QualityBounds;
use crate::ros::Distro;

/// How the loop publishes.
#[derive(Debug, Clone)]
pub struct LoopConfig {
    /// Node name: diagnostics status name and marker namespace.
    pub name: String,
    pub distro: Distro,
    /// Empty: the robot's root link, else `world`.
    pub frame_id: String,
    pub publish_rate: f64,
    /// 0: no obstacle markers.
    pub obstacles_rate: f64,
    pub diagnostics_rate: f64,
    pub max_backlog_steps: u32,
    /// Joint states are reached no faster than the URDF's velocity limits allow
    /// ([`super::JointGate::velocity_limits`]).
    pub joint_velocity_limits: bool,
    pub paused: bool,
    pub color: [f32; 4],
    /// Adaptive quality within these bounds (see [`super::quality`]); `None`: the scene's
    /// quality, fixed (the default here, so a loop driven on a synthetic clock steps the same
    /// on any machine; `drape node` turns it on unless `adaptive_quality: false`).
    pub quality: Option<QualityBounds>,
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            name: "drape".into(),
            distro: Distro::Jazzy,
            frame_id: String::new(),
            publish_rate: 30.0,
            obstacles_rate: 2.0,
            diagnostics_rate: 1.0,
            max_backlog_steps: 6,
            joint_velocity_limits: true,
            paused: false,
            color: [0.85, 0.35, 0.2, 1.0],
            quality: None,
        }
    }
}
