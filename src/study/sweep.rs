//! The study's sweep: references first (in parallel, cached), then every planned run timed one
//! at a time and compared with its reference ([`measure`]), then the CSV, plots and summary.

use super::error::StudyError;
use super::plan::{Plan, PlannedRun};
use super::record::{RunRecord, StudyResult};
use super::reference::{self, Reference};
use super::run::{self, Horizon, RunOutput};
use super::scenes::StudyScene;
use super::{csv, plots, summary};
use crate::Vec3;
use std::path::Path;

/// Extra repetitions of a run whose timing is noisy because it is short.
const REPEATS: usize = 2;
/// Runs that took longer than this in total are not repeated (s).
const REPEAT_BUDGET_S: f64 = 0.5;

/// A reference's identity: scene, resolution, stiffness factor.
type RefKey = (StudyScene, usize, f64);

/// Runs the whole study and writes its outputs into `out`. `progress` gets one line per run.
pub fn run_study(
    plan: &Plan,
    out: &Path,
    mut progress: impl FnMut(&str),
) -> Result<StudyResult, StudyError> {
    std::fs::create_dir_all(out).map_err(|source| StudyError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let planned = plan.runs();
    // References first, in parallel (they are not timed); the timed runs then go one at a time.
    let mut keys: Vec<RefKey> = Vec::new();
    for p in &planned {
        let k = (p.settings.scene, p.settings.n, p.settings.stiffness);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    use rayon::prelude::*;
    let computed: Vec<Result<Reference, StudyError>> = keys
        .par_iter()
        .map(|&(scene, n, k)| {
            reference::reference(
                out,
                scene,
                n,
                k,
                &plan.horizon,
                plan.reference_level_for(n, k),
            )
        })
        .collect();
    let mut references: Vec<(RefKey, Reference)> = Vec::new();
    for (key, r) in keys.into_iter().zip(computed) {
        let r = r?;
        progress(&format!(
            "reference {} n={} stiffness x{}: RK4 dt=1/{} ({})",
            key.0.name(),
            key.1,
            key.2,
            60u64 << r.dt_level,
            if r.cached { "cached" } else { "computed" }
        ));
        references.push((key, r));
    }
    let mut records = Vec::with_capacity(planned.len());
    for (i, p) in planned.iter().enumerate() {
        let key = (p.settings.scene, p.settings.n, p.settings.stiffness);
        let Some((_, r)) = references.iter().find(|(k, _)| *k == key) else {
            unreachable!("every planned run's reference was computed above");
        };
        let mut o = run::run(&p.settings, &plan.horizon)?;
        // Short runs are repeated and the fastest kept, to damp the noise of a shared machine.
        let mut spent = o.wall;
        for _ in 0..REPEATS {
            if spent > REPEAT_BUDGET_S {
                break;
            }
            let again = run::run(&p.settings, &plan.horizon)?;
            spent += again.wall;
            o.wall = o.wall.min(again.wall);
            o.collision_wall = o.collision_wall.min(again.collision_wall);
        }
        let rec = measure(p, &o, r, &plan.horizon);
        progress(&format!(
            "[{}/{}] {} n={} stiffness x{} {} dt=1/{} tol={:e} cap={}: {}",
            i + 1,
            planned.len(),
            rec.settings.scene.name(),
            rec.settings.n,
            rec.settings.stiffness,
            rec.settings.integrator.name(),
            60u64 << rec.settings.dt_level,
            rec.settings.cg_tolerance,
            rec.settings.cg_max_iterations,
            if rec.diverged {
                format!("diverged at {:.3} s", rec.diverged_at.unwrap_or(0.0))
            } else {
                format!("rms {:.2e} m, {:.3} s/s", rec.rms_error, rec.wall_per_sim_s)
            }
        ));
        records.push(rec);
    }
    let mut result = StudyResult {
        plan: plan.clone(),
        runs: records,
        references: references
            .iter()
            .map(|((s, n, k), r)| {
                (
                    *s,
                    *n,
                    *k,
                    1.0 / (60.0 * f64::from(1u32 << r.dt_level)),
                    r.cached,
                )
            })
            .collect(),
        files: Vec::new(),
    };
    result.files.push(csv::write_csv(out, &result)?);
    result.files.extend(plots::write_all(out, &result)?);
    result.files.push(summary::write_summary(out, &result)?);
    Ok(result)
}

/// Compares a run with its reference.
fn measure(p: &PlannedRun, o: &RunOutput, r: &Reference, h: &Horizon) -> RunRecord {
    let diverged = o.diverged.is_some();
    let nan = f64::NAN;
    let (mut sum_sq, mut count, mut max) = (0.0, 0usize, 0.0f64);
    let mut final_rms = nan;
    for (xs, rs) in o.trajectory.positions.iter().zip(&r.trajectory.positions) {
        let mut s = 0.0;
        for (x, y) in xs.iter().zip(rs) {
            let d = (*x - *y).length_squared();
            s += d;
            max = max.max(d.sqrt());
        }
        sum_sq += s;
        count += xs.len();
        final_rms = (s / xs.len().max(1) as f64).sqrt();
    }
    let complete = !diverged && o.trajectory.positions.len() == h.sample_frames.len();
    let lowest = |xs: &[Vec3]| xs.iter().map(|x| x.z).fold(f64::INFINITY, f64::min);
    let (energy_drift, sag_error) =
        match (o.trajectory.positions.last(), r.trajectory.positions.last()) {
            (Some(x), Some(y)) if complete => {
                let g = 9.81;
                let scale = o.total_mass * g * p.settings.scene.length();
                let de = o.trajectory.energy.last().copied().unwrap_or(nan)
                    - r.trajectory.energy.last().copied().unwrap_or(nan);
                (de / scale, (lowest(x) - lowest(y)).abs())
            }
            _ => (nan, nan),
        };
    // A diverged run is charged for the step that failed too, so its rates stay defined.
    let attempted = o.steps + u64::from(diverged);
    let steps = attempted.max(1) as f64;
    let sim_time = steps * p.settings.dt();
    RunRecord {
        groups: p.groups.clone(),
        settings: p.settings.clone(),
        vertices: o.vertices,
        steps: o.steps,
        simulated: o.simulated,
        wall: o.wall,
        wall_per_sim_s: o.wall / sim_time,
        us_per_vertex_step: 1e6 * o.wall / (steps * o.vertices.max(1) as f64),
        realtime_factor: sim_time / o.wall.max(1e-9),
        cg_per_step: o.cg_iterations as f64 / steps,
        rms_error: if complete {
            (sum_sq / count.max(1) as f64).sqrt()
        } else {
            nan
        },
        max_error: if complete { max } else { nan },
        final_rms_error: if complete { final_rms } else { nan },
        energy_drift,
        sag_error,
        diverged,
        diverged_at: o.diverged_at,
        message: o.diverged.clone().unwrap_or_default(),
        collides: o.collides,
        deepest_penetration: o.deepest_penetration,
        self_intersections: o.self_intersections,
        collision_share: if o.wall > 0.0 {
            o.collision_wall / o.wall
        } else {
            0.0
        },
    }
}
