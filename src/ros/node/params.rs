//! The node's parameters: a ROS 2 style parameters file (`drape: ros__parameters: ...`) and
//! the ROS command line conventions (`--ros-args --params-file F -r __ns:=/ns -r __node:=n`).
//!
//! Pure parsing, no DDS: every rule here has a unit test.

mod error;

pub use error::{ArgsError, ParamError, ParamsError};

use super::quality::QualityBounds;
use crate::ros::Distro;
use serde_yaml_ng::Value;
use std::path::{Path, PathBuf};

/// Which request/reply mapping the node's services use on the wire. ROS 2 rmw
/// implementations disagree: Fast DDS uses the RPC-over-DDS "enhanced" mapping, Cyclone DDS
/// its own header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ServiceWire {
    /// rmw_fastrtps (default in Humble and Jazzy) and rmw_connextdds.
    #[default]
    Enhanced,
    /// rmw_cyclonedds.
    Cyclone,
}

/// Topic names; `~/x` is relative to the node (`/<ns>/<node>/x`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topics {
    pub joint_states: String,
    pub robot_description: String,
    pub clock: String,
    pub mesh: String,
    pub points: String,
    pub obstacles: String,
    pub diagnostics: String,
}

impl Default for Topics {
    fn default() -> Self {
        Self {
            joint_states: "/joint_states".into(),
            robot_description: "/robot_description".into(),
            clock: "/clock".into(),
            mesh: "~/mesh".into(),
            points: "~/points".into(),
            obstacles: "~/obstacles".into(),
            diagnostics: "/diagnostics".into(),
        }
    }
}

/// Everything `drape node` is configured with.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeParams {
    /// Node name (default `drape`) and namespace (default `/`).
    pub name: String,
    pub namespace: String,
    /// Scene file (a parameters file's value is resolved against that file's folder, a `-p`
    /// value against the working directory).
    pub scene: PathBuf,
    /// The robot's URDF as XML text, as `robot_state_publisher`'s parameter of that name holds
    /// it; empty: the scene's `robot.urdf` file. Meshes are resolved against that file's folder.
    pub robot_description: String,
    /// Also follow the `robot_description` topic (transient-local): each URDF published there
    /// reloads the robot; until one arrives the parameter's (or the scene's file) is used.
    pub robot_description_from_topic: bool,
    /// Folders searched for `package://` meshes besides `ROS_PACKAGE_PATH` and
    /// `AMENT_PREFIX_PATH` (a parameters file's entries resolved against its folder).
    pub package_paths: Vec<PathBuf>,
    /// Mesh, points and obstacles messages per second of (simulated) time. Live.
    pub publish_rate: f64,
    /// Obstacle markers per second (0: never).
    pub obstacles_rate: f64,
    /// Diagnostics per second.
    pub diagnostics_rate: f64,
    /// Frame of the outputs; empty: the robot's root link (else `world`).
    pub frame_id: String,
    /// Marker layout; `None`: `$ROS_DISTRO`, else Jazzy.
    pub distro: Option<Distro>,
    /// Follow `/clock` (rosgraph_msgs/Clock) instead of the wall clock.
    pub use_sim_time: bool,
    /// Start paused. Live.
    pub paused: bool,
    /// Steps the simulation may be behind before the backlog is dropped.
    pub max_backlog_steps: u32,
    /// Levels of halving fast contact may use per substep when the scene sets none
    /// (`solver.guard.max_contact_split_levels`): a jump of the arm otherwise splits one frame
    /// into as many substeps as the link's motion has thirds of a cloth spacing.
    pub max_contact_split_levels: u32,
    /// Reach joint states no faster than the URDF's joint velocity limits allow.
    pub joint_velocity_limits: bool,
    /// Lower an implicit scene's quality to hold real time (see [`super::quality`]).
    pub adaptive_quality: bool,
    /// How low (`quality.min_substeps`, `quality.max_cg_tolerance`,
    /// `quality.min_cg_max_iterations`, `quality.max_linearisation_tolerance`, `quality.levels`).
    pub quality: QualityBounds,
    pub service_wire: ServiceWire,
    pub topics: Topics,
    pub color: [f32; 4],
}

