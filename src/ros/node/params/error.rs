//! [`ParamsError`]: a parameters file or command line the node cannot use, naming the file (or
//! the command line) and the key; what is wrong with the value is a [`ParamError`] with the
//! value and the expected form or range, as `source()`.

use serde_yaml_ng::Value;
use std::path::PathBuf;

/// A parameters file or command line the node cannot use; names the file and key.
#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    #[error("cannot read parameters file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Not a regular file, too large, not UTF-8 (see `crate::input`).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    #[error("{origin}: not YAML")]
    Yaml {
        origin: String,
        #[source]
        source: serde_yaml_ng::Error,
    },
    #[error("{origin}: line {line}: nested deeper than {max} levels")]
    TooDeep {
        origin: String,
        line: usize,
        max: usize,
    },
    #[error("{origin}: no `ros__parameters` for node `{node}` (expected `{node}:`, `/{node}:` or `/**:` at the top)")]
    NoSection { origin: String, node: String },
    /// `ros__parameters:` with nothing under it (or not a mapping): its parameters are
    /// probably indented wrongly.
    #[error("{origin}: `{section}: ros__parameters:` {}", if *empty { "is empty: indent the parameters under it (e.g. `scene: my_scene.yaml`)" } else { "is not a mapping of parameter names to values" })]
    NotAMapping {
        origin: String,
        section: String,
        empty: bool,
    },
    #[error("{origin}: parameter `{key}`")]
    Invalid {
        origin: String,
        key: String,
        #[source]
        source: ParamError,
    },
    #[error("command line")]
    Args(#[from] ArgsError),
}

/// What is wrong with one parameter's value ([`ParamsError::Invalid`] names the key). Values
/// are boxed: the error stays small on every `Ok` path of the node.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ParamError {
    #[error("unknown parameter")]
    Unknown,
    #[error("unknown topic (one of {})", alternatives(TOPICS))]
    UnknownTopic,
    #[error("missing: name the scene file")]
    MissingScene,
    /// A parameter that no longer exists, and what replaced it.
    #[error("replaced by {by}")]
    Replaced { by: &'static str },
    #[error("expected a string, got {got:?}")]
    NotAString { got: Box<Value> },
    /// `robot_description` holds URDF XML (as `robot_state_publisher`'s does), not a word.
    #[error("expected the URDF's XML text (`<robot ...>`), got `{got}`; the scene's URDF file is used when this is empty, and `robot_description_from_topic: true` follows the topic")]
    NotUrdf { got: String },
    #[error("expected a list, got {got:?}")]
    NotAList { got: Box<Value> },
    #[error("expected a number, got {got:?}")]
    NotANumber { got: Box<Value> },
    #[error("expected true or false, got {got:?}")]
    NotABool { got: Box<Value> },
    #[error("expected {}, got `{got}`", alternatives(expected))]
    NotOneOf {
        expected: &'static [&'static str],
        got: String,
    },
    #[error("must be an integer in {min}..={max}, got {value}")]
    NotAnIntegerIn { value: f64, min: u32, max: u32 },
    /// A rate outside (0, max] Hz.
    #[error("must be in (0, {max}] Hz, got {value}")]
    Rate { value: f64, max: f64 },
    #[error("must be in (0, 1), got {value}")]
    NotAFraction { value: f64 },
    #[error("must be >= 0, got {value}")]
    Negative { value: f64 },
    #[error("must be > 0, got {value}")]
    NotPositive { value: f64 },
    #[error("expected [r, g, b, a], got {got:?}")]
    NotAColor { got: Box<Value> },
    #[error("expected 4 components, got {count}")]
    ColorComponents { count: usize },
    #[error("component {value} is outside [0, 1]")]
    ColorComponent { value: f64 },
    #[error("`{name}` is not a topic name")]
    NotATopicName { name: String },
    #[error(transparent)]
    Distro(#[from] crate::ros::UnknownDistro),
}

/// The topic keys under `topics.`.
const TOPICS: &[&str] = &[
    "joint_states",
    "robot_description",
    "clock",
    "mesh",
    "points",
    "obstacles",
    "diagnostics",
];

/// `` `a`, `b` or `c` `` for messages.
fn alternatives(names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => quoted.concat(),
    }
}

/// A `--ros-args` command line the node does not take.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ArgsError {
    #[error("`{flag}` needs a value")]
    NeedsValue { flag: String },
    #[error("remap `{remap}` is not supported; set topic names in the parameters file")]
    Remap { remap: String },
    #[error("unknown ROS argument `{arg}`")]
    Unknown { arg: String },
    #[error("expected `name:=value`, got `{got}`")]
    NotAssignment { got: String },
}
