//! Sweep files and their plan: which jobs a sweep has and each job's scene.
//!
//! ```yaml
//! name: three_corner_materials
//! scene: ../config/three_corner_normal.yaml    # relative to the sweep file
//! out: runs/three_corner                       # output folder (default: <sweep>.out beside it)
//! seed: 7                                      # random draws depend on the seed and job index only
//! samples: 10                                  # random draws per grid point (default 1)
//! set:                                         # applied to every job
//!   duration: 2.0
//! grid:                                        # every combination, the last key fastest
//!   cloths[0].material.stretch: [1000, 2000]
//!   effects: [[gravity, stretch, shear, bending, damping], [gravity, stretch, shear, bending, damping, wind]]
//! random:
//!   cloths[0].material.bend_warp: { log_uniform: [1.0e-4, 1.0e-2] }
//!   wind.velocity[0]: { uniform: [0.0, 4.0] }
//!   cloths[0].grid.pose.xyz: { jitter: [0.02, 0.02, 0.0] }   # base value + uniform(-a, a)
//!   solver.substeps: { integer: [1, 3] }
//!   cloths[0].grid.resolution: { choice: [[16, 16], [24, 24]] }
//!   job.time_scale: { uniform: [0.8, 1.25] }   # robot trajectory times scaled (slower above 1)
//! # job.joints: a `/joint_states` bag per job (grid list or choice), relative to the sweep file
//! ```
//!
//! Key paths are the scene's own (`cloths[0].material.stretch`) and are set on the scene's YAML
//! value before the scene's strict parse and validation, so a bad value gets the scene's own
//! error, prefixed with the sweep key that set it. [`Sweep::load`] checks every key and every
//! job's scene before returning, so a bad sweep fails before any job runs.
//!
//! Jobs are numbered `0..job_count()`: grid point `index / samples`, draw `index % samples`.

use super::draw::{check_draw, sample, Draw, Target};
use super::error::{ApplyError, JobSceneError, KeyError, SweepError};
use super::keypath::{describe, KeyPath};
use super::limits::{check_name, job_count, name_char};
pub use super::limits::{MAX_JOBS, MAX_JOB_DOCUMENTS, MAX_NAME};
use super::rng::SplitMix64;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use serde_yaml_ng::{Mapping, Value};
use std::path::{Path, PathBuf};

/// The sweep file as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    #[serde(default)]
    pub name: String,
    /// Base scene, relative to the sweep file.
    pub scene: PathBuf,
    /// Output folder, relative to the sweep file.
    #[serde(default)]
    pub out: Option<PathBuf>,
    #[serde(default)]
    pub seed: u64,
    /// Random draws per grid point.
    #[serde(default = "one")]
    pub samples: usize,
    /// Key path -> value, applied to every job.
    #[serde(default)]
    pub set: Mapping,
    /// Key path -> list of values; jobs run every combination.
    #[serde(default)]
    pub grid: Mapping,
    /// Key path -> draw.
    #[serde(default)]
    pub random: Mapping,
}

fn one() -> usize {
    1
}

/// One job of a sweep: its index and the values it sets, in the sweep file's key order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Job {
    pub index: usize,
    pub params: Vec<(String, Value)>,
}

