//! What bounds a sweep before any work: its job count, the size of the job scene documents it
//! checks, and what its `name` may hold.

use super::draw::Target;
use super::error::KeyError;
use serde_yaml_ng::Value;

/// Most jobs in one sweep (also the most completions of a Kubernetes Indexed Job); a larger
/// dataset is several sweep files.
pub const MAX_JOBS: usize = 100_000;

/// Most bytes of job scene documents a sweep may make (jobs times the scene document's size):
/// [`super::Sweep::load`] parses and validates each one, and this bounds its time (about ten
/// seconds on two cores of a debug build, a few in a release build).
pub const MAX_JOB_DOCUMENTS: u64 = 64 << 20;

/// Jobs of a sweep (`samples` times each grid list's length), refused above [`MAX_JOBS`] or
/// [`MAX_JOB_DOCUMENTS`] before anything is built; the error names `samples` or `grid`.
pub(super) fn job_count(
    samples: usize,
    axes: &[(String, Target, Vec<Value>)],
    base: &Value,
) -> Result<usize, (&'static str, KeyError)> {
    let key = if axes.is_empty() { "samples" } else { "grid" };
    let mut count = samples as u128;
    for (_, _, values) in axes {
        count = count.saturating_mul(values.len() as u128);
    }
    if count > MAX_JOBS as u128 {
        return Err((
            key,
            KeyError::TooManyJobs {
                count: if count >= u64::MAX as u128 {
                    "more than 2^64".into()
                } else {
                    count.to_string()
                },
                max: MAX_JOBS,
            },
        ));
    }
    let doc = serde_yaml_ng::to_string(base).map_or(0, |t| t.len()) as u64;
    let widest: u64 = axes
        .iter()
        .map(|(_, _, values)| {
            values
                .iter()
                .map(|v| serde_json::to_string(v).map_or(0, |t| t.len()) as u64)
                .max()
                .unwrap_or(0)
        })
        .sum();
    let per_job = doc + widest;
    if (count as u64).saturating_mul(per_job) > MAX_JOB_DOCUMENTS {
        return Err((
            key,
            KeyError::TooMuchWork {
                count: count as usize,
                bytes: per_job,
                max: MAX_JOB_DOCUMENTS,
            },
        ));
    }
    Ok(count as usize)
}

/// Longest sweep `name`.
pub const MAX_NAME: usize = 100;

/// What a sweep name may hold: it reaches job names, log file names and comment lines of the
/// scheduler files (`sweep emit`), so nothing a shell, YAML or a file name would read as syntax.
pub(super) fn name_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | ' ')
}

pub(super) fn check_name(name: &str) -> Result<(), KeyError> {
    let bad = name.chars().find(|c| !name_char(*c));
    if name.chars().count() > MAX_NAME || bad.is_some() {
        return Err(KeyError::BadName {
            found: bad.map(|c| format!("{c:?}")),
            max: MAX_NAME,
        });
    }
    Ok(())
}
