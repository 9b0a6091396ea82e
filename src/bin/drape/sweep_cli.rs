//! `drape sweep`: the sweep subcommands' arguments and how each calls the library's `sweep`
//! module (plan, run one job or all locally, collect, emit for Slurm or Kubernetes).

use anyhow::{Context, Result};
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Subcommand)]
pub(crate) enum SweepCommand {
    /// Check a sweep file and print its job count and the first jobs' values.
    Plan {
        /// Sweep file (YAML).
        file: PathBuf,
        /// Jobs to show.
        #[arg(long, default_value_t = 10)]
        show: usize,
    },
    /// Run one job (`--index`, else $SLURM_ARRAY_TASK_ID or $JOB_COMPLETION_INDEX) or, with
    /// `--local`, every job not yet done.
    Run {
        /// Sweep file (YAML).
        file: PathBuf,
        /// Job to run (default: $SLURM_ARRAY_TASK_ID, else $JOB_COMPLETION_INDEX).
        #[arg(long)]
        index: Option<usize>,
        /// Run every job on this machine.
        #[arg(long)]
        local: bool,
        /// Jobs at once with --local.
        #[arg(short = 'j', long = "jobs", default_value_t = 1)]
        jobs: usize,
        /// Output folder (default: the sweep file's `out`, else <sweep>.out beside it).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Rerun jobs that are done.
        #[arg(long)]
        force: bool,
        /// Marker layout: humble or jazzy (default jazzy, whatever $ROS_DISTRO says, so that a
        /// job's bag does not depend on the machine).
        #[arg(long)]
        distro: Option<String>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Merge the job records of an output folder into manifest.jsonl and manifest.csv.
    Collect {
        /// Output folder of a sweep (with its jobs' records).
        dir: PathBuf,
        /// Also hash every finished bag and compare it with its record's SHA-256.
        #[arg(long)]
        verify: bool,
    },
    /// Write the files that run a sweep on a cluster scheduler.
    Emit {
        #[command(subcommand)]
        target: EmitTarget,
    },
}

#[derive(Subcommand)]
pub(crate) enum EmitTarget {
    /// An `sbatch` array script: one task per job.
    Slurm {
        /// Sweep file (YAML).
        file: PathBuf,
        /// Script to write (default: stdout).
        #[arg(long)]
        script: Option<PathBuf>,
        /// Output folder as the compute nodes see it (default: the sweep's, made absolute).
        #[arg(long)]
        out: Option<PathBuf>,
        /// The drape executable as the compute nodes see it (default: this one).
        #[arg(long)]
        drape: Option<PathBuf>,
        /// CPUs per task (`#SBATCH --cpus-per-task`).
        #[arg(long, default_value_t = 1)]
        cpus_per_task: u32,
        /// Time limit per task, e.g. 00:30:00.
        #[arg(long)]
        time: Option<String>,
        /// Slurm partition (`#SBATCH --partition`).
        #[arg(long)]
        partition: Option<String>,
        /// Most tasks at once.
        #[arg(long)]
        max_parallel: Option<usize>,
        /// Extra `#SBATCH` option, repeatable (e.g. --sbatch=--mem=2G).
        #[arg(long = "sbatch", allow_hyphen_values = true)]
        sbatch: Vec<String>,
    },
    /// A Kubernetes Indexed Job manifest: one completion per job.
    K8s {
        /// Sweep file (YAML).
        file: PathBuf,
        /// Manifest to write (default: stdout).
        #[arg(long)]
        manifest: Option<PathBuf>,
        /// Container image with the drape executable.
        #[arg(long, default_value = "drape:latest")]
        image: String,
        /// PersistentVolumeClaim with the sweep file, its scenes and the output.
        #[arg(long, default_value = "drape-data")]
        pvc: String,
        /// Where the PersistentVolumeClaim is mounted in the container.
        #[arg(long, default_value = "/data")]
        mount: String,
        /// The sweep file inside the container (default: <mount>/<file name>).
        #[arg(long)]
        sweep_path: Option<String>,
        /// Output folder inside the container (default: <mount>/<name>.out).
        #[arg(long)]
        out: Option<String>,
        /// Pods at once.
        #[arg(long, default_value_t = 10)]
        parallelism: usize,
        /// Retries of failed pods before the Job fails.
        #[arg(long, default_value_t = 6)]
        backoff_limit: u32,
        /// CPU request per pod.
        #[arg(long, default_value = "1")]
        cpu: String,
        /// Memory request and limit per pod.
        #[arg(long, default_value = "2Gi")]
        memory: String,
    },
}

pub(crate) fn sweep(command: SweepCommand) -> Result<()> {
    use drape::sweep::{self, Sweep};
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let stop_flag = || -> Result<Arc<AtomicBool>> {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
            .context("cannot install the Ctrl-C handler")?;
        Ok(stop)
    };
    match command {
        SweepCommand::Plan { file, show } => {
            let s = Sweep::load(&file)?;
            print!("{}", sweep::plan_text(&s, show));
        }
        SweepCommand::Run {
            file,
            index,
            local,
            jobs,
            out,
            force,
            distro,
            quiet,
        } => {
            // One job checks its own scene; --local checks every job before starting any.
            let s = if local {
                Sweep::load(&file)?
            } else {
                Sweep::open(&file)?
            };
            let out = out.unwrap_or_else(|| s.out_dir.clone());
            let index = match (local, index) {
                (false, None) => Some(index_from_env()?),
                _ => index,
            };
            if let Some(i) = index {
                s.job(i)?;
            }
            sweep::write_plan(&s, &out)?;
            let distro = distro
                .map(|d| d.parse::<drape::ros::Distro>())
                .transpose()
                .context("--distro")?;
            let stop = stop_flag()?;
            if local {
                if index.is_some() {
                    anyhow::bail!("--local runs every job: leave out --index");
                }
                let mut extra = Vec::new();
                if let Some(d) = distro {
                    extra.extend(["--distro".to_string(), d.to_string()]);
                }
                if force {
                    anyhow::bail!("--force with --local: remove the output folder instead");
                }
                let opts = sweep::PoolOptions {
                    exe: std::env::current_exe().context("cannot find the drape executable")?,
                    jobs,
                    extra_args: extra,
                    log_dir: None,
                };
                let bar = if quiet {
                    indicatif::ProgressBar::hidden()
                } else {
                    indicatif::ProgressBar::new(s.job_count() as u64)
                };
                bar.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{elapsed_precise} [{bar:40}] {pos}/{len} jobs {msg} (eta {eta})",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                let r = sweep::run_local(&s, &out, &opts, &stop, &mut |done, _, failed| {
                    bar.set_position(done as u64);
                    if failed > 0 {
                        bar.set_message(format!("{failed} failed"));
                    }
                })?;
                bar.finish_and_clear();
                let m = sweep::collect(&out)?;
                println!(
                    "{}: {} jobs, {} ran, {} already done, {} failed{}; manifest {}",
                    file.display(),
                    r.total,
                    r.succeeded,
                    r.skipped,
                    r.failed.len(),
                    if r.interrupted { " (interrupted)" } else { "" },
                    m.jsonl.display()
                );
                if !r.failed.is_empty() || r.interrupted {
                    anyhow::bail!(
                        "{} jobs did not finish (see {}/logs); rerun to complete them",
                        r.total - r.succeeded - r.skipped,
                        out.display()
                    );
                }
            } else {
                let index = index.unwrap_or_default();
                let opts = sweep::JobOptions { force, distro };
                let o = sweep::run_job(&s, index, &out, &opts, &stop)?;
                let r = o.record();
                match (&o, r.status) {
                    (sweep::JobOutcome::Skipped(_), _) => {
                        println!(
                            "job {index}: already done ({})",
                            r.bag.as_deref().unwrap_or("")
                        )
                    }
                    (_, sweep::Status::Ok) => {
                        println!("job {index}: {}", r.bag.as_deref().unwrap_or(""));
                        if let Some(sum) = &r.summary {
                            print!("{}", sum.table());
                        }
                    }
                    _ => anyhow::bail!(
                        "job {index} failed: {}",
                        r.error.as_deref().unwrap_or("unknown error")
                    ),
                }
            }
        }
        SweepCommand::Collect { dir, verify } => {
            let m = sweep::collect_with(&dir, verify)?;
            println!(
                "{}: {} jobs, {} ok, {} failed, {} missing; wrote {} and {}",
                dir.display(),
                m.entries.len(),
                m.count(sweep::Status::Ok),
                m.count(sweep::Status::Failed),
                m.count(sweep::Status::Missing),
                m.jsonl.display(),
                m.csv.display()
            );
        }
        SweepCommand::Emit { target } => emit(target)?,
    }
    Ok(())
}

