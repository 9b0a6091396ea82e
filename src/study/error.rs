//! What can stop a study: [`StudyError`].

use std::path::PathBuf;

/// Why a study could not finish.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error("reference for scene '{scene}' at resolution {n}: {reason}")]
    Reference {
        scene: String,
        n: usize,
        reason: String,
    },
    #[error("plot {path}: {reason}")]
    Plot { path: PathBuf, reason: String },
}
