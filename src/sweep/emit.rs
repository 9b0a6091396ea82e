//! `drape sweep emit slurm|k8s`: the files that run a sweep on the scheduler a cluster already
//! has. Each array task (Slurm) or indexed pod (Kubernetes) runs `drape sweep run FILE --index I`
//! for its own index; see [`super::job`] for why reruns and requeues are safe.
//!
//! Text that reaches these files is checked for where it goes ([`EmitError`] names the option):
//! the sweep's `name` is letters, digits, spaces, `-`, `_` and `.` (checked when the sweep is
//! read);
//! paths and values on `#SBATCH` lines (which `sbatch` reads without shell quoting) are limited
//! to characters that need no quoting there (no whitespace, quotes, `%` patterns or control
//! characters); the paths on the command line are single-quoted; and no value may hold a
//! control character (a newline would end a comment or a `#SBATCH` line). The Kubernetes Job
//! is serialised by serde, which quotes every string, so it is always one YAML document.

use super::plan::Sweep;
use std::path::{Path, PathBuf};

/// A value that cannot be written into a scheduler file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{key}: {value:?} {why}")]
pub struct EmitError {
    /// The option or key the value came from (`--out`, `--partition`, `--sbatch`).
    pub key: String,
    pub value: String,
    pub why: &'static str,
}

fn no_control(key: &str, value: &str) -> Result<(), EmitError> {
    if value.chars().any(char::is_control) {
        return Err(EmitError {
            key: key.to_string(),
            value: value.to_string(),
            why: "holds a control character (newline, tab, ...)",
        });
    }
    Ok(())
}

/// A value for a `#SBATCH` line: no control characters, whitespace, quotes, `%` (a Slurm
/// file-name pattern), `#`, `$`, backticks, backslashes or shell operators.
fn sbatch_safe(key: &str, value: &str) -> Result<(), EmitError> {
    no_control(key, value)?;
    let bad = |c: char| {
        c.is_whitespace()
            || matches!(
                c,
                '\'' | '"'
                    | '`'
                    | '$'
                    | '\\'
                    | '%'
                    | '#'
                    | ';'
                    | '&'
                    | '|'
                    | '<'
                    | '>'
                    | '('
                    | ')'
                    | '*'
                    | '?'
                    | '['
                    | ']'
                    | '{'
                    | '}'
                    | '!'
            )
    };
    if value.chars().any(bad) {
        return Err(EmitError {
            key: key.to_string(),
            value: value.to_string(),
            why: "holds a character an #SBATCH line cannot carry (whitespace, quotes, %, #, $, or a shell operator)",
        });
    }
    Ok(())
}

fn path_str<'a>(key: &str, p: &'a Path) -> Result<&'a str, EmitError> {
    p.to_str().ok_or_else(|| EmitError {
        key: key.to_string(),
        value: p.display().to_string(),
        why: "is not UTF-8",
    })
}

/// Settings of the `sbatch` array script.
#[derive(Debug, Clone)]
pub struct SlurmOptions {
    /// The `drape` executable as the compute nodes see it.
    pub drape: PathBuf,
    /// Output folder as the compute nodes see it (shared file system).
    pub out: PathBuf,
    pub cpus_per_task: u32,
    /// `--time` (e.g. `00:30:00`).
    pub time: Option<String>,
    pub partition: Option<String>,
    /// Most tasks running at once (`--array=0-N%max`).
    pub max_parallel: Option<usize>,
    /// More `#SBATCH` lines, e.g. `--mem=2G`.
    pub extra: Vec<String>,
}

fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// The `sbatch` script: one array task per job, `SLURM_ARRAY_TASK_ID` as the job index,
/// `--requeue` (a task whose node fails or is preempted runs again and redoes only its own job),
/// and a log per task in `<out>/logs/slurm-<array job>_<task>.out` (the folder must exist before
/// `sbatch`; [`super::write_plan`] and `drape sweep emit slurm` create it).
pub fn slurm_script(
    sweep: &Sweep,
    sweep_path: &Path,
    o: &SlurmOptions,
) -> Result<String, EmitError> {
    let n = sweep.job_count();
    no_control("name", &sweep.name)?;
    // `--out`, or the sweep's `out` made absolute.
    let out = path_str("out", &o.out)?;
    sbatch_safe("out", out)?;
    no_control("--drape", path_str("--drape", &o.drape)?)?;
    no_control("the sweep file's path", path_str("sweep file", sweep_path)?)?;
    if let Some(t) = &o.time {
        sbatch_safe("--time", t)?;
    }
    if let Some(p) = &o.partition {
        sbatch_safe("--partition", p)?;
    }
    for e in &o.extra {
        sbatch_safe("--sbatch", e)?;
    }
    let name: String = sweep
        .name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let logs = o.out.join("logs");
    let mut s = String::new();
    s.push_str("#!/bin/bash\n");
    s.push_str(&format!(
        "# drape sweep `{}`: {n} jobs as a Slurm array (written by `drape sweep emit slurm`).\n\
         # Submit: sbatch THIS_FILE; afterwards: drape sweep collect {}\n",
        sweep.name,
        o.out.display()
    ));
    s.push_str(&format!("#SBATCH --job-name=drape-{name}\n"));
    let throttle = o.max_parallel.map(|m| format!("%{m}")).unwrap_or_default();
    s.push_str(&format!(
        "#SBATCH --array=0-{}{throttle}\n",
        n.saturating_sub(1)
    ));
    s.push_str(&format!(
        "#SBATCH --output={}/slurm-%A_%a.out\n",
        logs.display()
    ));
    s.push_str("#SBATCH --open-mode=append\n");
    s.push_str("#SBATCH --requeue\n");
    s.push_str("#SBATCH --ntasks=1\n");
    s.push_str(&format!(
        "#SBATCH --cpus-per-task={}\n",
        o.cpus_per_task.max(1)
    ));
    if let Some(t) = &o.time {
        s.push_str(&format!("#SBATCH --time={t}\n"));
    }
    if let Some(p) = &o.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    for e in &o.extra {
        s.push_str(&format!("#SBATCH {e}\n"));
    }
    s.push_str("set -euo pipefail\n");
    s.push_str("export RAYON_NUM_THREADS=\"${SLURM_CPUS_PER_TASK:-1}\"\n");
    s.push_str(&format!(
        "exec {} sweep run {} --out {} --index \"$SLURM_ARRAY_TASK_ID\" --quiet\n",
        quote(&o.drape.display().to_string()),
        quote(&sweep_path.display().to_string()),
        quote(&o.out.display().to_string()),
    ));
    Ok(s)
}

