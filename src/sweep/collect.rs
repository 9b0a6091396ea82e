//! `drape sweep collect DIR`: one manifest of a sweep's jobs from their result records, as JSON
//! lines (`manifest.jsonl`) and CSV (`manifest.csv`), both readable by pandas.
//!
//! The output folder's `plan.json` (written by every `sweep run` and `sweep emit`) says which
//! jobs exist, so jobs that never ran appear too: `missing`, or `failed` with the reason when a
//! partial bag or a failed record is there. The plan must list each job once, in order; an `ok`
//! record is `failed` when it claims another job's index, names a bag other than its job's own
//! `jobs/I.mcap`, or its bag is gone or has another size (or, with `--verify`, another
//! SHA-256); an unreadable record is `failed` with the reason. Every `failed` entry says why.

use super::error::SweepError;
use super::job::{params_json, JobFiles, JobRecord, Status};
use super::plan::{Job, Sweep};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `plan.json`: the jobs of a sweep, for collecting without the sweep file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanFile {
    pub name: String,
    pub sweep: PathBuf,
    pub scene: PathBuf,
    pub job_count: usize,
    pub jobs: Vec<Job>,
}

/// Writes `plan.json` into `out` (through [`crate::output`]; concurrent writers write the same
/// text). The jobs are computed and written one at a time, so the plan is never held whole in
/// memory, and the file is refused once it passes the sweep plan's size cap.
pub fn write_plan(sweep: &Sweep, out: &Path) -> Result<PathBuf, SweepError> {
    use std::io::Write;
    std::fs::create_dir_all(out).map_err(|source| SweepError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let path = out.join("plan.json");
    let also = [sweep.path.as_path(), sweep.scene_path.as_path()];
    let mut file = crate::output::Output::create(&path, &also)?;
    let cap = crate::input::InputKind::SweepPlan.cap();
    let encode = |what: &str, source| SweepError::Encode {
        what: what.to_string(),
        source,
    };
    let io = |source| SweepError::Io {
        path: path.clone(),
        source,
    };
    let head = serde_json::json!({
        "name": sweep.name,
        "sweep": sweep.path,
        "scene": sweep.scene_path,
        "job_count": sweep.job_count(),
    });
    // The fields in `PlanFile`'s order, then the jobs.
    let mut text = String::from("{");
    for key in ["name", "sweep", "scene", "job_count"] {
        let v = serde_json::to_string(&head[key]).map_err(|e| encode("the plan", e))?;
        text.push_str(&format!("\"{key}\":{v},"));
    }
    text.push_str("\"jobs\":[");
    file.write_all(text.as_bytes()).map_err(io)?;
    let mut written = text.len() as u64;
    for (k, job) in sweep.jobs().enumerate() {
        let mut line = if k == 0 { String::new() } else { ",".into() };
        line.push_str(
            &serde_json::to_string(&job)
                .map_err(|e| encode(&format!("job {} of the plan", job.index), e))?,
        );
        written += line.len() as u64;
        if written > cap {
            return Err(SweepError::PlanTooLarge { path, cap });
        }
        file.write_all(line.as_bytes()).map_err(io)?;
    }
    file.write_all(b"]}\n").map_err(io)?;
    file.finish()?;
    Ok(path)
}

/// A collected manifest.
#[derive(Debug, Clone, PartialEq)]
pub struct Manifest {
    pub entries: Vec<JobRecord>,
    pub jsonl: PathBuf,
    pub csv: PathBuf,
}

impl Manifest {
    pub fn count(&self, status: Status) -> usize {
        self.entries.iter().filter(|e| e.status == status).count()
    }
}

/// Merges the job records of `out` into `manifest.jsonl` and `manifest.csv` there.
pub fn collect(out: &Path) -> Result<Manifest, SweepError> {
    collect_with(out, false)
}

/// [`collect`]; with `verify`, each `ok` job's bag is also hashed and compared with the
/// SHA-256 its record holds.
pub fn collect_with(out: &Path, verify: bool) -> Result<Manifest, SweepError> {
    let plan_path = out.join("plan.json");
    let text = crate::input::read_text(&plan_path, crate::input::InputKind::SweepPlan)?;
    let plan: PlanFile = serde_json::from_str(&text).map_err(|source| SweepError::Json {
        origin: plan_path.display().to_string(),
        source,
    })?;
    let bad_plan = |why: String| SweepError::BadPlan {
        path: plan_path.clone(),
        why,
    };
    if plan.jobs.len() != plan.job_count {
        return Err(bad_plan(format!(
            "job_count is {} but {} jobs are listed",
            plan.job_count,
            plan.jobs.len()
        )));
    }
    if let Some((pos, job)) = plan.jobs.iter().enumerate().find(|(k, j)| j.index != *k) {
        return Err(bad_plan(format!(
            "entry {pos} of jobs is job {} (each job is listed once, in order)",
            job.index
        )));
    }
    let mut entries = Vec::with_capacity(plan.jobs.len());
    for job in &plan.jobs {
        entries.push(entry(out, job, verify));
    }
    let jsonl = out.join("manifest.jsonl");
    let mut lines = String::new();
    for e in &entries {
        let line = serde_json::to_string(e).map_err(|source| SweepError::Encode {
            what: format!("the manifest line of job {}", e.index),
            source,
        })?;
        lines.push_str(&line);
        lines.push('\n');
    }
    // The sweep file and its scene are inputs of the sweep even when this command does not
    // read them: the manifests never replace them.
    let also = [plan.sweep.as_path(), plan.scene.as_path()];
    crate::output::write(&jsonl, lines.as_bytes(), &also)?;
    let csv = out.join("manifest.csv");
    crate::output::write(&csv, to_csv(&entries).as_bytes(), &also)?;
    Ok(Manifest {
        entries,
        jsonl,
        csv,
    })
}

fn entry(out: &Path, job: &Job, verify: bool) -> JobRecord {
    let files = JobFiles::new(out, job.index);
    let blank = |status, error: Option<String>| JobRecord {
        index: job.index,
        status,
        params: params_json(job),
        bag: None,
        size: None,
        sha256: None,
        summary: None,
        error,
    };
    match files.load_record() {
        Ok(Some(mut r)) if r.status == Status::Ok => {
            if let Some(why) = files.fault(&r, job.index, verify) {
                // The entry is the plan's job, whatever the record claims.
                r = JobRecord {
                    summary: r.summary,
                    ..blank(Status::Failed, Some(why))
                };
            }
            r
        }
        Ok(Some(r)) if r.index != job.index => blank(
            Status::Failed,
            Some(format!(
                "its record claims job {} (the record of job {} must say {})",
                r.index, job.index, job.index
            )),
        ),
        Ok(Some(mut r)) => {
            if r.error.as_deref().is_none_or(str::is_empty) {
                r.error = Some("failed (the record gives no reason)".into());
            }
            r
        }
        Err(why) => blank(Status::Failed, Some(format!("unreadable record: {why}"))),
        Ok(None) if files.part.exists() => blank(
            Status::Failed,
            Some(format!(
                "no result record; a partial bag {}.part is left (killed mid-run, or still running)",
                files.bag_rel
            )),
        ),
        Ok(None) => blank(Status::Missing, None),
    }
}

/// CSV with one row per job: index, status, bag, size, sha256, error, one column per sweep key
/// (`param.<key>`) and one per summary field (`summary.<field>`). Lists are written as JSON.
fn to_csv(entries: &[JobRecord]) -> String {
    let mut param_keys: Vec<String> = Vec::new();
    for e in entries {
        for k in e.params.keys() {
            if !param_keys.contains(k) {
                param_keys.push(k.clone());
            }
        }
    }
    let summary_keys: Vec<String> =
        match serde_json::to_value(crate::ros::telemetry::RunSummary::default()) {
            Ok(serde_json::Value::Object(m)) => m.keys().cloned().collect(),
            _ => Vec::new(),
        };
    let mut header: Vec<String> = ["index", "status", "bag", "size", "sha256", "error"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(param_keys.iter().map(|k| format!("param.{k}")));
    header.extend(summary_keys.iter().map(|k| format!("summary.{k}")));
    let mut out = header
        .iter()
        .map(|h| field(h))
        .collect::<Vec<_>>()
        .join(",");
    out.push('\n');
    for e in entries {
        let mut row = vec![
            e.index.to_string(),
            serde_json::to_value(e.status)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default(),
            e.bag.clone().unwrap_or_default(),
            e.size.map(|s| s.to_string()).unwrap_or_default(),
            e.sha256.clone().unwrap_or_default(),
            e.error.clone().unwrap_or_default(),
        ];
        for k in &param_keys {
            row.push(e.params.get(k).map(scalar).unwrap_or_default());
        }
        let summary = e
            .summary
            .as_ref()
            .and_then(|s| serde_json::to_value(s).ok());
        for k in &summary_keys {
            row.push(
                summary
                    .as_ref()
                    .and_then(|s| s.get(k))
                    .map(scalar)
                    .unwrap_or_default(),
            );
        }
        out.push_str(&row.iter().map(|f| field(f)).collect::<Vec<_>>().join(","));
        out.push('\n');
    }
    out
}

fn scalar(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Null => String::new(),
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// RFC 4180 quoting where needed.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
