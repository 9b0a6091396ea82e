//! Sweeps: many varied recordings of one base scene, for datasets.
//!
//! A sweep file ([`plan`]) names a base scene and how to vary it; [`Sweep::load`] checks it
//! whole before any job runs. [`run_job`] runs one job (what a Slurm array task or a Kubernetes
//! indexed pod runs), [`run_local`] runs all of them on this machine with a bounded pool,
//! [`collect`] merges the result records into a manifest, and [`emit`] writes the `sbatch`
//! script and the Kubernetes Indexed Job.
//!
//! A job's bag depends only on the sweep file, the scene and the job index: not on the machine,
//! the thread count (`RAYON_NUM_THREADS`) or the other jobs (`tests/sweep.rs` checks 1 and 2
//! threads give the same bytes). Step wall time is therefore kept out of sweep bags.

pub mod collect;
pub mod draw;
pub mod emit;
pub use emit::EmitError;
mod error;
pub mod job;
pub mod keypath;
mod limits;
pub mod plan;
pub mod pool;
mod rng;

pub use collect::{collect, collect_with, write_plan, Manifest, PlanFile};
pub use draw::{Draw, DrawError, RangeError, Target, TargetError};
pub use error::{ApplyError, JobSceneError, KeyError, SweepError};
pub use job::{run_job, JobFiles, JobOptions, JobOutcome, JobRecord, Status};
pub use keypath::{KeyPath, KeyPathError, SetError};
pub use plan::{Job, JobSpec, Sweep, SweepFile};
pub use pool::{run_local, PoolOptions, PoolReport};

/// What `drape sweep plan` prints: the job count and the first `show` jobs' values.
pub fn plan_text(sweep: &Sweep, show: usize) -> String {
    let n = sweep.job_count();
    let mut s = format!(
        "{}: {n} job{} of {} (output {})\n",
        sweep.path.display(),
        if n == 1 { "" } else { "s" },
        sweep.scene_path.display(),
        sweep.out_dir.display()
    );
    for job in sweep.jobs().take(show) {
        s.push_str(&format!("  {:>6}  {}\n", job.index, job.describe()));
    }
    if n > show {
        s.push_str(&format!("  ... {} more\n", n - show));
    }
    s
}
