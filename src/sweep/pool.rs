//! `drape sweep run --local -j N`: every job of a sweep on this machine, at most `N` at a time.
//!
//! Each job runs as its own process (`drape sweep run FILE --index I`, the same command an array
//! task runs), so a job killed or crashing loses only itself, and its record and bag follow the
//! rules of [`super::job`]. Jobs already done (their bag still has the size and SHA-256 their
//! record gives) are skipped without starting a process. Children
//! get `RAYON_NUM_THREADS` = cores / N (at least 1) unless it is set: results do not depend on
//! it, only the run time does.

use super::error::SweepError;
use super::job::JobFiles;
use super::plan::Sweep;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How the pool runs.
#[derive(Debug, Clone)]
pub struct PoolOptions {
    /// The `drape` executable to run jobs with.
    pub exe: PathBuf,
    /// Jobs at once (at least 1).
    pub jobs: usize,
    /// Extra arguments passed to every `sweep run --index` (e.g. `--distro humble`).
    pub extra_args: Vec<String>,
    /// Where each job's stdout and stderr go (`logs/I.log` in the output folder when `None`).
    pub log_dir: Option<PathBuf>,
}

/// What happened to the jobs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoolReport {
    pub total: usize,
    /// Done before this run.
    pub skipped: usize,
    pub succeeded: usize,
    pub failed: Vec<usize>,
    /// Set when a stop request ended the run early (unstarted jobs stay missing).
    pub interrupted: bool,
}

/// Progress after each finished job: (finished including skipped, total, failed so far).
pub type Progress<'a> = dyn FnMut(usize, usize, usize) + 'a;

/// Runs every job not yet done. `stop` asks running children to stop (SIGTERM: they finish
/// cleanly and record `failed`) and starts no more.
pub fn run_local(
    sweep: &Sweep,
    out: &Path,
    opts: &PoolOptions,
    stop: &AtomicBool,
    progress: &mut Progress,
) -> Result<PoolReport, SweepError> {
    let total = sweep.job_count();
    let mut report = PoolReport {
        total,
        ..PoolReport::default()
    };
    let logs = opts.log_dir.clone().unwrap_or_else(|| out.join("logs"));
    std::fs::create_dir_all(&logs).map_err(|source| SweepError::Io {
        path: logs.clone(),
        source,
    })?;
    let mut todo: Vec<usize> = Vec::new();
    for i in 0..total {
        // A bag changed in place since its record was written is redone, not skipped.
        if JobFiles::new(out, i).done_checked(i, true).is_some() {
            report.skipped += 1;
        } else {
            todo.push(i);
        }
    }
    progress(report.skipped, total, 0);
    let threads = std::env::var("RAYON_NUM_THREADS").ok().unwrap_or_else(|| {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        (cores / opts.jobs.max(1)).max(1).to_string()
    });
    let mut next = todo.into_iter();
    let mut running: Vec<(usize, Child)> = Vec::new();
    let mut stopping = false;
    loop {
        if stop.load(Ordering::Relaxed) && !stopping {
            stopping = true;
            report.interrupted = true;
            for (_, c) in &running {
                terminate(c);
            }
        }
        while !stopping && running.len() < opts.jobs.max(1) {
            let Some(i) = next.next() else { break };
            let log = logs.join(format!("{i:06}.log"));
            // The child writes its log as it runs (no staging file), so the rules of
            // `crate::output` that apply are checked here: never an input, and a symlink
            // planted under the log's name is not followed.
            crate::output::check(&log, &[])?;
            let file = {
                use std::os::unix::fs::OpenOptionsExt;
                std::fs::OpenOptions::new()
                    .write(true)
                    .create(true)
                    .truncate(true)
                    .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
                    .open(&log)
            }
            .map_err(|source| SweepError::Io {
                path: log.clone(),
                source,
            })?;
            let err = file.try_clone().map_err(|source| SweepError::Io {
                path: log.clone(),
                source,
            })?;
            let child = Command::new(&opts.exe)
                .args(["sweep", "run"])
                .arg(&sweep.path)
                .arg("--out")
                .arg(out)
                .arg("--index")
                .arg(i.to_string())
                .args(&opts.extra_args)
                .env("RAYON_NUM_THREADS", &threads)
                .stdin(Stdio::null())
                .stdout(file)
                .stderr(err)
                .spawn()
                .map_err(|source| SweepError::Spawn {
                    exe: opts.exe.clone(),
                    source,
                })?;
            running.push((i, child));
        }
        if running.is_empty() {
            break;
        }
        let mut k = 0;
        let mut changed = false;
        while k < running.len() {
            match running[k].1.try_wait() {
                Ok(Some(_status)) => {
                    let (i, _) = running.swap_remove(k);
                    // The record is the truth: a child may exit 0 with nothing to do.
                    if JobFiles::new(out, i).done().is_some() {
                        report.succeeded += 1;
                    } else {
                        report.failed.push(i);
                    }
                    changed = true;
                }
                Ok(None) => k += 1,
                Err(e) => {
                    let (i, _) = running.swap_remove(k);
                    log::warn!("job {i}: cannot wait for its process: {e}");
                    report.failed.push(i);
                    changed = true;
                }
            }
        }
        if changed {
            progress(
                report.skipped + report.succeeded + report.failed.len(),
                total,
                report.failed.len(),
            );
        } else {
            std::thread::sleep(Duration::from_millis(10));
        }
    }
    report.failed.sort_unstable();
    Ok(report)
}

/// Asks a child to stop with SIGTERM (it finishes its bag and records `failed`).
fn terminate(c: &Child) {
    let _ = Command::new("kill")
        .arg("-TERM")
        .arg(c.id().to_string())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
}
