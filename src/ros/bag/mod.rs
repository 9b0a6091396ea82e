//! rosbag2-compatible MCAP files: writing any [`RosMessage`](super::msg::RosMessage),
//! reading typed messages back (e.g. `/joint_states` to drive a robot).

mod error;
pub mod lengths;
mod metadata;
mod read;
mod write;

pub use error::BagError;
pub use metadata::RunInfo;
pub use read::{read_joint_states, read_topic, BagBytes, TopicIter, TopicRead};
pub use write::{BagWriter, TopicId};
