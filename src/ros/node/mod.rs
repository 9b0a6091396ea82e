//! The live ROS 2 node (`drape node`): joint states in, cloth out at a fixed rate.
//!
//! Two threads with one direction of data each: the DDS thread ([`dds`]) turns subscriptions
//! into [`Command`]s and publishes [`Output`]s; the simulation thread ([`thread`]) drives the
//! [`SimLoop`] ([`sim_loop`]), which steps at a fixed `dt` paced by the wall clock or `/clock`
//! ([`pacer`], [`clock`]) and never touches DDS. [`messages`] holds what crosses between them
//! and the counters; [`joints`] gates joint states; [`outputs`] builds the diagnostics and
//! obstacle messages; [`quality`] adapts the solver's quality to hold real time; [`params`]
//! and [`network`] read the configuration. This file only
//! declares, re-exports and defines [`NodeError`].

pub mod clock;
pub mod config;
pub mod dds;
pub mod endpoints;
pub mod joints;
pub mod messages;
pub mod network;
pub mod outputs;
pub mod pacer;
pub mod params;
pub mod quality;
pub mod sim_loop;
pub mod thread;

pub use clock::{time_of, ClockMode, WallClock};
pub use config::LoopConfig;
pub use dds::{run_node, NodeSummary};
pub use endpoints::{context, resolve_topic};
pub use joints::{Dropped, JointGate};
pub use messages::{Command, DroppedInputs, Level, LoopStats, Output};
pub use network::{Network, NetworkError};
pub use pacer::{Pacer, Schedule};
pub use params::{parse_ros_args, NodeParams, ParamsError, RosArgs, ServiceWire};
pub use quality::{
    lowest_quality, Decision, Quality, QualityBounds, QualityController, QualityStatus,
};
pub use sim_loop::SimLoop;

/// Why the node could not run. Each variant names what it was making and keeps the cause as
/// its `source()`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NodeError {
    #[error(transparent)]
    ParamsFile(#[from] ParamsError),
    #[error("ROS_DISTRO")]
    Distro(#[from] crate::ros::UnknownDistro),
    #[error(transparent)]
    Network(#[from] NetworkError),
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// The `robot_description` parameter holds a URDF but the scene has no robot to load it as.
    #[error("parameter `robot_description`: the scene {} has no `robot:` section to load it into", scene.display())]
    DescriptionWithoutRobot { scene: std::path::PathBuf },
    #[error("node name `{name}` in namespace `{namespace}` is not a ROS name")]
    NodeName {
        name: String,
        namespace: String,
        #[source]
        source: ros2_client::names::NameError,
    },
    #[error("topic `{topic}` is not a ROS name (resolved as `{resolved}`)")]
    Topic {
        topic: String,
        resolved: String,
        #[source]
        source: ros2_client::names::NameError,
    },
    #[error("DDS participant on domain {domain_id}")]
    Participant {
        domain_id: u16,
        #[source]
        source: ros2_client::dds::rustdds::dds::CreateError,
    },
    #[error("ROS context")]
    Context(#[source] ros2_client::CreateError),
    #[error("ROS node `{name}`")]
    Node {
        name: String,
        #[source]
        source: ros2_client::NodeCreateError,
    },
    #[error("ROS spinner")]
    Spinner(#[source] ros2_client::CreateError),
    /// A topic, publisher, subscription or service the node needs.
    #[error("DDS endpoint `{endpoint}`")]
    Endpoint {
        endpoint: String,
        #[source]
        source: ros2_client::CreateError,
    },
    #[error("cannot start the {thread} thread")]
    Thread {
        thread: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error("the simulation thread stopped unexpectedly")]
    SimulationStopped,
}
