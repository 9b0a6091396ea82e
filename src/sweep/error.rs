//! [`SweepError`]: what can be wrong with a sweep, its files or one of its jobs, as variants with
//! fields (the file, the key, the job) and the cause (the scene's error, the I/O or parse error)
//! as `source()`; the command line prints the chain.

use crate::scene::SceneError;
use std::path::PathBuf;

/// A sweep that cannot be planned or run; names the file and the key or job, and keeps the
/// cause (the scene's error, the I/O or parse error) as its `source()`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SweepError {
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
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
        source: std::io::Error,
    },
    /// A key of the sweep file is wrong (unknown path, wrong type, empty range, ...).
    #[error("{origin}: {key}: {reason}")]
    Key {
        origin: String,
        key: String,
        reason: String,
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
    /// A job's values cannot be set on the scene document.
    #[error("{origin}: job {index} ({params}): {reason}")]
    Job {
        origin: String,
        index: usize,
        params: String,
        reason: String,
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
    #[error("{origin}: too many jobs (the grid overflows)")]
    TooManyJobs { origin: String },
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

/// Why a job's scene document is not a scene.
#[derive(Debug, thiserror::Error)]
pub enum JobSceneError {
    #[error("cannot write the job's scene as YAML")]
    Encode(#[source] serde_yaml_ng::Error),
    #[error(transparent)]
    Scene(Box<SceneError>),
}
