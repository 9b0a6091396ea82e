//! Running one job of a sweep (what one Slurm array task or Kubernetes pod runs) and its result
//! record.
//!
//! Files of job `I` in the output folder (`I` zero-padded to 6 digits):
//! - `jobs/I.mcap.part`: the bag while it is written;
//! - `jobs/I.mcap`: the finished bag, renamed from the `.part` only once it is complete;
//! - `jobs/I.json`: the result record, written last (through a temporary file and a rename).
//!
//! So a killed job never leaves a bag under its final name that is not complete, a job with a
//! record whose bag is present and of the recorded size is done (and is skipped by a rerun), and
//! anything else is redone. A job stopped by SIGTERM or SIGINT (Slurm's `scancel`, Kubernetes'
//! pod deletion, Ctrl-C) removes its partial bag and writes a record with status `failed`.

use super::error::SweepError;
use super::plan::{inline, Job, Sweep};
use crate::ros::record::{record_with_robot, RecordOptions};
use crate::ros::telemetry::RunSummary;
use crate::ros::Distro;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// `ok` or `failed` (a record); `missing` and `running`/`killed` appear only in manifests.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Ok,
    Failed,
    /// No record and no partial bag: never run (or its record was lost).
    Missing,
}

/// The result record of one job (`jobs/I.json`), also one line of the manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobRecord {
    pub index: usize,
    pub status: Status,
    /// Key path -> value, in the sweep file's order.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Bag path relative to the output folder (`jobs/I.mcap`), when ok.
    #[serde(default)]
    pub bag: Option<String>,
    #[serde(default)]
    pub size: Option<u64>,
    #[serde(default)]
    pub sha256: Option<String>,
    #[serde(default)]
    pub summary: Option<RunSummary>,
    #[serde(default)]
    pub error: Option<String>,
}

/// Where job `index`'s files are.
#[derive(Debug, Clone)]
pub struct JobFiles {
    pub index: usize,
    pub bag: PathBuf,
    pub part: PathBuf,
    pub record: PathBuf,
    /// `jobs/I.lock`: held while the job runs.
    pub lock: PathBuf,
    /// `jobs/I.mcap`, relative to the output folder.
    pub bag_rel: String,
}

impl JobFiles {
    pub fn new(out: &Path, index: usize) -> JobFiles {
        let stem = format!("{index:06}");
        let jobs = out.join("jobs");
        JobFiles {
            index,
            bag: jobs.join(format!("{stem}.mcap")),
            part: jobs.join(format!("{stem}.mcap.part")),
            record: jobs.join(format!("{stem}.json")),
            lock: jobs.join(format!("{stem}.lock")),
            bag_rel: format!("jobs/{stem}.mcap"),
        }
    }

    /// The job's record: `Ok(None)` when there is none, `Err(reason)` when one is there but
    /// cannot be used (not a regular file, too large, not a record).
    pub fn load_record(&self) -> Result<Option<JobRecord>, String> {
        if std::fs::symlink_metadata(&self.record).is_err() {
            return Ok(None);
        }
        let text = crate::input::read_text(&self.record, crate::input::InputKind::JobRecord)
            .map_err(|e| crate::input::error_line(&e))?;
        serde_json::from_str(&text)
            .map(Some)
            .map_err(|e| format!("{}: not a job record: {e}", self.record.display()))
    }

    /// The job's record, if it has a readable one.
    pub fn read_record(&self) -> Option<JobRecord> {
        self.load_record().ok().flatten()
    }

