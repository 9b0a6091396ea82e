//! ROS 2 layer: message types, cloth-to-message conversion and rosbag2 MCAP files.
//!
//! No DDS here; the live node (`ros::node`) builds on these pieces.

pub mod bag;
pub mod cdr;
pub mod convert;
mod distro;
pub mod drive;
pub mod msg;
pub mod node;
pub mod obstacles;
pub mod qos;
pub mod record;
pub mod telemetry;

pub use bag::{read_joint_states, read_topic, BagError, BagWriter, TopicId, TopicRead};
pub use convert::{mesh_marker, point_cloud};
pub use distro::{Distro, UnknownDistro};
pub use msg::RosMessage;
pub use qos::{offered_qos_profiles, Durability, Reliability};