impl Default for NodeParams {
    fn default() -> Self {
        Self {
            name: "drape".into(),
            namespace: "/".into(),
            scene: PathBuf::new(),
            robot_description: String::new(),
            robot_description_from_topic: false,
            package_paths: Vec::new(),
            publish_rate: 30.0,
            obstacles_rate: 2.0,
            diagnostics_rate: 1.0,
            frame_id: String::new(),
            distro: None,
            use_sim_time: false,
            paused: false,
            max_backlog_steps: 6,
            max_contact_split_levels: 2,
            joint_velocity_limits: true,
            adaptive_quality: true,
            quality: QualityBounds::default(),
            service_wire: ServiceWire::Enhanced,
            topics: Topics::default(),
            color: [0.85, 0.35, 0.2, 1.0],
        }
    }
}

/// The highest publish or diagnostics rate, in Hz.
const MAX_RATE: f64 = 1000.0;

/// What the command line asked for, ROS style.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RosArgs {
    pub params_files: Vec<PathBuf>,
    pub namespace: Option<String>,
    pub node_name: Option<String>,
    /// Single parameters from `-p name:=value`.
    pub overrides: Vec<(String, String)>,
}

/// Parses arguments after `--ros-args` (up to `--`): `--params-file F`, `-r __ns:=/ns`,
/// `-r __node:=name` (also `--remap`), `-p name:=value` (also `--param`). Remaps of topics are
/// rejected rather than ignored, so a launch file that relies on one fails loudly.
pub fn parse_ros_args<S: AsRef<str>>(args: &[S]) -> Result<RosArgs, ParamsError> {
    let mut out = RosArgs::default();
    let mut it = args.iter().map(|s| s.as_ref());
    while let Some(a) = it.next() {
        let mut value = |flag: &str| {
            it.next()
                .map(str::to_string)
                .ok_or_else(|| ArgsError::NeedsValue {
                    flag: flag.to_string(),
                })
        };
        match a {
            "--ros-args" => {}
            "--" => break,
            "--params-file" => out.params_files.push(PathBuf::from(value(a)?)),
            "-r" | "--remap" => {
                let v = value(a)?;
                let (from, to) = split_assign(&v)?;
                match from {
                    "__ns" => out.namespace = Some(to.to_string()),
                    "__node" | "__name" => out.node_name = Some(to.to_string()),
                    _ => return Err(ArgsError::Remap { remap: v }.into()),
                }
            }
            "-p" | "--param" => {
                let v = value(a)?;
                let (k, val) = split_assign(&v)?;
                out.overrides.push((k.to_string(), val.to_string()));
            }
            other => {
                return Err(ArgsError::Unknown {
                    arg: other.to_string(),
                }
                .into())
            }
        }
    }
    Ok(out)
}

fn split_assign(s: &str) -> Result<(&str, &str), ArgsError> {
    s.split_once(":=")
        .filter(|(k, _)| !k.is_empty())
        .ok_or_else(|| ArgsError::NotAssignment { got: s.to_string() })
}

impl NodeParams {
    /// The parameters of node `node_name` from `files` in order (a later file's value wins, as
    /// ROS merges them), then the `-p` overrides; checked once, at the end, so that a file may
    /// leave the scene to the command line. Relative paths in a file are resolved against its
    /// folder.
    pub fn from_sources(
        files: &[PathBuf],
        overrides: &[(String, String)],
        node_name: &str,
    ) -> Result<NodeParams, ParamsError> {
        let mut p = NodeParams {
            name: node_name.to_string(),
            ..NodeParams::default()
        };
        for file in files {
            p.read_file(file, node_name)?;
        }
        p.set_overrides(overrides)?;
        let origin = match (overrides.is_empty(), files.last()) {
            (true, Some(f)) => f.display().to_string(),
            (false, _) | (true, None) => Self::COMMAND_LINE.to_string(),
        };
        p.checked(&origin)
    }