    /// Why an `ok` record of job `index` does not stand for its bag (checked against this
    /// job's own files: index, bag path, size, and with `verify` the SHA-256), or `None`.
    pub fn fault(&self, r: &JobRecord, index: usize, verify: bool) -> Option<String> {
        if r.index != index {
            return Some(format!(
                "its record claims job {} (the record of job {index} must say {index})",
                r.index
            ));
        }
        if r.bag.as_deref() != Some(self.bag_rel.as_str()) {
            return Some(format!(
                "its record names the bag {:?}; job {index}'s bag is {}",
                r.bag.as_deref().unwrap_or(""),
                self.bag_rel
            ));
        }
        let size = match std::fs::symlink_metadata(&self.bag) {
            Ok(m) if m.is_file() => m.len(),
            Ok(_) => return Some(format!("its bag {} is not a regular file", self.bag_rel)),
            Err(_) => return Some(format!("its bag {} is missing", self.bag_rel)),
        };
        if Some(size) != r.size {
            return Some(format!(
                "its bag {} has {size} bytes, the record says {:?}",
                self.bag_rel, r.size
            ));
        }
        if verify {
            match sha256_file(&self.bag) {
                Ok(sha) if Some(&sha) == r.sha256.as_ref() => {}
                Ok(sha) => {
                    return Some(format!(
                        "its bag {} has SHA-256 {sha}, the record says {}",
                        self.bag_rel,
                        r.sha256.as_deref().unwrap_or("none")
                    ))
                }
                Err(e) => return Some(format!("its bag {} cannot be read: {e}", self.bag_rel)),
            }
        }
        None
    }

    /// Done: an `ok` record of this job whose bag is present with the recorded size (and,
    /// with `verify`, the recorded SHA-256).
    pub fn done_checked(&self, index: usize, verify: bool) -> Option<JobRecord> {
        let r = self.read_record()?;
        (r.status == Status::Ok && self.fault(&r, index, verify).is_none()).then_some(r)
    }

    /// Done, by size (what a local run checks for every job before starting any).
    pub fn done(&self) -> Option<JobRecord> {
        self.done_checked(self.index, false)
    }

    /// Takes job `index`'s lock (`jobs/I.lock`, an advisory `flock` released when the returned
    /// file is dropped or the process ends), so the same job never runs twice at once (a
    /// requeued array task whose first attempt still runs).
    pub fn lock(&self, index: usize) -> Result<std::fs::File, SweepError> {
        use std::os::unix::fs::OpenOptionsExt;
        use std::os::unix::io::AsRawFd;
        let io = |source| SweepError::Io {
            path: self.lock.clone(),
            source,
        };
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW)
            .open(&self.lock)
            .map_err(io)?;
        if !f.metadata().map_err(io)?.is_file() {
            return Err(io(std::io::Error::other("not a regular file")));
        }
        if unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::WouldBlock {
                return Err(SweepError::Busy {
                    index,
                    lock: self.lock.clone(),
                });
            }
            return Err(io(e));
        }
        Ok(f)
    }
}

/// How jobs run.
#[derive(Debug, Clone, Default)]
pub struct JobOptions {
    /// Run even when the job is done.
    pub force: bool,
    /// Marker layout (default: jazzy).
    pub distro: Option<Distro>,
}

/// What running a job did.
#[derive(Debug, Clone, PartialEq)]
pub enum JobOutcome {
    /// Already done; the existing record.
    Skipped(JobRecord),
    Ran(JobRecord),
}

impl JobOutcome {
    pub fn record(&self) -> &JobRecord {
        match self {
            JobOutcome::Skipped(r) | JobOutcome::Ran(r) => r,
        }
    }
}

/// The params of a job as a JSON map.
pub fn params_json(job: &Job) -> serde_json::Map<String, serde_json::Value> {
    job.params
        .iter()
        .map(|(k, v)| {
            let j = serde_json::to_value(v).unwrap_or(serde_json::Value::String(inline(v)));
            (k.clone(), j)
        })
        .collect()
}

/// Writes `text` to `path` through [`crate::output`]: never onto an input, through a temporary
/// file and a rename, so readers see the old file or the whole new one.
pub fn write_atomic(path: &Path, text: &str) -> Result<(), SweepError> {
    Ok(crate::output::write(path, text.as_bytes(), &[])?)
}

