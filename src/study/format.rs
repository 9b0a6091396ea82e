//! What `runs.csv` and `summary.md` share: writing a file, and how a run's collision mode and
//! a step are written.

use super::{RunRecord, StudyError};
use std::path::PathBuf;

pub(super) fn write(path: PathBuf, text: &str) -> Result<PathBuf, StudyError> {
    crate::output::write(&path, text.as_bytes(), &[])?;
    Ok(path)
}

/// Detection mode as written in scene files, "scene" for the scene's own, "n/a" without collisions.
pub(super) fn collision_mode(x: &RunRecord) -> String {
    match x.settings.collision {
        _ if !x.collides => "n/a".into(),
        Some((m, _)) => format!("{m:?}").to_lowercase(),
        None => "scene".into(),
    }
}

pub(super) fn dt_str(dt: f64) -> String {
    format!("1/{:.0}", 1.0 / dt)
}