    /// Reads one parameters file; relative paths are resolved against the file's folder.
    pub fn load(path: &Path, node_name: &str) -> Result<NodeParams, ParamsError> {
        Self::from_sources(&[path.to_path_buf()], &[], node_name)
    }

    /// Parses the `ros__parameters` of `node_name` from parameters-file text.
    pub fn from_yaml(text: &str, origin: &str, node_name: &str) -> Result<NodeParams, ParamsError> {
        let mut p = NodeParams {
            name: node_name.to_string(),
            ..NodeParams::default()
        };
        p.merge_yaml(text, origin, node_name, None)?;
        p.checked(origin)
    }

    /// Where `-p` values come from, in errors.
    const COMMAND_LINE: &'static str = "command line";

    fn read_file(&mut self, path: &Path, node_name: &str) -> Result<(), ParamsError> {
        let text = crate::input::read_text(path, crate::input::InputKind::NodeParams)?;
        self.merge_yaml(&text, &path.display().to_string(), node_name, path.parent())
    }

    /// Sets the parameters of `node_name`'s section of parameters-file text over `self`; the
    /// file's relative paths are resolved against `dir`.
    fn merge_yaml(
        &mut self,
        text: &str,
        origin: &str,
        node_name: &str,
        dir: Option<&Path>,
    ) -> Result<(), ParamsError> {
        if let Err(line) = crate::input::check_yaml_depth(text) {
            return Err(ParamsError::TooDeep {
                origin: origin.into(),
                line,
                max: crate::input::MAX_YAML_DEPTH,
            });
        }
        let doc: Value = serde_yaml_ng::from_str(text).map_err(|source| ParamsError::Yaml {
            origin: origin.into(),
            source,
        })?;
        let (section_name, node) = [
            node_name.to_string(),
            format!("/{node_name}"),
            "/**".to_string(),
        ]
        .into_iter()
        .find_map(|k| doc.get(k.as_str()).map(|v| (k, v)))
        .or_else(|| {
            // `/ns/name:` also names this node.
            doc.as_mapping()?.iter().find_map(|(k, v)| {
                let k = k.as_str()?;
                k.rsplit_once('/')
                    .filter(|(_, n)| *n == node_name)
                    .map(|_| (k.to_string(), v))
            })
        })
        .ok_or_else(|| ParamsError::NoSection {
            origin: origin.into(),
            node: node_name.into(),
        })?;
        let section = node
            .get("ros__parameters")
            .ok_or_else(|| ParamsError::NoSection {
                origin: origin.into(),
                node: node_name.into(),
            })?;
        let Value::Mapping(map) = section else {
            return Err(ParamsError::NotAMapping {
                origin: origin.into(),
                section: section_name,
                empty: section.is_null(),
            });
        };
        let mut flat = Vec::new();
        flatten("", &Value::Mapping(map.clone()), &mut flat);
        for (key, value) in flat {
            self.set(&key, &value)
                .map_err(|source| ParamsError::Invalid {
                    origin: origin.into(),
                    key: key.clone(),
                    source,
                })?;
            let Some(dir) = dir else { continue };
            let resolve = |p: &mut PathBuf| {
                if p.is_relative() {
                    *p = dir.join(&*p);
                }
            };
            match key.as_str() {
                "scene" => resolve(&mut self.scene),
                "package_paths" => self.package_paths.iter_mut().for_each(resolve),
                _ => {}
            }
        }
        Ok(())
    }

    /// Applies `-p name:=value` overrides (values parsed as YAML scalars, as ROS does, except
    /// `robot_description`: URDF text is taken as it is) and checks the result.
    pub fn apply_overrides(&mut self, overrides: &[(String, String)]) -> Result<(), ParamsError> {
        self.set_overrides(overrides)?;
        self.validate()
            .map_err(|(key, source)| ParamsError::Invalid {
                origin: Self::COMMAND_LINE.into(),
                key: key.into(),
                source,
            })
    }

