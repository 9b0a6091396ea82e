//! The head of a `visualization_msgs/msg/Marker` (everything up to `points`), which is all the
//! renderer reads of the cloth's and the obstacles' markers, in either distro's layout.

use crate::ros::msg::{Header, Point};
use crate::ros::RosMessage;
use serde::{Deserialize, Serialize};

/// The part of a `visualization_msgs/msg/Marker` the renderer needs: everything up to `points`
/// (CDR is read in order, the rest of the message is ignored).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct MarkerHead {
    pub header: Header,
    pub ns: String,
    pub id: i32,
    pub r#type: i32,
    pub action: i32,
    pub pose: crate::ros::msg::Pose,
    pub scale: crate::ros::msg::Vector3,
    pub color: crate::ros::msg::ColorRGBA,
    pub lifetime: crate::ros::msg::Duration,
    pub frame_locked: bool,
    pub points: Vec<Point>,
}

impl RosMessage for MarkerHead {
    const TYPE_NAME: &'static str = "visualization_msgs/msg/Marker";
}