/// SHA-256 of a regular file (a FIFO or device is refused without blocking), lowercase hex.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    use std::os::unix::fs::OpenOptionsExt;
    let mut f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)?;
    if !f.metadata()?.is_file() {
        return Err(std::io::Error::other("not a regular file"));
    }
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(h.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// Runs job `index` of `sweep` into `out` unless it is done. `stop` is polled every step
/// (a signal handler sets it); a stopped job removes its partial bag and records `failed`.
/// The returned record is on disk; a job that failed is `Ok(Ran(record))` with status
/// `failed`, and `Err` is kept for what prevents writing a record at all.
pub fn run_job(
    sweep: &Sweep,
    index: usize,
    out: &Path,
    opts: &JobOptions,
    stop: &AtomicBool,
) -> Result<JobOutcome, SweepError> {
    let job = sweep.job(index)?;
    let files = JobFiles::new(out, index);
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| SweepError::Io { path, source }
    };
    let jobs_dir = out.join("jobs");
    std::fs::create_dir_all(&jobs_dir).map_err(io(&jobs_dir))?;
    // Held until this function returns: another attempt at the same job fails here instead
    // of writing the same bag and record at the same time.
    let _lock = files.lock(index)?;
    // A rerun redoes a job whose bag no longer matches its record's SHA-256.
    if !opts.force {
        if let Some(r) = files.done_checked(index, true) {
            return Ok(JobOutcome::Skipped(r));
        }
    }
    // A stale record or partial bag from an earlier, killed attempt goes first.
    for stale in [&files.record, &files.part, &files.bag] {
        if stale.exists() {
            std::fs::remove_file(stale).map_err(io(stale))?;
        }
    }
    let spec = sweep.job_spec(&job)?;
    let mut record = JobRecord {
        index,
        status: Status::Failed,
        params: params_json(&job),
        bag: None,
        size: None,
        sha256: None,
        summary: None,
        error: None,
    };
    match record_job(&spec, &files.part, opts, stop) {
        Ok(summary) if summary.interrupted => {
            let _ = std::fs::remove_file(&files.part);
            record.error = Some("interrupted by a stop signal (partial bag removed)".into());
            record.summary = Some(summary);
        }
        Ok(summary) => {
            let sha = sha256_file(&files.part).map_err(io(&files.part))?;
            let size = std::fs::metadata(&files.part)
                .map_err(io(&files.part))?
                .len();
            std::fs::rename(&files.part, &files.bag).map_err(io(&files.bag))?;
            record.status = Status::Ok;
            record.bag = Some(files.bag_rel.clone());
            record.size = Some(size);
            record.sha256 = Some(sha);
            record.summary = Some(summary);
        }
        Err(e) => {
            let _ = std::fs::remove_file(&files.part);
            record.error = Some(format!("{e:#}"));
        }
    }
    let text = serde_json::to_string_pretty(&record).map_err(|source| SweepError::Encode {
        what: format!("the record of job {index}"),
        source,
    })?;
    write_atomic(&files.record, &(text + "\n"))?;
    Ok(JobOutcome::Ran(record))
}

/// Records one job's scene to `bag` as `drape record` would.
fn record_job(
    spec: &super::plan::JobSpec,
    bag: &Path,
    opts: &JobOptions,
    stop: &AtomicBool,
) -> anyhow::Result<RunSummary> {
    let scene = &spec.scene;
    let (mut sim, mut driver) = scene.build_with_robot()?;
    if let Some(joints) = &spec.joints {
        let d = driver
            .as_mut()
            .ok_or_else(|| anyhow::anyhow!("job.joints: the scene has no robot"))?;
        crate::ros::drive::drive_from_bag(d, joints)?;
    }
    let frame_id = driver
        .as_ref()
        .map_or_else(|| "world".to_string(), |d| d.root_link().to_string());
    let ropts = RecordOptions {
        duration: scene.duration,
        publish_rate: scene.publish_rate,
        distro: opts.distro.unwrap_or(Distro::Jazzy),
        frame_id,
        // The job stages its bag as `.part` itself (renamed when finished).
        in_place: true,
        ..RecordOptions::default()
    };
    let summary = record_with_robot(&mut sim, driver.as_mut(), bag, &ropts, stop, |_| {})?;
    Ok(summary.run_summary())
}