impl Job {
    /// `key=value, ...` for messages.
    pub fn describe(&self) -> String {
        self.params
            .iter()
            .map(|(k, v)| format!("{k}={}", inline(v)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// A value on one line (YAML flow style via JSON).
pub fn inline(v: &Value) -> String {
    serde_json::to_string(v).unwrap_or_else(|_| format!("{v:?}"))
}

/// What a job runs: its scene and, with `job.joints`, the bag that drives the robot.
#[derive(Debug, Clone)]
pub struct JobSpec {
    pub scene: Scene,
    pub joints: Option<PathBuf>,
}

/// A loaded, checked sweep.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The sweep file.
    pub path: PathBuf,
    pub name: String,
    /// The base scene file.
    pub scene_path: PathBuf,
    /// Default output folder (from the file, else `<sweep>.out` beside it).
    pub out_dir: PathBuf,
    base: Value,
    axes: Vec<(String, Target, Vec<Value>)>,
    draws: Vec<(String, Target, Draw)>,
    samples: usize,
    seed: u64,
    count: usize,
}

impl Sweep {
    /// Reads and checks a sweep file: every key path, value type and range, and the scene of
    /// every job (the scene's strict parse and validation), so that a bad sweep fails here,
    /// before any job runs.
    pub fn load(path: &Path) -> Result<Sweep, SweepError> {
        let text = crate::input::read_text(path, crate::input::InputKind::Sweep)?;
        let sweep = Self::from_yaml(&text, path)?;
        // Jobs are checked on every core; the error reported is the lowest job's.
        use rayon::prelude::*;
        let first = (0..sweep.count)
            .into_par_iter()
            .find_map_first(|i| sweep.job(i).and_then(|j| sweep.job_spec(&j)).err());
        match first {
            Some(e) => Err(e),
            None => Ok(sweep),
        }
    }

    /// Reads a sweep file and checks each key, but not every job's scene: what one array task
    /// needs before running its own job (the whole plan was checked by `plan`, `emit` or
    /// `run --local`).
    pub fn open(path: &Path) -> Result<Sweep, SweepError> {
        let text = crate::input::read_text(path, crate::input::InputKind::Sweep)?;
        Self::from_yaml(&text, path)
    }

    /// Parses a sweep file's text (`path` locates the scene and names errors) and checks each
    /// key on its own; [`Sweep::load`] also checks every job.
    pub fn from_yaml(text: &str, path: &Path) -> Result<Sweep, SweepError> {
        let origin = path.display().to_string();
        let key_err = |key: &str, source: KeyError| SweepError::Key {
            origin: origin.clone(),
            key: key.to_string(),
            source: Box::new(source),
        };
        let file: SweepFile = serde_yaml_ng::from_str(text).map_err(|source| SweepError::Yaml {
            origin: origin.clone(),
            source,
        })?;
        if file.samples == 0 {
            return Err(key_err("samples", KeyError::ZeroSamples));
        }
        let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
        let scene_path = dir.join(&file.scene);
        let scene_text = crate::input::read_text(&scene_path, crate::input::InputKind::Scene)
            .map_err(|source| SweepError::SceneFile {
                origin: origin.clone(),
                path: scene_path.clone(),
                source: Box::new(source),
            })?;
        let mut base: Value =
            serde_yaml_ng::from_str(&scene_text).map_err(|source| SweepError::Yaml {
                origin: scene_path.display().to_string(),
                source,
            })?;
        let key_of = |k: &Value, section: &str| -> Result<String, SweepError> {
            k.as_str()
                .map(str::to_string)
                .ok_or_else(|| key_err(section, KeyError::NotAKeyPath { got: inline(k) }))
        };

        for (k, v) in &file.set {
            let key = key_of(k, "set")?;
            let name = format!("set.{key}");
            let target = Target::parse(&key).map_err(|r| key_err(&name, r.into()))?;
            let Target::Scene(kp) = target else {
                return Err(key_err(&name, KeyError::JobKeyInSet));
            };
            kp.set(&mut base, v.clone())
                .map_err(|r| key_err(&name, r.into()))?;
        }

        let mut seen: Vec<String> = Vec::new();
        let mut axes = Vec::new();
        for (k, v) in &file.grid {
            let key = key_of(k, "grid")?;
            let name = format!("grid.{key}");
            let target = Target::parse(&key).map_err(|r| key_err(&name, r.into()))?;
            let Value::Sequence(values) = v else {
                return Err(key_err(&name, KeyError::NotAList { found: describe(v) }));
            };
            if values.is_empty() {
                return Err(key_err(&name, KeyError::EmptyList));
            }
            if seen.contains(&key) {
                return Err(key_err(&name, KeyError::VariedTwice { also_grid: false }));
            }
            seen.push(key.clone());
            axes.push((key, target, values.clone()));
        }
        let mut draws = Vec::new();
        for (k, v) in &file.random {
            let key = key_of(k, "random")?;
            let name = format!("random.{key}");
            let target = Target::parse(&key).map_err(|r| key_err(&name, r.into()))?;
            let draw = Draw::from_value(v).map_err(|e| key_err(&name, e.into()))?;
            check_draw(&draw, &target, &base).map_err(|r| key_err(&name, r.into()))?;
            if seen.contains(&key) {
                return Err(key_err(&name, KeyError::VariedTwice { also_grid: true }));
            }
            seen.push(key.clone());
            draws.push((key, target, draw));
        }

        let count = job_count(file.samples, &axes, &base).map_err(|e| key_err(e.0, e.1))?;
        let out_dir = match &file.out {
            Some(o) => dir.join(o),
            None => dir.join(format!(
                "{}.out",
                path.file_stem().and_then(|s| s.to_str()).unwrap_or("sweep")
            )),
        };
        let name = if file.name.is_empty() {
            // The file's stem, with anything a name may not hold replaced.
            path.file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("sweep")
                .chars()
                .take(MAX_NAME)
                .map(|c| if name_char(c) { c } else { '_' })
                .collect()
        } else {
            check_name(&file.name).map_err(|e| key_err("name", e))?;
            file.name.clone()
        };
        let sweep = Sweep {
            path: path.to_path_buf(),
            name,
            scene_path,
            out_dir,
            base,
            axes,
            draws,
            samples: file.samples,
            seed: file.seed,
            count,
        };
        sweep.check_keys_alone()?;
        Ok(sweep)
    }

    /// Each grid value, and each draw of job 0, set over job 0's other values must parse: an
    /// error there belongs to that key (the scene may need the other keys to be valid, e.g. a
    /// `wind` effect and a drawn `wind.velocity`).
    fn check_keys_alone(&self) -> Result<(), SweepError> {
        let origin = self.path.display().to_string();
        let first = self.job(0)?;
        let mut singles: Vec<(String, String, Value)> = Vec::new();
        for (key, _, values) in &self.axes {
            for v in values {
                singles.push((format!("grid.{key}"), key.clone(), v.clone()));
            }
        }
        for (key, _, _) in &self.draws {
            if let Some((_, v)) = first.params.iter().find(|(k, _)| k == key) {
                singles.push((format!("random.{key}"), key.clone(), v.clone()));
            }
        }
        for (name, key, v) in singles {
            let params: Vec<(String, Value)> = first
                .params
                .iter()
                .map(|(k, old)| (k.clone(), if *k == key { v.clone() } else { old.clone() }))
                .collect();
            let (doc, _) = self.document(&params).map_err(|(k, source)| {
                if k == key {
                    SweepError::Key {
                        origin: origin.clone(),
                        key: name.clone(),
                        source: Box::new(KeyError::Value {
                            value: inline(&v),
                            source,
                        }),
                    }
                } else {
                    SweepError::Key {
                        origin: origin.clone(),
                        key: k,
                        source: Box::new(source.into()),
                    }
                }
            })?;
            self.parse_scene(&doc, &name)
                .map_err(|source| SweepError::KeyValue {
                    origin: origin.clone(),
                    key: name.clone(),
                    value: inline(&v),
                    source,
                })?;
        }
        Ok(())
    }

    /// The base scene with `params` set (scene keys in order, then the trajectory scale, which
    /// reads the final trajectory), and the joints bag if one is named. Errors name the key.
    fn document(
        &self,
        params: &[(String, Value)],
    ) -> Result<(Value, Option<PathBuf>), (String, ApplyError)> {
        let mut doc = self.base.clone();
        let mut joints = None;
        let mut scale = None;
        for (key, value) in params {
            let target = Target::parse(key).map_err(|r| (key.clone(), r.into()))?;
            if target == Target::TimeScale {
                scale = Some((key, value));
                continue;
            }
            apply(&mut doc, &target, value, &self.path, &mut joints)
                .map_err(|r| (key.clone(), r))?;
        }
        if let Some((key, v)) = scale {
            apply(&mut doc, &Target::TimeScale, v, &self.path, &mut joints)
                .map_err(|r| (key.clone(), r))?;
        }
        Ok((doc, joints))
    }

    pub fn job_count(&self) -> usize {
        self.count
    }

    /// The values job `index` sets.
    pub fn job(&self, index: usize) -> Result<Job, SweepError> {
        if index >= self.count {
            return Err(SweepError::IndexOutOfRange {
                index,
                count: self.count,
            });
        }
        let mut params = Vec::new();
        let mut point = index / self.samples;
        let mut picks = vec![0; self.axes.len()];
        for (a, (_, _, values)) in self.axes.iter().enumerate().rev() {
            picks[a] = point % values.len();
            point /= values.len();
        }
        for (a, (key, _, values)) in self.axes.iter().enumerate() {
            params.push((key.clone(), values[picks[a]].clone()));
        }
        let mut rng = SplitMix64::for_job(self.seed, index);
        for (key, target, draw) in &self.draws {
            params.push((key.clone(), sample(draw, target, &self.base, &mut rng)));
        }
        Ok(Job { index, params })
    }

    /// Job `job`'s scene, parsed and validated.
    pub fn job_spec(&self, job: &Job) -> Result<JobSpec, SweepError> {
        let origin = || self.path.display().to_string();
        let (doc, joints) =
            self.document(&job.params)
                .map_err(|(key, source)| SweepError::Job {
                    origin: origin(),
                    index: job.index,
                    params: job.describe(),
                    key,
                    source: Box::new(source),
                })?;
        let scene = self
            .parse_scene(&doc, &format!("job {}", job.index))
            .map_err(|source| SweepError::JobScene {
                origin: origin(),
                index: job.index,
                params: job.describe(),
                source,
            })?;
        Ok(JobSpec { scene, joints })
    }

    fn parse_scene(&self, doc: &Value, what: &str) -> Result<Scene, JobSceneError> {
        let text = serde_yaml_ng::to_string(doc).map_err(JobSceneError::Encode)?;
        let origin = format!("{} ({what})", self.scene_path.display());
        let mut scene =
            Scene::from_yaml(&text, &origin).map_err(|e| JobSceneError::Scene(Box::new(e)))?;
        scene.base_dir = self.scene_path.parent().map(Path::to_path_buf);
        Ok(scene)
    }

    /// Every job's values, for the plan file and `drape sweep plan`.
    pub fn jobs(&self) -> impl Iterator<Item = Job> + '_ {
        (0..self.count).filter_map(|i| self.job(i).ok())
    }
}

/// Sets one sweep value on the scene document (or records the joints bag).
fn apply(
    doc: &mut Value,
    target: &Target,
    value: &Value,
    sweep_path: &Path,
    joints: &mut Option<PathBuf>,
) -> Result<(), ApplyError> {
    match target {
        Target::Scene(kp) => Ok(kp.set(doc, value.clone())?),
        Target::Joints => {
            let s = value.as_str().ok_or(ApplyError::NotABagPath {
                found: describe(value),
            })?;
            let p = sweep_path.parent().unwrap_or(Path::new("")).join(s);
            if !p.is_file() {
                return Err(ApplyError::NoSuchBag { path: p });
            }
            *joints = Some(p);
            Ok(())
        }
        Target::TimeScale => {
            let s = value
                .as_f64()
                .filter(|s| s.is_finite() && *s > 0.0)
                .ok_or_else(|| ApplyError::BadTimeScale {
                    value: inline(value),
                })?;
            let path = KeyPath::of_keys(&["robot", "trajectory", "points"]);
            let Some(Value::Sequence(mut points)) = path.get(doc).cloned() else {
                return Err(ApplyError::NoTrajectory);
            };
            for p in &mut points {
                if let Some(t) = p.get_mut("t") {
                    let scaled = t.as_f64().map(|t| t * s);
                    if let Some(x) = scaled {
                        *t = Value::from(x);
                    }
                }
            }
            Ok(path.set(doc, Value::Sequence(points))?)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sweep(body: &str) -> Result<Sweep, SweepError> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
        let text = format!("scene: three_corner_normal.yaml\nseed: 5\n{body}");
        Sweep::from_yaml(&text, &dir.join("test_sweep.yaml"))
    }

    #[test]
    fn grid_order_and_samples() {
        let s = sweep("samples: 2\ngrid:\n  duration: [1.0, 2.0]\n  solver.substeps: [1, 2, 3]\n")
            .unwrap();
        assert_eq!(s.job_count(), 12);
        let v = |i: usize| -> (f64, u64) {
            let j = s.job(i).unwrap();
            (
                j.params[0].1.as_f64().unwrap(),
                j.params[1].1.as_u64().unwrap(),
            )
        };
        assert_eq!(v(0), (1.0, 1));
        assert_eq!(v(1), (1.0, 1));
        assert_eq!(v(2), (1.0, 2));
        assert_eq!(v(6), (2.0, 1));
        assert_eq!(v(11), (2.0, 3));
        let spec = s.job_spec(&s.job(11).unwrap()).unwrap();
        assert_eq!(spec.scene.duration, 2.0);
        assert_eq!(spec.scene.solver.substeps, 3);
        assert!(matches!(
            s.job(12),
            Err(SweepError::IndexOutOfRange {
                index: 12,
                count: 12
            })
        ));
    }

    #[test]
    fn draws_stay_in_their_ranges() {
        let s = sweep(
            "samples: 50\nrandom:\n  cloths[0].material.stretch: { uniform: [1000, 2000] }\n  \
             cloths[0].material.bend_warp: { log_uniform: [1.0e-4, 1.0e-2] }\n  \
             solver.substeps: { integer: [1, 3] }\n  cloths[0].grid.pose.xyz: { jitter: 0.1 }\n",
        )
        .unwrap();
        let mut substeps = std::collections::BTreeSet::new();
        for j in s.jobs() {
            let k = j.params[0].1.as_f64().unwrap();
            assert!((1000.0..=2000.0).contains(&k));
            let b = j.params[1].1.as_f64().unwrap();
            assert!((1e-4..=1e-2).contains(&b));
            substeps.insert(j.params[2].1.as_u64().unwrap());
            let z = j.params[3].1.as_sequence().unwrap()[2].as_f64().unwrap();
            assert!((z - 1.0).abs() <= 0.1);
        }
        assert_eq!(substeps.into_iter().collect::<Vec<_>>(), [1, 2, 3]);
    }

    #[test]
    fn bad_keys_are_named() {
        // The whole chain, as the command line shows it: the scene's causes are sources.
        let err = |body: &str| crate::input::error_line(&sweep(body).unwrap_err());
        let e = err("grid:\n  cloths[0].material.stiffnes: [1]\n");
        assert!(
            e.contains("grid.cloths[0].material.stiffnes") && e.contains("unknown field"),
            "{e}"
        );
        let e = err("random:\n  solver.dt: { uniform: [0.1, 0.01] }\n");
        assert!(
            e.contains("random.solver.dt") && e.contains("empty range"),
            "{e}"
        );
        let e = err("random:\n  solver.dt: { gaussian: [0.1, 0.01] }\n");
        assert!(
            e.contains("random.solver.dt") && e.contains("unknown draw"),
            "{e}"
        );
        let e = err("grid:\n  solver.dt: 0.1\n");
        assert!(
            e.contains("grid.solver.dt") && e.contains("must be a list"),
            "{e}"
        );
        let e = err("grid:\n  job.speed: [1]\n");
        assert!(
            e.contains("grid.job.speed") && e.contains("unknown job key"),
            "{e}"
        );
        let e = err("samples: 0\n");
        assert!(e.contains("samples"), "{e}");
    }
}
