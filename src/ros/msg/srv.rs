//! Service types: std_srvs/srv/Trigger.

use serde::{Deserialize, Serialize};

/// std_srvs/srv/Trigger request (empty; IDL needs one member).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct TriggerRequest {
    pub structure_needs_at_least_one_member: u8,
}

/// std_srvs/srv/Trigger response.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct TriggerResponse {
    pub success: bool,
    pub message: String,
}

impl ros2_client::Message for TriggerRequest {}
impl ros2_client::Message for TriggerResponse {}