/// Settings of the Kubernetes Indexed Job.
#[derive(Debug, Clone)]
pub struct K8sOptions {
    pub image: String,
    /// PersistentVolumeClaim holding the sweep file, its scenes and the output.
    pub pvc: String,
    /// Where the claim is mounted.
    pub mount: String,
    /// The sweep file inside the container (default `<mount>/<file name>`).
    pub sweep_path: Option<String>,
    /// Output folder inside the container (default `<mount>/<sweep name>.out`).
    pub out: Option<String>,
    /// Pods at once.
    pub parallelism: usize,
    /// Failed pods retried before the Job fails.
    pub backoff_limit: u32,
    pub cpu: String,
    pub memory: String,
}

/// A DNS-1123 name from `s` (lowercase alphanumerics and `-`, at most 63 characters).
fn dns_name(s: &str) -> String {
    let mut n: String = s
        .to_ascii_lowercase()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    n.truncate(52);
    let n = n.trim_matches('-');
    if n.is_empty() {
        "sweep".to_string()
    } else {
        n.to_string()
    }
}

/// A `batch/v1` Job with `completionMode: Indexed`: one completion per sweep job; each pod runs
/// `drape sweep run --index $(JOB_COMPLETION_INDEX)` (the index the Job controller gives it).
pub fn k8s_job(sweep: &Sweep, sweep_file_name: &str, o: &K8sOptions) -> Result<String, EmitError> {
    let n = sweep.job_count();
    no_control("name", &sweep.name)?;
    no_control("the sweep file's name", sweep_file_name)?;
    for (key, v) in [
        ("--image", Some(&o.image)),
        ("--pvc", Some(&o.pvc)),
        ("--mount", Some(&o.mount)),
        ("--sweep-path", o.sweep_path.as_ref()),
        ("--out", o.out.as_ref()),
        ("--cpu", Some(&o.cpu)),
        ("--memory", Some(&o.memory)),
    ] {
        if let Some(v) = v {
            no_control(key, v)?;
        }
    }
    let mount = o.mount.trim_end_matches('/');
    let sweep_path = o
        .sweep_path
        .clone()
        .unwrap_or_else(|| format!("{mount}/{sweep_file_name}"));
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| format!("{mount}/{}.out", dns_name(&sweep.name)));
    let job = serde_json::json!({
        "apiVersion": "batch/v1",
        "kind": "Job",
        "metadata": {
            "name": format!("drape-{}", dns_name(&sweep.name)),
            "labels": { "app.kubernetes.io/name": "drape", "drape/sweep": dns_name(&sweep.name) },
        },
        "spec": {
            "completionMode": "Indexed",
            "completions": n,
            "parallelism": o.parallelism.clamp(1, n.max(1)),
            "backoffLimit": o.backoff_limit,
            "template": {
                "metadata": { "labels": { "app.kubernetes.io/name": "drape" } },
                "spec": {
                    "restartPolicy": "Never",
                    "containers": [{
                        "name": "drape",
                        "image": o.image,
                        "command": ["drape"],
                        "args": ["sweep", "run", sweep_path, "--out", out,
                                 "--index", "$(JOB_COMPLETION_INDEX)", "--quiet"],
                        "env": [{ "name": "RAYON_NUM_THREADS", "value": "1" }],
                        "resources": {
                            "requests": { "cpu": o.cpu, "memory": o.memory },
                            "limits": { "memory": o.memory },
                        },
                        "volumeMounts": [{ "name": "data", "mountPath": mount }],
                    }],
                    "volumes": [{
                        "name": "data",
                        "persistentVolumeClaim": { "claimName": o.pvc },
                    }],
                },
            },
        },
    });
    let header = format!(
        "# drape sweep `{}`: {n} jobs as a Kubernetes Indexed Job (written by `drape sweep emit k8s`).\n\
         # kubectl apply -f THIS_FILE; afterwards, on the volume: drape sweep collect {out}\n",
        sweep.name
    );
    let body = serde_yaml_ng::to_string(&job).map_err(|_| EmitError {
        key: "the Job".into(),
        value: String::new(),
        why: "cannot be written as YAML",
    })?;
    Ok(header + &body)
}
