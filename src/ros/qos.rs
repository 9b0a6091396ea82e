//! `offered_qos_profiles` channel metadata, so `ros2 bag play` re-offers the QoS a
//! topic was published with (e.g. transient-local `/robot_description` replays latched).
//!
//! rosbag2 stores a YAML sequence of rmw QoS profiles. Humble only understands the
//! integer-enum form (bag metadata version 8); Jazzy writes names (version 9) but reads
//! integers when the file's `rosbag2` metadata record has an empty `serialized_metadata`,
//! which [`super::BagWriter`] writes. So the integer form is the one both replay.

/// rmw reliability policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reliability {
    Reliable,
    BestEffort,
}

/// rmw durability policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Durability {
    Volatile,
    /// Late joiners get the last message ("latched").
    TransientLocal,
}

/// `RMW_DURATION_INFINITE` as rosbag2 serialises it.
const INFINITE: &str = "\n    sec: 9223372036\n    nsec: 854775807";

/// The YAML rosbag2 (`ros2 bag record`, Humble layout) writes for one publisher with
/// these policies: history unknown / depth 0 as recorded from discovery, infinite
/// deadline, lifespan and lease, automatic liveliness.
pub fn offered_qos_profiles(reliability: Reliability, durability: Durability) -> String {
    let reliability = match reliability {
        Reliability::Reliable => 1,
        Reliability::BestEffort => 2,
    };
    let durability = match durability {
        Durability::TransientLocal => 1,
        Durability::Volatile => 2,
    };
    format!(
        "- history: 3\n  depth: 0\n  reliability: {reliability}\n  durability: {durability}\n  \
         deadline:{INFINITE}\n  lifespan:{INFINITE}\n  liveliness: 1\n  \
         liveliness_lease_duration:{INFINITE}\n  avoid_ros_namespace_conventions: false"
    )
}

/// Why user-supplied `offered_qos_profiles` YAML would not replay on Humble.
#[derive(Debug, thiserror::Error)]
pub enum QosError {
    #[error("not YAML")]
    Yaml(#[source] serde_yaml_ng::Error),
    #[error("expected a YAML sequence of QoS profiles")]
    NotSequence,
    #[error("profile {index} is not a mapping")]
    NotMapping { index: usize },
    /// Humble reads the rmw enums only as integers (see the module doc).
    #[error("profile {index}: `{key}` must be an rmw enum integer (Humble form), got {got}")]
    NotInteger {
        index: usize,
        key: &'static str,
        got: String,
    },
    #[error("profile {index}: missing `{key}`")]
    Missing { index: usize, key: &'static str },
}

/// Checks that user-supplied `offered_qos_profiles` YAML is a sequence of profiles in
/// the integer form; returns the first problem.
pub fn validate(yaml: &str) -> Result<(), QosError> {
    use serde_yaml_ng::Value;
    let value: Value = serde_yaml_ng::from_str(yaml).map_err(QosError::Yaml)?;
    let Value::Sequence(profiles) = value else {
        return Err(QosError::NotSequence);
    };
    for (index, profile) in profiles.iter().enumerate() {
        let Value::Mapping(map) = profile else {
            return Err(QosError::NotMapping { index });
        };
        for key in ["history", "reliability", "durability", "liveliness"] {
            match map.get(key) {
                Some(Value::Number(_)) => {}
                Some(other) => {
                    return Err(QosError::NotInteger {
                        index,
                        key,
                        got: format!("{other:?}"),
                    })
                }
                None => return Err(QosError::Missing { index, key }),
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latched_profile_matches_rosbag2_text() {
        let yaml = offered_qos_profiles(Reliability::Reliable, Durability::TransientLocal);
        // Text as found in bags recorded by `ros2 bag record` on Humble.
        let recorded = "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 1\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n  avoid_ros_namespace_conventions: false";
        assert_eq!(yaml, recorded);
        assert!(validate(&yaml).is_ok());
        let volatile = offered_qos_profiles(Reliability::BestEffort, Durability::Volatile);
        assert!(volatile.contains("reliability: 2\n  durability: 2\n"));
    }

    #[test]
    fn validate_rejects_named_enums_and_non_sequences() {
        assert!(validate("history: 1").is_err());
        let named = offered_qos_profiles(Reliability::Reliable, Durability::Volatile)
            .replace("reliability: 1", "reliability: reliable");
        let err = validate(&named).unwrap_err();
        assert!(
            matches!(
                err,
                QosError::NotInteger {
                    index: 0,
                    key: "reliability",
                    ..
                }
            ),
            "{err:?}"
        );
        assert!(matches!(
            validate("[1]"),
            Err(QosError::NotMapping { index: 0 })
        ));
        assert!(matches!(validate("["), Err(QosError::Yaml(_))));
        assert!(validate("[]").is_ok());
    }
}
