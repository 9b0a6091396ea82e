//! What can stop a study: [`StudyError`], each variant with the file, scene or plot at fault
//! and its cause as `source()`.

use std::path::PathBuf;

/// Why a study could not finish.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudyError {
    #[error("{path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// A cached reference holds a value that no run writes (NaN or infinite).
    #[error("{}: cached reference: {what} of sample {sample} is not finite (delete the file to recompute it)", path.display())]
    BadCache {
        path: PathBuf,
        what: String,
        sample: usize,
    },
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error(
        "reference for scene '{scene}' at resolution {n}: RK4 diverged down to dt level {dt_level}"
    )]
    ReferenceDiverged {
        scene: String,
        n: usize,
        dt_level: u32,
    },
    #[error("plot {path}")]
    Plot {
        path: PathBuf,
        #[source]
        source: plotters::drawing::DrawingAreaErrorKind<std::io::Error>,
    },
}
