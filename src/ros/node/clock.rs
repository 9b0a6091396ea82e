//! The node's clocks: which one paces the loop ([`ClockMode`]), wall time as Unix seconds from
//! a monotonic clock ([`WallClock`]), and seconds to ROS time ([`time_of`]).

use crate::ros::msg::Time;
use std::time::Instant;

/// Which clock paces the loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClockMode {
    /// System time (stamps are Unix time).
    Wall,
    /// `/clock` messages ([`super::Command::Clock`]); nothing runs before the first one.
    Sim,
}

/// Seconds since the Unix epoch, from a monotonic clock anchored once.
#[derive(Debug, Clone, Copy)]
pub struct WallClock {
    start: Instant,
    epoch: f64,
}

impl WallClock {
    pub fn new() -> WallClock {
        let epoch = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        WallClock {
            start: Instant::now(),
            epoch,
        }
    }

    pub fn now(&self) -> f64 {
        self.epoch + self.start.elapsed().as_secs_f64()
    }
}

impl Default for WallClock {
    fn default() -> Self {
        Self::new()
    }
}

/// ROS time from seconds (negative clamps to 0).
pub fn time_of(seconds: f64) -> Time {
    Time::from_nanos((seconds * 1e9).round().max(0.0) as u64)
}
