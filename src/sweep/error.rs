//! [`SweepError`]: what can be wrong with a sweep, its files or one of its jobs, as variants with
//! fields (the file, the key, the job) and the cause (the scene's error, the I/O or parse error)
//! as `source()`; the command line prints the chain.

use super::draw::{DrawError, RangeError, TargetError};
use super::keypath::SetError;
use crate::scene::SceneError;
use std::path::PathBuf;

/// A sweep that cannot be planned or run; names the file and the key or job, and keeps the
/// cause (the scene's error, the I/O or parse error) as its `source()`. Large causes are boxed:
/// the error stays small on every `Ok` path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SweepError {
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The sweep file (or another file a sweep reads) is not a regular file of bounded size.
    #[error(transparent)]
    Input(Box<crate::input::InputError>),
    /// An output would overwrite an input, or could not be written whole.
    #[error(transparent)]
    Output(Box<crate::output::OutputError>),
    /// The sweep file or the base scene is not YAML of the expected form.
    #[error("{origin}: not a valid sweep file or scene")]
    Yaml {
        origin: String,
        #[source]
        source: serde_yaml_ng::Error,
    },
    /// `plan.json` (or a record) is not what `drape sweep` writes.
    #[error("{origin}: not a sweep plan")]
    Json {
        origin: String,
        #[source]
        source: serde_json::Error,
    },
    /// The base scene named by `scene:` cannot be read.
    #[error("{origin}: scene: cannot read {}", path.display())]
    SceneFile {
        origin: String,
        path: PathBuf,
        #[source]
        source: Box<crate::input::InputError>,
    },
    /// A key of the sweep file is wrong (unknown path, wrong type, empty range, ...).
    #[error("{origin}: {key}")]
    Key {
        origin: String,
        key: String,
        #[source]
        source: Box<KeyError>,
    },
    /// A value of a key that the scene rejects (the scene's error is the source).
    #[error("{origin}: {key}: value {value}")]
    KeyValue {
        origin: String,
        key: String,
        value: String,
        #[source]
        source: JobSceneError,
    },
    /// A job's value of `key` cannot be set on the scene document.
    #[error("{origin}: job {index} ({params}): {key}")]
    Job {
        origin: String,
        index: usize,
        params: String,
        key: String,
        #[source]
        source: Box<ApplyError>,
    },
    /// A job's scene is not valid (the scene's error is the source).
    #[error("{origin}: job {index} ({params})")]
    JobScene {
        origin: String,
        index: usize,
        params: String,
        #[source]
        source: JobSceneError,
    },
    #[error("job index {index} is out of range: the sweep has {count} jobs (0 to {})", count.saturating_sub(1))]
    IndexOutOfRange { index: usize, count: usize },
    /// `plan.json` would pass the sweep plan's size cap.
    #[error("{}: the plan is larger than the {cap} bytes allowed (the jobs' values are too large)", path.display())]
    PlanTooLarge { path: PathBuf, cap: u64 },
    /// Another process runs this job now (it holds the job's lock).
    #[error("job {index} is already running (another process holds {}); a job runs once at a time", lock.display())]
    Busy { index: usize, lock: PathBuf },
    /// `plan.json` does not list each job once, in order, as many as it says.
    #[error("{}: {why}", path.display())]
    BadPlan { path: PathBuf, why: String },
    #[error("cannot encode {what}")]
    Encode {
        what: String,
        #[source]
        source: serde_json::Error,
    },
    #[error("cannot start {}", exe.display())]
    Spawn {
        exe: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl From<crate::input::InputError> for SweepError {
    fn from(e: crate::input::InputError) -> Self {
        SweepError::Input(Box::new(e))
    }
}

impl From<crate::output::OutputError> for SweepError {
    fn from(e: crate::output::OutputError) -> Self {
        SweepError::Output(Box::new(e))
    }
}

/// Why a job's scene document is not a scene.
#[derive(Debug, thiserror::Error)]
pub enum JobSceneError {
    #[error("cannot write the job's scene as YAML")]
    Encode(#[source] serde_yaml_ng::Error),
    #[error(transparent)]
    Scene(Box<SceneError>),
}

/// What is wrong with one key of a sweep file ([`SweepError::Key`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum KeyError {
    #[error("must be at least 1")]
    ZeroSamples,
    /// `samples` times the grid's lists makes more jobs than a sweep may have.
    #[error("{count} jobs: a sweep has at most {max} (split it into several sweep files)")]
    TooManyJobs { count: String, max: usize },
    /// The jobs' scene documents, which are all checked before any job runs, are too large.
    #[error("{count} jobs of {bytes}-byte scene documents: more than the {max} bytes a sweep checks (fewer jobs, or a smaller scene)")]
    TooMuchWork { count: usize, bytes: u64, max: u64 },
    /// `name` with a character outside letters, digits, spaces, `-`, `_` and `.` (or longer
    /// than `max`).
    #[error("must be 1 to {max} letters, digits, spaces, `-`, `_` or `.`{}", found.as_ref().map(|c| format!(" (found {c})")).unwrap_or_default())]
    BadName { found: Option<String>, max: usize },
    /// A key of `set`, `grid` or `random` that is not a string (`got`: the key as JSON).
    #[error("keys must be key paths (strings), got {got}")]
    NotAKeyPath { got: String },
    #[error(transparent)]
    Target(#[from] TargetError),
    #[error("job keys vary per job: put them under grid or random")]
    JobKeyInSet,
    #[error(transparent)]
    Set(#[from] SetError),
    #[error("must be a list of values, got {found}")]
    NotAList { found: &'static str },
    #[error("empty list: no values to run")]
    EmptyList,
    /// The key is varied by two `grid` entries, or by `grid` and `random` (`also_grid`).
    #[error("varied twice{}", if *also_grid { " (also under grid)" } else { "" })]
    VariedTwice { also_grid: bool },
    #[error(transparent)]
    Draw(#[from] DrawError),
    #[error(transparent)]
    Range(#[from] RangeError),
    /// This key's value (as JSON) cannot be set over job 0's other values.
    #[error("value {value}")]
    Value {
        value: String,
        #[source]
        source: ApplyError,
    },
    /// Another key's value of job 0 cannot be set (the key is the error's key).
    #[error(transparent)]
    Apply(#[from] ApplyError),
}

/// Why one sweep value cannot be set on a job's scene document (or as its joints bag).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ApplyError {
    #[error(transparent)]
    Target(#[from] TargetError),
    #[error(transparent)]
    Set(#[from] SetError),
    #[error("must be a bag path, got {found}")]
    NotABagPath { found: &'static str },
    #[error("no such bag: {}", path.display())]
    NoSuchBag { path: PathBuf },
    /// `job.time_scale` that is not a number > 0 (`value` as JSON).
    #[error("must be a number > 0, got {value}")]
    BadTimeScale { value: String },
    #[error("the scene has no robot trajectory to scale")]
    NoTrajectory,
}
