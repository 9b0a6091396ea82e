//! The live ROS 2 node (`drape node`): joint states in, cloth out at a fixed rate.
//!
//! Two threads with one direction of data each: the DDS thread ([`dds`]) turns subscriptions
//! into [`Command`]s and publishes [`Output`]s; the simulation thread ([`sim_loop`]) steps at a
//! fixed `dt` paced by the wall clock or `/clock` ([`pacer`]) and never touches DDS.

pub mod dds;
pub mod network;
pub mod outputs;
pub mod pacer;
pub mod params;
pub mod sim_loop;

pub use dds::{context, resolve_topic, run_node, NodeSummary};
pub use network::Network;
pub use pacer::{Pacer, Schedule};
pub use params::{
    parse_ros_args, DescriptionSource, NodeParams, ParamsError, RosArgs, ServiceWire,
};
pub use sim_loop::{
    real_time_preview, ClockMode, Command, DroppedInputs, Level, LoopConfig, LoopStats, Output,
    SimLoop, WallClock,
};

/// Why the node could not run.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    #[error(transparent)]
    ParamsFile(#[from] ParamsError),
    #[error("{0}")]
    Params(String),
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error("{0}")]
    Topic(String),
    #[error("DDS: {0}")]
    Dds(String),
    #[error("the simulation thread stopped unexpectedly")]
    SimulationStopped,
}