    fn set_overrides(&mut self, overrides: &[(String, String)]) -> Result<(), ParamsError> {
        for (k, v) in overrides {
            let value = if k == "robot_description" {
                Value::String(v.clone())
            } else {
                serde_yaml_ng::from_str(v).unwrap_or_else(|_| Value::String(v.clone()))
            };
            self.set(k, &value).map_err(|source| ParamsError::Invalid {
                origin: Self::COMMAND_LINE.into(),
                key: k.clone(),
                source,
            })?;
        }
        Ok(())
    }

    /// `self` if its cross-field checks pass, else the error naming `origin` and the key.
    fn checked(self, origin: &str) -> Result<NodeParams, ParamsError> {
        self.validate()
            .map_err(|(key, source)| ParamsError::Invalid {
                origin: origin.into(),
                key: key.into(),
                source,
            })?;
        Ok(self)
    }

    fn set(&mut self, key: &str, v: &Value) -> Result<(), ParamError> {
        match key {
            "scene" => self.scene = PathBuf::from(string(v)?),
            "robot_description" => {
                let text = string(v)?;
                let trimmed = text.trim_start();
                if !(trimmed.is_empty() || trimmed.starts_with('<')) {
                    return Err(ParamError::NotUrdf {
                        got: text.chars().take(40).collect(),
                    });
                }
                self.robot_description = text;
            }
            "robot_description_from_topic" => self.robot_description_from_topic = boolean(v)?,
            "package_paths" => {
                let Value::Sequence(s) = v else {
                    return Err(ParamError::NotAList {
                        got: Box::new(v.clone()),
                    });
                };
                self.package_paths = s
                    .iter()
                    .map(|p| string(p).map(PathBuf::from))
                    .collect::<Result<_, _>>()?;
            }
            "publish_rate" => self.publish_rate = number(v)?,
            "obstacles_rate" => self.obstacles_rate = number(v)?,
            "diagnostics_rate" => self.diagnostics_rate = number(v)?,
            "frame_id" => self.frame_id = string(v)?,
            "distro" => {
                let s = string(v)?;
                self.distro = if s.is_empty() {
                    None
                } else {
                    Some(s.parse::<Distro>()?)
                }
            }
            "use_sim_time" => self.use_sim_time = boolean(v)?,
            "paused" => self.paused = boolean(v)?,
            "adaptive_quality" => self.adaptive_quality = boolean(v)?,
            "joint_velocity_limits" => self.joint_velocity_limits = boolean(v)?,
            "real_time_preview" => {
                return Err(ParamError::Replaced {
                    by: "`adaptive_quality` (on by default: the node lowers quality only when \
                         it cannot hold real time) and `quality.*` bounds",
                })
            }
            "quality.min_substeps" => self.quality.min_substeps = integer(v, 1, 100_000)?,
            "quality.max_cg_tolerance" => {
                let t = number(v)?;
                if !(t > 0.0 && t < 1.0) {
                    return Err(ParamError::NotAFraction { value: t });
                }
                self.quality.max_cg_tolerance = t;
            }
            "quality.min_cg_max_iterations" => {
                self.quality.min_cg_max_iterations = integer(v, 1, 100_000)?
            }
            "quality.max_linearisation_tolerance" => {
                let t = number(v)?;
                if t <= 0.0 {
                    return Err(ParamError::NotPositive { value: t });
                }
                self.quality.max_linearisation_tolerance = t;
            }
            "quality.levels" => self.quality.levels = integer(v, 2, 64)?,
            "max_backlog_steps" => self.max_backlog_steps = integer(v, 1, 1000)?,
            "max_contact_split_levels" => self.max_contact_split_levels = integer(v, 0, 20)?,
            "service_mapping" => {
                self.service_wire = match string(v)?.to_ascii_lowercase().as_str() {
                    "enhanced" | "fastdds" | "fastrtps" => ServiceWire::Enhanced,
                    "cyclone" | "cyclonedds" => ServiceWire::Cyclone,
                    other => {
                        return Err(ParamError::NotOneOf {
                            expected: &["enhanced", "cyclone"],
                            got: other.to_string(),
                        })
                    }
                }
            }
            "color" => {
                let Value::Sequence(s) = v else {
                    return Err(ParamError::NotAColor {
                        got: Box::new(v.clone()),
                    });
                };
                if s.len() != 4 {
                    return Err(ParamError::ColorComponents { count: s.len() });
                }
                for (c, x) in self.color.iter_mut().zip(s) {
                    let x = number(x)?;
                    if !(0.0..=1.0).contains(&x) {
                        return Err(ParamError::ColorComponent { value: x });
                    }
                    *c = x as f32;
                }
            }
            k if k.starts_with("topics.") => {
                let t = &mut self.topics;
                let slot = match &k["topics.".len()..] {
                    // The names of `error::TOPICS`.
                    "joint_states" => &mut t.joint_states,
                    "robot_description" => &mut t.robot_description,
                    "clock" => &mut t.clock,
                    "mesh" => &mut t.mesh,
                    "points" => &mut t.points,
                    "obstacles" => &mut t.obstacles,
                    "diagnostics" => &mut t.diagnostics,
                    _ => return Err(ParamError::UnknownTopic),
                };
                let name = string(v)?;
                if name.is_empty() || name.contains(char::is_whitespace) {
                    return Err(ParamError::NotATopicName { name });
                }
                *slot = name;
            }
            _ => return Err(ParamError::Unknown),
        }
        Ok(())
    }

