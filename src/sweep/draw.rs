//! Random draws of a sweep ([`Draw`]: uniform, log-uniform, integer, choice, jitter) and what a
//! sweep key varies ([`Target`]); their checks against the base scene and their sampling.

use super::keypath::{describe, KeyPath, KeyPathError};
use super::rng::SplitMix64;
use serde::{Deserialize, Serialize};
use serde_yaml_ng::Value;

/// The draws a sweep knows, for messages.
const DRAWS: &str = "{ uniform: [lo, hi] }, { log_uniform: [lo, hi] }, { integer: [lo, hi] }, \
                     { choice: [..] } or { jitter: a }";

/// Why a sweep value is not a draw ([`Draw::from_value`]).
#[derive(Debug, thiserror::Error)]
pub enum DrawError {
    #[error("expected a draw ({DRAWS}), got {found}")]
    NotADraw { found: &'static str },
    /// `uniform`, `log_uniform` or `integer` without two bounds of the right type.
    #[error("{kind}: expected [lo, hi] {what}")]
    Bounds {
        kind: &'static str,
        what: &'static str,
        #[source]
        source: serde_yaml_ng::Error,
    },
    #[error("choice: expected a list, got {found}")]
    ChoiceNotList { found: &'static str },
    #[error("unknown draw `{name}` (a draw is {DRAWS})")]
    Unknown { name: String },
}

/// Why a draw cannot vary its key ([`check_draw`]): an empty range, or a jitter without a scene
/// value of its shape.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RangeError {
    #[error("empty range [{lo}, {hi}]: needs lo <= hi")]
    Empty { lo: f64, hi: f64 },
    #[error("empty range [{lo}, {hi}]: needs 0 < lo <= hi")]
    EmptyLog { lo: f64, hi: f64 },
    #[error("empty range [{lo}, {hi}]: needs lo <= hi")]
    EmptyInteger { lo: i64, hi: i64 },
    #[error("empty choice: no values to draw from")]
    EmptyChoice,
    #[error("jitter applies to scene values only")]
    JitterNotScene,
    #[error("jitter needs a value in the scene to jitter around (set it under `set`)")]
    JitterNoValue,
    #[error("jitter needs a number or a list of numbers, the scene has {found}")]
    JitterNotNumbers { found: &'static str },
    #[error("jitter needs one amplitude or one per element (the scene's value has {elements}, the jitter {amplitudes})")]
    JitterShape { elements: usize, amplitudes: usize },
    #[error("jitter amplitudes must be >= 0")]
    JitterNegative,
}

/// A sweep key that names nothing it can vary.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TargetError {
    #[error("unknown job key `{key}` (job.joints: a joint-states bag, job.time_scale: trajectory time scale)")]
    UnknownJobKey { key: String },
    #[error(transparent)]
    Path(#[from] KeyPathError),
}

/// A random draw for one key.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Draw {
    /// Uniform in `[lo, hi]`.
    Uniform([f64; 2]),
    /// `exp` of a uniform draw in `[ln lo, ln hi]` (`lo > 0`).
    LogUniform([f64; 2]),
    /// Integer in `lo..=hi`.
    Integer([i64; 2]),
    /// One of the values.
    Choice(Vec<Value>),
    /// The scene's value plus uniform(-a, a), per element for lists (initial pose jitter).
    Jitter(Value),
}

impl Draw {
    /// From its YAML form, a map with one key naming the draw: `{ uniform: [0, 1] }`.
    pub fn from_value(v: &Value) -> Result<Draw, DrawError> {
        let not_a_draw = || DrawError::NotADraw { found: describe(v) };
        let (k, arg) = match v {
            Value::Mapping(m) if m.len() == 1 => m.iter().next().ok_or_else(not_a_draw)?,
            _ => return Err(not_a_draw()),
        };
        let kind = k.as_str().unwrap_or_default();
        let pair = |kind: &'static str| {
            serde_yaml_ng::from_value::<[f64; 2]>(arg.clone()).map_err(|source| DrawError::Bounds {
                kind,
                what: "numbers",
                source,
            })
        };
        match kind {
            "uniform" => pair("uniform").map(Draw::Uniform),
            "log_uniform" => pair("log_uniform").map(Draw::LogUniform),
            "integer" => serde_yaml_ng::from_value::<[i64; 2]>(arg.clone())
                .map(Draw::Integer)
                .map_err(|source| DrawError::Bounds {
                    kind: "integer",
                    what: "integers",
                    source,
                }),
            "choice" => match arg {
                Value::Sequence(l) => Ok(Draw::Choice(l.clone())),
                other => Err(DrawError::ChoiceNotList {
                    found: describe(other),
                }),
            },
            "jitter" => Ok(Draw::Jitter(arg.clone())),
            other => Err(DrawError::Unknown {
                name: other.to_string(),
            }),
        }
    }
}

