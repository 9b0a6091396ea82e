//! std_msgs: Header, ColorRGBA, String.

use super::Time;
use serde::{Deserialize, Serialize};

/// std_msgs/Header: stamp and coordinate frame of the data.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

impl Header {
    pub fn new(stamp: Time, frame_id: &str) -> Header {
        Header {
            stamp,
            frame_id: frame_id.to_string(),
        }
    }
}

/// std_msgs/ColorRGBA, components in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ColorRGBA {
    pub r: f32,
    pub g: f32,
    pub b: f32,
    pub a: f32,
}

impl ColorRGBA {
    pub fn new(r: f32, g: f32, b: f32, a: f32) -> ColorRGBA {
        ColorRGBA { r, g, b, a }
    }
}

/// std_msgs/String (named to avoid clashing with `std::string::String`).
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct RosString {
    pub data: String,
}
