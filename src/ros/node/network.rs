//! ROS 2 networking conventions from the environment: `ROS_DOMAIN_ID`, `ROS_LOCALHOST_ONLY`
//! (Humble) and `ROS_AUTOMATIC_DISCOVERY_RANGE` (Jazzy).

/// Where the node's DDS participant may talk.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Network {
    pub domain_id: u16,
    /// Restrict discovery and traffic to 127.0.0.1.
    pub localhost_only: bool,
}

/// An environment variable with a value the node cannot use.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum NetworkError {
    #[error("ROS_DOMAIN_ID={value:?}: expected an integer 0..={max}")]
    DomainId { value: String, max: u16 },
    #[error(
        "ROS_AUTOMATIC_DISCOVERY_RANGE={value:?}: expected SUBNET, LOCALHOST, OFF or SYSTEM_DEFAULT"
    )]
    DiscoveryRange { value: String },
}

/// Highest domain id whose ports fit below 65535 with the RTPS port mapping.
pub const MAX_DOMAIN_ID: u16 = 232;

impl Network {
    /// Reads the process environment.
    pub fn from_env() -> Result<Network, NetworkError> {
        Network::from_lookup(|k| std::env::var(k).ok())
    }

    /// Reads the variables through `get` (testable without touching the environment).
    pub fn from_lookup(get: impl Fn(&str) -> Option<String>) -> Result<Network, NetworkError> {
        let domain_id = match get("ROS_DOMAIN_ID").map(|s| s.trim().to_string()) {
            None => 0,
            Some(s) if s.is_empty() => 0,
            Some(s) => s
                .parse::<u16>()
                .ok()
                .filter(|d| *d <= MAX_DOMAIN_ID)
                .ok_or(NetworkError::DomainId {
                    value: s,
                    max: MAX_DOMAIN_ID,
                })?,
        };
        let flag = get("ROS_LOCALHOST_ONLY").is_some_and(|v| v.trim() == "1");
        let range = match get("ROS_AUTOMATIC_DISCOVERY_RANGE")
            .map(|v| v.trim().to_ascii_uppercase())
            .as_deref()
        {
            None | Some("") | Some("SUBNET") | Some("SYSTEM_DEFAULT") => false,
            // OFF means no automatic discovery at all; localhost is the closest RustDDS offers.
            Some("LOCALHOST") | Some("OFF") => true,
            Some(other) => {
                return Err(NetworkError::DiscoveryRange {
                    value: other.to_string(),
                })
            }
        };
        Ok(Network {
            domain_id,
            localhost_only: flag || range,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn net(vars: &[(&str, &str)]) -> Result<Network, NetworkError> {
        let m: HashMap<String, String> = vars
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        Network::from_lookup(|k| m.get(k).cloned())
    }

    #[test]
    fn reads_ros_conventions() {
        assert_eq!(net(&[]), Ok(Network::default()));
        assert_eq!(net(&[("ROS_DOMAIN_ID", "42")]).unwrap().domain_id, 42);
        assert!(net(&[("ROS_DOMAIN_ID", "233")]).is_err());
        assert_eq!(
            net(&[("ROS_DOMAIN_ID", "x")]),
            Err(NetworkError::DomainId {
                value: "x".into(),
                max: MAX_DOMAIN_ID
            })
        );
        assert!(net(&[("ROS_DOMAIN_ID", "x")])
            .unwrap_err()
            .to_string()
            .contains("ROS_DOMAIN_ID"));
        assert!(net(&[("ROS_LOCALHOST_ONLY", "1")]).unwrap().localhost_only);
        assert!(!net(&[("ROS_LOCALHOST_ONLY", "0")]).unwrap().localhost_only);
        assert!(
            net(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "localhost")])
                .unwrap()
                .localhost_only
        );
        assert!(
            !net(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET")])
                .unwrap()
                .localhost_only
        );
        assert_eq!(
            net(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "LAN")]),
            Err(NetworkError::DiscoveryRange {
                value: "LAN".into()
            })
        );
    }
}
