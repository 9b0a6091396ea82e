//! builtin_interfaces: Time and Duration.

use serde::{Deserialize, Serialize};

const NANOS_PER_SEC: u64 = 1_000_000_000;

/// builtin_interfaces/Time: seconds and nanoseconds since the epoch (or sim start).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    /// From nanoseconds; saturates at `i32::MAX` seconds (year 2038) rather than wrapping.
    pub fn from_nanos(ns: u64) -> Time {
        let sec = i32::try_from(ns / NANOS_PER_SEC).unwrap_or(i32::MAX);
        Time {
            sec,
            nanosec: (ns % NANOS_PER_SEC) as u32,
        }
    }

    /// Total nanoseconds (negative before the epoch).
    pub fn as_nanos(self) -> i64 {
        i64::from(self.sec) * NANOS_PER_SEC as i64 + i64::from(self.nanosec)
    }
}

/// builtin_interfaces/Duration; zero means "forever" for Marker lifetimes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Duration {
    pub sec: i32,
    pub nanosec: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_from_nanos_splits_and_saturates() {
        let t = Time::from_nanos(3_000_000_007);
        assert_eq!((t.sec, t.nanosec), (3, 7));
        assert_eq!(t.as_nanos(), 3_000_000_007);
        assert_eq!(Time::from_nanos(u64::MAX).sec, i32::MAX);
    }
}