/// What a sweep key varies.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// A key path in the scene.
    Scene(KeyPath),
    /// `job.joints`: drive the robot from this `/joint_states` bag.
    Joints,
    /// `job.time_scale`: every robot trajectory time multiplied by this.
    TimeScale,
}

impl Target {
    pub(super) fn parse(key: &str) -> Result<Target, TargetError> {
        match key {
            "job.joints" => Ok(Target::Joints),
            "job.time_scale" => Ok(Target::TimeScale),
            k if k.starts_with("job.") => Err(TargetError::UnknownJobKey { key: k.to_string() }),
            k => Ok(Target::Scene(KeyPath::parse(k)?)),
        }
    }
}

pub(super) fn check_draw(draw: &Draw, target: &Target, base: &Value) -> Result<(), RangeError> {
    let finite = |r: &[f64; 2]| r[0].is_finite() && r[1].is_finite();
    match draw {
        Draw::Uniform([lo, hi]) if !finite(&[*lo, *hi]) || hi < lo => {
            Err(RangeError::Empty { lo: *lo, hi: *hi })
        }
        Draw::LogUniform([lo, hi]) if !finite(&[*lo, *hi]) || hi < lo || *lo <= 0.0 => {
            Err(RangeError::EmptyLog { lo: *lo, hi: *hi })
        }
        Draw::Integer([lo, hi]) if hi < lo => Err(RangeError::EmptyInteger { lo: *lo, hi: *hi }),
        Draw::Choice(v) if v.is_empty() => Err(RangeError::EmptyChoice),
        Draw::Jitter(a) => {
            let Target::Scene(kp) = target else {
                return Err(RangeError::JitterNotScene);
            };
            let around = kp.get(base).ok_or(RangeError::JitterNoValue)?;
            let Some(b) = numbers(around) else {
                return Err(RangeError::JitterNotNumbers {
                    found: describe(around),
                });
            };
            let amp = numbers(a).unwrap_or_default();
            if !(amp.len() == 1 || amp.len() == b.len()) {
                return Err(RangeError::JitterShape {
                    elements: b.len(),
                    amplitudes: amp.len(),
                });
            }
            if amp.iter().all(|x| x.is_finite() && *x >= 0.0) {
                Ok(())
            } else {
                Err(RangeError::JitterNegative)
            }
        }
        _ => Ok(()),
    }
}

/// A number or a list of numbers as f64s.
fn numbers(v: &Value) -> Option<Vec<f64>> {
    match v {
        Value::Number(_) => v.as_f64().map(|x| vec![x]),
        Value::Sequence(l) => l.iter().map(Value::as_f64).collect(),
        _ => None,
    }
}

pub(super) fn sample(draw: &Draw, target: &Target, base: &Value, rng: &mut SplitMix64) -> Value {
    match draw {
        Draw::Uniform([lo, hi]) => Value::from(lo + (hi - lo) * rng.next_f64()),
        Draw::LogUniform([lo, hi]) => {
            let (a, b) = (lo.ln(), hi.ln());
            Value::from((a + (b - a) * rng.next_f64()).exp())
        }
        Draw::Integer([lo, hi]) => {
            let span = (hi - lo) as u64 + 1;
            Value::from(lo + rng.below(span) as i64)
        }
        Draw::Choice(values) => values[rng.below(values.len() as u64) as usize].clone(),
        Draw::Jitter(a) => {
            let Target::Scene(kp) = target else {
                return Value::Null;
            };
            let around = kp.get(base).cloned().unwrap_or(Value::Null);
            let amp = numbers(a).unwrap_or_default();
            let mut jitter = |i: usize, x: f64| {
                let a = amp.get(i).or(amp.first()).copied().unwrap_or(0.0);
                Value::from(x + a * (2.0 * rng.next_f64() - 1.0))
            };
            match around {
                Value::Sequence(l) => Value::Sequence(
                    l.iter()
                        .enumerate()
                        .map(|(i, x)| jitter(i, x.as_f64().unwrap_or(0.0)))
                        .collect(),
                ),
                v => jitter(0, v.as_f64().unwrap_or(0.0)),
            }
        }
    }
}
