//! Which ROS 2 distribution's message layouts to produce.
//!
//! Only `visualization_msgs/Marker` differs between the distributions drape
//! targets: Iron added texture and embedded-mesh fields, which changes the CDR
//! wire layout, so a Humble subscriber cannot decode a Jazzy Marker (or the
//! reverse).

use std::fmt;
use std::str::FromStr;

/// ROS 2 distribution selecting message layouts. Default: [`Distro::Jazzy`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Distro {
    /// Humble Hawksbill (2022 LTS): Marker without texture / mesh_file fields.
    Humble,
    /// Jazzy Jalisco (2024 LTS), also the layout of Iron, Kilted and Rolling.
    #[default]
    Jazzy,
}

/// A distribution name drape does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown ROS 2 distribution {0:?} (expected \"humble\" or \"jazzy\")")]
pub struct UnknownDistro(pub String);

impl Distro {
    /// Lower-case name as in `ROS_DISTRO`.
    pub fn name(self) -> &'static str {
        match self {
            Distro::Humble => "humble",
            Distro::Jazzy => "jazzy",
        }
    }

    /// Distribution from the `ROS_DISTRO` environment variable; Jazzy when unset or empty.
    pub fn from_env() -> Result<Distro, UnknownDistro> {
        match std::env::var("ROS_DISTRO") {
            Ok(value) if !value.trim().is_empty() => value.parse(),
            _ => Ok(Distro::default()),
        }
    }
}

impl FromStr for Distro {
    type Err = UnknownDistro;

    /// Case-insensitive. Iron, Kilted and Rolling share Jazzy's layouts, so they map to Jazzy.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "humble" => Ok(Distro::Humble),
            "jazzy" | "iron" | "kilted" | "rolling" => Ok(Distro::Jazzy),
            _ => Err(UnknownDistro(s.to_string())),
        }
    }
}

impl fmt::Display for Distro {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_names_and_rejects_unknown() {
        assert_eq!("humble".parse(), Ok(Distro::Humble));
        assert_eq!(" Jazzy\n".parse(), Ok(Distro::Jazzy));
        assert_eq!("rolling".parse(), Ok(Distro::Jazzy));
        assert_eq!(
            "foxy".parse::<Distro>(),
            Err(UnknownDistro("foxy".to_string()))
        );
        assert_eq!(Distro::default(), Distro::Jazzy);
        assert_eq!(Distro::Humble.to_string(), "humble");
    }
}
