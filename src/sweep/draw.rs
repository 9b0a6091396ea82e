//! Random draws of a sweep ([`Draw`]: uniform, log-uniform, integer, choice, jitter) and what a
//! sweep key varies ([`Target`]); their checks against the base scene and their sampling.

use super::keypath::{describe, KeyPath};
use super::rng::SplitMix64;
use serde::{Deserialize, Serialize};
use serde_yaml_ng::Value;

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
    pub fn from_value(v: &Value) -> Result<Draw, String> {
        let m = match v {
            Value::Mapping(m) if m.len() == 1 => m,
            _ => return Err(format!("expected a draw, got {}", describe(v))),
        };
        let Some((k, arg)) = m.iter().next() else {
            return Err("expected a draw".into());
        };
        let kind = k.as_str().unwrap_or_default();
        let pair = |what: &str| -> Result<[f64; 2], String> {
            serde_yaml_ng::from_value::<[f64; 2]>(arg.clone())
                .map_err(|e| format!("{kind}: expected [lo, hi] {what}: {e}"))
        };
        match kind {
            "uniform" => pair("numbers").map(Draw::Uniform),
            "log_uniform" => pair("numbers").map(Draw::LogUniform),
            "integer" => serde_yaml_ng::from_value::<[i64; 2]>(arg.clone())
                .map(Draw::Integer)
                .map_err(|e| format!("integer: expected [lo, hi] integers: {e}")),
            "choice" => match arg {
                Value::Sequence(l) => Ok(Draw::Choice(l.clone())),
                other => Err(format!("choice: expected a list, got {}", describe(other))),
            },
            "jitter" => Ok(Draw::Jitter(arg.clone())),
            other => Err(format!(
                "unknown draw `{other}` (uniform, log_uniform, integer, choice, jitter)"
            )),
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
    pub(super) fn parse(key: &str) -> Result<Target, String> {
        match key {
            "job.joints" => Ok(Target::Joints),
            "job.time_scale" => Ok(Target::TimeScale),
            k if k.starts_with("job.") => Err(
                "unknown job key (job.joints: a joint-states bag, job.time_scale: trajectory time scale)"
                    .to_string(),
            ),
            k => KeyPath::parse(k).map(Target::Scene),
        }
    }
}

pub(super) fn check_draw(draw: &Draw, target: &Target, base: &Value) -> Result<(), String> {
    let finite = |r: &[f64; 2]| r[0].is_finite() && r[1].is_finite();
    match draw {
        Draw::Uniform(r) if !finite(r) || r[1] < r[0] => {
            Err(format!("empty range [{}, {}]: needs lo <= hi", r[0], r[1]))
        }
        Draw::LogUniform(r) if !finite(r) || r[1] < r[0] || r[0] <= 0.0 => Err(format!(
            "empty range [{}, {}]: needs 0 < lo <= hi",
            r[0], r[1]
        )),
        Draw::Integer(r) if r[1] < r[0] => {
            Err(format!("empty range [{}, {}]: needs lo <= hi", r[0], r[1]))
        }
        Draw::Choice(v) if v.is_empty() => Err("empty choice: no values to draw from".into()),
        Draw::Jitter(a) => {
            let Target::Scene(kp) = target else {
                return Err("jitter applies to scene values only".into());
            };
            let around = kp.get(base).ok_or_else(|| {
                "jitter needs a value in the scene to jitter around (set it under `set`)"
                    .to_string()
            })?;
            let (n_base, n_amp) = (numbers(around), numbers(a));
            match (n_base, n_amp) {
                (Some(b), Some(amp)) if amp.len() == 1 || amp.len() == b.len() => {
                    if amp.iter().all(|x| x.is_finite() && *x >= 0.0) {
                        Ok(())
                    } else {
                        Err("jitter amplitudes must be >= 0".into())
                    }
                }
                (None, _) => Err(format!(
                    "jitter needs a number or a list of numbers, the scene has {}",
                    describe(around)
                )),
                _ => Err("jitter needs one amplitude or one per element".into()),
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
