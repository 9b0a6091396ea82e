//! ROS 2 message types drape publishes and records.
//!
//! Plain serde structs whose fields follow the upstream `.msg` order exactly, so that
//! `cdr-encoding` produces the ROS 2 wire layout. Each type implements [`RosMessage`],
//! which names it and yields the rosbag2 schema text for a [`Distro`].

mod builtin;
mod bytes;
pub(crate) mod defs;
mod diagnostic;
mod geometry;
mod misc;
pub(crate) mod schema;
mod sensor;
mod srv;
mod std_msgs;
mod visualization;

pub use super::distro::Distro;
pub use builtin::{Duration, Time};
pub use diagnostic::{DiagnosticArray, DiagnosticStatus, KeyValue};
pub use geometry::{Point, Pose, Quaternion, Transform, TransformStamped, Vector3};
pub use misc::{Clock, TFMessage};
pub use sensor::{CompressedImage, JointState, PointCloud2, PointField};
pub use srv::{TriggerRequest, TriggerResponse};
pub use std_msgs::{ColorRGBA, Header, RosString};
pub use visualization::{Marker, MarkerArray, MeshFile, UVCoordinate};

use serde::Serialize;

/// A message type that can be recorded to a rosbag2 file.
pub trait RosMessage: Serialize {
    /// Full ROS type name, e.g. `"sensor_msgs/msg/JointState"`.
    const TYPE_NAME: &'static str;

    /// rosbag2 `ros2msg` schema text: the `.msg` definition followed by every dependency,
    /// each after a line of 80 `=` and `MSG: pkg/Type`. The default covers drape's own
    /// types; implement it for any other type.
    fn definition(distro: Distro) -> String {
        schema::schema_text(Self::TYPE_NAME, distro).unwrap_or_default()
    }

    /// Whether this value serialises with `distro`'s layout (only Markers carry one).
    fn fits_layout(&self, _distro: Distro) -> bool {
        true
    }
}

macro_rules! ros_message {
    ($($ty:ty => $name:literal),* $(,)?) => {
        $(impl RosMessage for $ty {
            const TYPE_NAME: &'static str = $name;
        })*
        /// Every type name defined in this module.
        pub const ALL_TYPE_NAMES: &[&str] = &[$($name),*];
    };
}

ros_message! {
    Time => "builtin_interfaces/msg/Time",
    Duration => "builtin_interfaces/msg/Duration",
    Header => "std_msgs/msg/Header",
    ColorRGBA => "std_msgs/msg/ColorRGBA",
    RosString => "std_msgs/msg/String",
    Point => "geometry_msgs/msg/Point",
    Vector3 => "geometry_msgs/msg/Vector3",
    Quaternion => "geometry_msgs/msg/Quaternion",
    Pose => "geometry_msgs/msg/Pose",
    Transform => "geometry_msgs/msg/Transform",
    TransformStamped => "geometry_msgs/msg/TransformStamped",
    UVCoordinate => "visualization_msgs/msg/UVCoordinate",
    MeshFile => "visualization_msgs/msg/MeshFile",
    CompressedImage => "sensor_msgs/msg/CompressedImage",
    PointField => "sensor_msgs/msg/PointField",
    PointCloud2 => "sensor_msgs/msg/PointCloud2",
    JointState => "sensor_msgs/msg/JointState",
    TFMessage => "tf2_msgs/msg/TFMessage",
    Clock => "rosgraph_msgs/msg/Clock",
    DiagnosticArray => "diagnostic_msgs/msg/DiagnosticArray",
    DiagnosticStatus => "diagnostic_msgs/msg/DiagnosticStatus",
    KeyValue => "diagnostic_msgs/msg/KeyValue",
}

impl RosMessage for Marker {
    const TYPE_NAME: &'static str = "visualization_msgs/msg/Marker";
    fn fits_layout(&self, distro: Distro) -> bool {
        self.distro == distro
    }
}

impl RosMessage for MarkerArray {
    const TYPE_NAME: &'static str = "visualization_msgs/msg/MarkerArray";
    fn fits_layout(&self, distro: Distro) -> bool {
        self.markers.iter().all(|m| m.distro == distro)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every type this module defines has a complete schema (the list comes from the
    /// `ros_message!` table above, so the test lives here rather than in `schema`).
    #[test]
    fn every_known_type_resolves_completely() {
        for name in ALL_TYPE_NAMES {
            for d in [Distro::Humble, Distro::Jazzy] {
                assert!(schema::schema_text(name, d).is_some(), "{name} ({d})");
            }
        }
        assert!(schema::schema_text("nav_msgs/msg/Odometry", Distro::Jazzy).is_none());
    }
}
