//! drape: cloth simulation on robots.
//!
//! The core (`cloth`, `effects`, `integrate`, `collide`, `scene`, `sim`, `mesh`, `robot`)
//! is pure Rust with no ROS types; `ros` (feature `ros`, on by default) turns cloth
//! into ROS 2 messages, writes rosbag2 MCAP files and runs the live node. `hard` (the hard-case
//! catalogue) and `study` (the accuracy/cost study) are tools around the simulator, behind the
//! feature `tools` (on by default); `--no-default-features` builds the simulator alone.
//! See `docs/DESIGN.md` for the layering and the order of one step.

// Numeric loops index several parallel arrays at once; iterator zips would hide the math.
#![allow(clippy::needless_range_loop)]

pub mod cancel;
pub mod cloth;
pub mod collide;
pub mod effects;
pub mod garment;
#[cfg(feature = "tools")]
pub mod hard;
pub mod input;
pub mod integrate;
pub mod linalg;
pub mod mesh;
pub mod output;
mod par;
pub mod pose;
#[cfg(feature = "ros")]
pub mod render;
pub mod robot;
#[cfg(feature = "ros")]
pub mod ros;
pub mod scene;
pub mod sim;
#[cfg(feature = "tools")]
pub mod study;
#[cfg(feature = "ros")]
pub mod sweep;

/// All simulation state is double precision: convergence-order and energy tests
/// need the headroom, and the cost over f32 is small for scalar spring loops.
pub type Vec3 = glam::DVec3;
/// 3x3 blocks of force Jacobians.
pub type Mat3 = glam::DMat3;
pub use pose::Pose;
