//! tf2_msgs/TFMessage and rosgraph_msgs/Clock.

use super::{Time, TransformStamped};
use serde::{Deserialize, Serialize};

/// tf2_msgs/TFMessage, the payload of `/tf` and `/tf_static`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TFMessage {
    pub transforms: Vec<TransformStamped>,
}

/// rosgraph_msgs/Clock, the payload of `/clock` for `use_sim_time`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Clock {
    pub clock: Time,
}