    /// Cross-field checks; returns the key at fault.
    fn validate(&self) -> Result<(), (&'static str, ParamError)> {
        if self.scene.as_os_str().is_empty() {
            return Err(("scene", ParamError::MissingScene));
        }
        rate(self.publish_rate).map_err(|r| ("publish_rate", r))?;
        rate(self.diagnostics_rate).map_err(|r| ("diagnostics_rate", r))?;
        if !(self.obstacles_rate.is_finite() && self.obstacles_rate >= 0.0) {
            return Err((
                "obstacles_rate",
                ParamError::Negative {
                    value: self.obstacles_rate,
                },
            ));
        }
        Ok(())
    }
}

/// A publish rate the node can honour: positive, finite, at most 1 kHz.
fn rate(r: f64) -> Result<(), ParamError> {
    if r.is_finite() && r > 0.0 && r <= MAX_RATE {
        Ok(())
    } else {
        Err(ParamError::Rate {
            value: r,
            max: MAX_RATE,
        })
    }
}

/// [`rate`] as the parameter service's reply text (`SetParametersResult.reason` is a string).
pub fn positive_rate(r: f64) -> Result<(), String> {
    rate(r).map_err(|e| e.to_string())
}

fn flatten(prefix: &str, v: &Value, out: &mut Vec<(String, Value)>) {
    match v {
        Value::Mapping(m) => {
            for (k, v) in m {
                let k = match k {
                    Value::String(s) => s.clone(),
                    other => format!("{other:?}"),
                };
                let key = if prefix.is_empty() {
                    k
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        _ => out.push((prefix.to_string(), v.clone())),
    }
}

fn string(v: &Value) -> Result<String, ParamError> {
    match v {
        Value::String(s) => Ok(s.clone()),
        Value::Null => Ok(String::new()),
        other => Err(ParamError::NotAString {
            got: Box::new(other.clone()),
        }),
    }
}

fn number(v: &Value) -> Result<f64, ParamError> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| ParamError::NotANumber {
            got: Box::new(v.clone()),
        })
}

fn integer(v: &Value, min: u32, max: u32) -> Result<u32, ParamError> {
    let n = number(v)?;
    if !((f64::from(min)..=f64::from(max)).contains(&n) && n.fract() == 0.0) {
        return Err(ParamError::NotAnIntegerIn { value: n, min, max });
    }
    Ok(n as u32)
}

fn boolean(v: &Value) -> Result<bool, ParamError> {
    v.as_bool().ok_or_else(|| ParamError::NotABool {
        got: Box::new(v.clone()),
    })
}

#[cfg(test)]
mod tests;