/// The job index of an array task: Slurm's or Kubernetes'.
fn index_from_env() -> Result<usize> {
    for var in ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"] {
        if let Ok(v) = std::env::var(var) {
            return v
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("${var} is not a job index: {v:?}"));
        }
    }
    anyhow::bail!(
        "no job index: pass --index I (or run as a Slurm array task or an Indexed Job pod)"
    )
}

fn emit(target: EmitTarget) -> Result<()> {
    use drape::sweep::{emit, write_plan, Sweep};
    let write = |path: Option<PathBuf>, text: String| -> Result<()> {
        match path {
            Some(p) => {
                drape::output::write(&p, text.as_bytes(), &[])?;
                println!("wrote {}", p.display());
            }
            None => print!("{text}"),
        }
        Ok(())
    };
    match target {
        EmitTarget::Slurm {
            file,
            script,
            out,
            drape,
            cpus_per_task,
            time,
            partition,
            max_parallel,
            sbatch,
        } => {
            let s = Sweep::load(&file)?;
            // The script is checked as an output before the plan is written beside the jobs.
            if let Some(p) = &script {
                drape::output::check(p, &[])?;
            }
            let abs = |p: &std::path::Path| -> Result<PathBuf> {
                std::path::absolute(p).with_context(|| format!("cannot resolve {}", p.display()))
            };
            let out = abs(&out.unwrap_or_else(|| s.out_dir.clone()))?;
            let opts = emit::SlurmOptions {
                drape: match drape {
                    Some(d) => d,
                    None => std::env::current_exe().context("cannot find the drape executable")?,
                },
                out: out.clone(),
                cpus_per_task,
                time,
                partition,
                max_parallel,
                extra: sbatch,
            };
            // Every value is checked for the script before anything is written.
            let text = emit::slurm_script(&s, &abs(&file)?, &opts)?;
            write_plan(&s, &out)?;
            std::fs::create_dir_all(out.join("logs"))
                .with_context(|| format!("cannot create {}/logs", out.display()))?;
            write(script, text)?;
        }
        EmitTarget::K8s {
            file,
            manifest,
            image,
            pvc,
            mount,
            sweep_path,
            out,
            parallelism,
            backoff_limit,
            cpu,
            memory,
        } => {
            let s = Sweep::load(&file)?;
            let name = file
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or("sweep.yaml")
                .to_string();
            let opts = emit::K8sOptions {
                image,
                pvc,
                mount,
                sweep_path,
                out,
                parallelism,
                backoff_limit,
                cpu,
                memory,
            };
            write(manifest, emit::k8s_job(&s, &name, &opts)?)?;
        }
    }
    Ok(())
}
