//! `summary.md`: the tables and conclusions computed from a study's runs.

use super::analysis::{
    cheapest_within, median, omega_max, orders, pareto, stability, theoretical_order,
};
use super::format::{collision_mode, dt_str, write};
use super::{RunRecord, StudyError, StudyResult};
use crate::collide::DetectionMode;
use crate::integrate::IntegratorKind;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn opt_dt(dt: Option<f64>) -> String {
    dt.map_or("-".into(), dt_str)
}

fn err_str(r: &RunRecord, v: f64) -> String {
    if r.diverged {
        format!("diverged at {:.3} s", r.diverged_at.unwrap_or(0.0))
    } else {
        format!("{v:.2e}")
    }
}

pub fn write_summary(out: &Path, r: &StudyResult) -> Result<PathBuf, StudyError> {
    let mut s = String::new();
    let runs = &r.runs;
    let n0 = r.plan.base_n;
    let diverged = runs.iter().filter(|x| x.diverged).count();
    let _ = writeln!(s, "# drape study: what accuracy costs in time\n");
    let _ = writeln!(
        s,
        "{} runs ({} diverged, reported not dropped), {:.2} s simulated each, errors sampled at t = {:?} s \
         against an RK4 reference at the same resolution. Cost is wall time inside `Simulation::step` \
         on one thread of the machine that ran the study.\n",
        runs.len(),
        diverged,
        r.plan.horizon.duration(),
        r.plan.horizon.sample_times()
    );
    let _ = writeln!(s, "References:\n");
    let _ = writeln!(s, "| scene | resolution | stiffness | reference | step |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (scene, n, k, dt, cached) in &r.references {
        let [a, b] = scene.resolution(*n);
        let _ = writeln!(
            s,
            "| {} | {a}x{b} | x{k} | RK4{} | {} |",
            scene.name(),
            if *cached { " (cached)" } else { "" },
            dt_str(*dt)
        );
    }

    // Convergence orders.
    let fits = orders(runs, &r.plan.scenes, n0, &r.plan.stiffnesses);
    let _ = writeln!(
        s,
        "\n## Measured convergence order (RMS error vs dt, {n0}-vertex side)\n"
    );
    let _ = writeln!(
        s,
        "| scene | stiffness | integrator | measured order | theory | matches | fitted on dt | points |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for f in &fits {
        let _ = writeln!(
            s,
            "| {} | x{} | {} | {:.2} | {} | {} | {} .. {} | {} |",
            f.scene.name(),
            f.stiffness,
            f.integrator.name(),
            f.order,
            theoretical_order(f.integrator),
            if (f.order - theoretical_order(f.integrator)).abs()
                <= 0.2 * theoretical_order(f.integrator)
            {
                "yes"
            } else {
                "no"
            },
            dt_str(f.dt_range.1),
            dt_str(f.dt_range.0),
            f.points
        );
    }
    let _ = writeln!(
        s,
        "\nThe fit uses the smallest steps (up to four) whose error is above {:.0e} m, the reference's own \
         accuracy; points where a smaller step did not reduce the error are outside the asymptotic range. \
         `matches` is within 20% of theory. Where it is not, the run is not asymptotic: on the flag, flutter \
         amplifies small differences so first-order errors only start to fall at the theoretical rate below the \
         smallest step tried, and on the sphere, contact makes the motion non-smooth, which caps every method's \
         order near 1 or below.",
        super::analysis::ERROR_FLOOR
    );

    // Stability.
    let _ = writeln!(s, "\n## Stability: largest step that ran to the end\n");
    let _ = writeln!(s, "| scene | resolution | stiffness | integrator | largest stable dt | smallest diverged dt | omega_max (rad/s) | dt*omega at largest stable |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let mut omegas: Vec<((super::StudyScene, usize, f64), Option<f64>)> = Vec::new();
    for st in stability(runs) {
        let key = (st.scene, st.n, st.stiffness);
        let w = match omegas.iter().find(|(k, _)| *k == key) {
            Some((_, w)) => *w,
            None => {
                let w = omega_max(st.scene, st.n, st.stiffness);
                omegas.push((key, w));
                w
            }
        };
        let [a, b] = st.scene.resolution(st.n);
        let _ = writeln!(
            s,
            "| {} | {a}x{b} | x{} | {} | {} | {} | {} | {} |",
            st.scene.name(),
            st.stiffness,
            st.integrator.name(),
            opt_dt(st.largest_stable),
            opt_dt(st.smallest_unstable),
            w.map_or("-".into(), |w| format!("{w:.0}")),
            match (w, st.largest_stable) {
                (Some(w), Some(dt)) => format!("{:.2}", w * dt),
                _ => "-".into(),
            }
        );
    }
    let _ = writeln!(s, "\nSteps were tried at 1/60 s x 2^-k only, so each limit lies between the two columns. \
        `omega_max` is the stiffness bound of the scene's springs (`EffectSet::stiffness`); the stiffest \
        mode scales with the number of vertices along a side.");

    // Implicit vs explicit cost.
    let _ = writeln!(s, "\n## Implicit against explicit ({n0}-vertex side)\n");
    let _ = writeln!(s, "| scene | implicit us/vertex-step | symplectic us/vertex-step | rk4 us/vertex-step | implicit cost per step / symplectic | largest stable dt implicit / symplectic |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    let stab = stability(runs);
    for &scene in &r.plan.scenes {
        let per = |k: IntegratorKind| {
            median(
                runs.iter()
                    .filter(|x| {
                        x.settings.scene == scene
                            && x.settings.n == n0
                            && x.settings.stiffness == 1.0
                            && x.settings.integrator == k
                            && x.groups.contains(&"dt")
                            && !x.diverged
                    })
                    .map(|x| x.us_per_vertex_step)
                    .collect(),
            )
        };
        let (im, se, rk) = (
            per(IntegratorKind::Implicit),
            per(IntegratorKind::SymplecticEuler),
            per(IntegratorKind::Rk4),
        );
        let lim = |k| {
            stab.iter()
                .find(|t| t.scene == scene && t.n == n0 && t.stiffness == 1.0 && t.integrator == k)
        };
        let ratio = match (
            lim(IntegratorKind::Implicit),
            lim(IntegratorKind::SymplecticEuler),
        ) {
            (Some(i), Some(e)) => match (i.largest_stable, e.largest_stable) {
                (Some(a), Some(b)) => format!(
                    "{}{:.0}",
                    if i.smallest_unstable.is_none() {
                        ">= "
                    } else {
                        ""
                    },
                    a / b
                ),
                _ => "-".into(),
            },
            _ => "-".into(),
        };
        let f = |x: Option<f64>| x.map_or("-".into(), |v| format!("{v:.3}"));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            scene.name(),
            f(im),
            f(se),
            f(rk),
            match (im, se) {
                (Some(a), Some(b)) => format!("{:.1}x", a / b),
                _ => "-".into(),
            },
            ratio
        );
    }
    let _ = writeln!(s, "\nCosts are medians over the stable runs of the step sweep (one implicit step includes assembling the Jacobians and the CG solve at tolerance {:.0e}). \
        `>=` means implicit never diverged, so its limit is above the largest step tried.", super::plan::TIGHT_CG.0);

    // CG sweep.
    let _ = writeln!(
        s,
        "\n## Implicit solver tolerance and iteration cap (dt = {})\n",
        dt_str(1.0 / (60.0 * f64::from(1u32 << r.plan.cg_dt_level)))
    );
    let _ = writeln!(
        s,
        "| scene | cg tolerance | cap | CG iterations/step | wall s per sim s | RMS error (m) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for &scene in &r.plan.scenes {
        let mut cg: Vec<&RunRecord> = runs
            .iter()
            .filter(|x| x.settings.scene == scene && x.groups.contains(&"cg"))
            .collect();
        cg.sort_by(|a, b| {
            (b.settings.cg_tolerance, a.settings.cg_max_iterations)
                .partial_cmp(&(a.settings.cg_tolerance, b.settings.cg_max_iterations))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        for x in &cg {
            let _ = writeln!(
                s,
                "| {} | {:.0e} | {} | {:.1} | {:.3} | {} |",
                scene.name(),
                x.settings.cg_tolerance,
                x.settings.cg_max_iterations,
                x.cg_per_step,
                x.cost(),
                err_str(x, x.rms_error)
            );
        }
    }

    // Resolution.
    let _ = writeln!(s, "\n## Resolution: cheapest stable run per integrator\n");
    let _ = writeln!(s, "| scene | resolution | vertices | integrator | dt | wall s per sim s | us/vertex-step | real time? | RMS error (m) |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for &scene in &r.plan.scenes {
        for &n in &r.plan.resolutions {
            for k in IntegratorKind::ALL {
                let tried = runs.iter().any(|x| {
                    x.settings.scene == scene
                        && x.settings.n == n
                        && x.settings.integrator == k
                        && x.groups.contains(&"resolution")
                });
                if !tried {
                    continue;
                }
                let best = runs
                    .iter()
                    .filter(|x| {
                        x.settings.scene == scene
                            && x.settings.n == n
                            && x.settings.integrator == k
                            && x.groups.contains(&"resolution")
                            && !x.diverged
                    })
                    .min_by(|a, b| a.cost().total_cmp(&b.cost()));
                let [a, b] = scene.resolution(n);
                match best {
                    Some(x) => {
                        let _ = writeln!(
                            s,
                            "| {} | {a}x{b} | {} | {} | {} | {:.3} | {:.3} | {} | {:.2e} |",
                            scene.name(),
                            x.vertices,
                            k.name(),
                            dt_str(x.settings.dt()),
                            x.cost(),
                            x.us_per_vertex_step,
                            if x.realtime_factor >= 1.0 {
                                "yes"
                            } else {
                                "no"
                            },
                            x.rms_error
                        );
                    }
                    None => {
                        let _ = writeln!(
                            s,
                            "| {} | {a}x{b} | - | {} | all diverged | - | - | - | - |",
                            scene.name(),
                            k.name()
                        );
                    }
                }
            }
        }
    }

    // Collision modes.
    let coll: Vec<&RunRecord> = runs
        .iter()
        .filter(|x| x.groups.contains(&"collision"))
        .collect();
    if !coll.is_empty() {
        let _ = writeln!(
            s,
            "\n## Collision detection mode and self-collision ({n0}-vertex side)\n"
        );
        let _ = writeln!(s, "| scene | mode | self-collision | integrator | dt | wall s per sim s | collision share of step | RMS error (m) | deepest penetration (m) | self-intersecting pairs |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for x in &coll {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {:.3} | {:.0}% | {} | {:.2e} | {} |",
                x.settings.scene.name(),
                collision_mode(x),
                x.settings.collision.is_some_and(|c| c.1),
                x.settings.integrator.name(),
                dt_str(x.settings.dt()),
                x.cost(),
                100.0 * x.collision_share,
                err_str(x, x.rms_error),
                x.deepest_penetration,
                x.self_intersections
            );
        }
        let ratio = |a: DetectionMode, b: DetectionMode, self_c: bool| {
            median(
                coll.iter()
                    .filter(|x| !x.diverged && x.settings.collision == Some((a, self_c)))
                    .filter_map(|x| {
                        coll.iter()
                            .find(|y| {
                                !y.diverged
                                    && y.settings.scene == x.settings.scene
                                    && y.settings.integrator == x.settings.integrator
                                    && y.settings.dt_level == x.settings.dt_level
                                    && y.settings.collision == Some((b, self_c))
                            })
                            .map(|y| x.cost() / y.cost())
                    })
                    .collect(),
            )
        };
        let _ = writeln!(s);
        for self_c in [false, true] {
            if let Some(q) = ratio(DetectionMode::Continuous, DetectionMode::Proximity, self_c) {
                let _ = writeln!(s, "- Self-collision {}: `continuous` costs {q:.2}x `proximity` per simulated second (median over matching integrator and step).", if self_c { "on" } else { "off" });
            }
            if let Some(q) = ratio(DetectionMode::Proximity, DetectionMode::Spheres, self_c) {
                let _ = writeln!(
                    s,
                    "- Self-collision {}: `proximity` costs {q:.2}x `spheres`.",
                    if self_c { "on" } else { "off" }
                );
            }
        }
        for m in [
            DetectionMode::Spheres,
            DetectionMode::Proximity,
            DetectionMode::Continuous,
        ] {
            if let Some(q) = median(
                coll.iter()
                    .filter(|x| !x.diverged && x.settings.collision == Some((m, false)))
                    .filter_map(|x| {
                        coll.iter()
                            .find(|y| {
                                !y.diverged
                                    && y.settings.scene == x.settings.scene
                                    && y.settings.integrator == x.settings.integrator
                                    && y.settings.dt_level == x.settings.dt_level
                                    && y.settings.collision == Some((m, true))
                            })
                            .map(|y| y.cost() / x.cost())
                    })
                    .collect(),
            ) {
                let _ = writeln!(
                    s,
                    "- Turning self-collision on with `{}` costs {q:.2}x.",
                    format!("{m:?}").to_lowercase()
                );
            }
        }
        let worst = |self_c: Option<bool>| {
            coll.iter()
                .filter(|x| {
                    !x.diverged
                        && self_c.is_none_or(|c| x.settings.collision.is_some_and(|k| k.1 == c))
                })
                .map(|x| x.self_intersections)
                .max()
        };
        if let (Some(off), Some(on)) = (worst(Some(false)), worst(Some(true))) {
            let _ = writeln!(s, "- Most self-intersecting triangle pairs at a sample time: {off} with self-collision off, {on} with it on.");
        }
    }

    // Cheapest for an accuracy target.
    let _ = writeln!(
        s,
        "\n## Cheapest setting for an accuracy target ({n0}-vertex side)\n"
    );
    let _ = writeln!(s, "| scene | RMS error at most | integrator | dt | cg tolerance | wall s per sim s | real-time factor |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for &scene in &r.plan.scenes {
        for tol in [1e-2, 1e-3, 1e-4, 1e-6] {
            match cheapest_within(runs, scene, n0, None, tol) {
                Some(x) => {
                    let _ = writeln!(
                        s,
                        "| {} | {tol:.0e} m | {} | {} | {} | {:.3} | {:.1} |",
                        scene.name(),
                        x.settings.integrator.name(),
                        dt_str(x.settings.dt()),
                        if x.settings.integrator == IntegratorKind::Implicit {
                            format!("{:.0e}", x.settings.cg_tolerance)
                        } else {
                            "-".into()
                        },
                        x.cost(),
                        x.realtime_factor
                    );
                }
                None => {
                    let _ = writeln!(
                        s,
                        "| {} | {tol:.0e} m | none reached it | - | - | - | - |",
                        scene.name()
                    );
                }
            }
        }
    }

    // Conclusions.
    let _ = writeln!(s, "\n## Conclusions (computed from the runs above)\n");
    for &scene in &r.plan.scenes {
        let base: Vec<&RunRecord> = runs
            .iter()
            .filter(|x| {
                x.settings.scene == scene && x.settings.n == n0 && x.settings.stiffness == 1.0
            })
            .collect();
        let front = pareto(&base);
        let _ = writeln!(s, "**{}**", scene.name());
        for st in stab
            .iter()
            .filter(|t| t.scene == scene && t.n == n0 && t.integrator != IntegratorKind::Implicit)
        {
            let _ = writeln!(
                s,
                "- stiffness x{}: {} {}.",
                st.stiffness,
                st.integrator.name(),
                match (st.largest_stable, st.smallest_unstable) {
                    (Some(a), Some(b)) => format!(
                        "is stable up to dt = {} and diverges at {}",
                        dt_str(a),
                        dt_str(b)
                    ),
                    (Some(a), None) =>
                        format!("is stable at every step tried (up to {})", dt_str(a)),
                    (None, Some(b)) =>
                        format!("diverged at every step tried (down to {})", dt_str(b)),
                    (None, None) => "was not run".into(),
                }
            );
        }
        if let (Some(first), Some(last)) = (front.first(), front.last()) {
            let (a, b) = (base[*first], base[*last]);
            let _ = writeln!(s, "- The Pareto front runs from {} at dt {} ({:.3} s/s, RMS {:.1e} m) to {} at dt {} ({:.3} s/s, RMS {:.1e} m).", a.settings.integrator.name(), dt_str(a.settings.dt()), a.cost(), a.rms_error, b.settings.integrator.name(), dt_str(b.settings.dt()), b.cost(), b.rms_error);
            // Where the error stops improving: the first front point from which four times the
            // cost buys less than half the error.
            let stall = front.iter().enumerate().find_map(|(k, &i)| {
                let p = base[i];
                front[k + 1..]
                    .iter()
                    .map(|&j| base[j])
                    .find(|q| q.cost() >= 4.0 * p.cost())
                    .filter(|q| q.rms_error > 0.5 * p.rms_error)
                    .map(|q| (p, q))
            });
            match stall {
                Some((p, q)) => {
                    let _ = writeln!(s, "- Error stops paying off after {} at dt {} ({:.3} s/s, RMS {:.1e} m): the cheapest run costing 4x more ({} at dt {}, {:.1}x the cost) lowers the error only {:.2}x.", p.settings.integrator.name(), dt_str(p.settings.dt()), p.cost(), p.rms_error, q.settings.integrator.name(), dt_str(q.settings.dt()), q.cost() / p.cost(), p.rms_error / q.rms_error);
                }
                None => {
                    let _ = writeln!(s, "- Along the whole front, four times the cost buys at least 2x lower error: no plateau down to the reference's own accuracy.");
                }
            }
        }
        let cg: Vec<&&RunRecord> = base
            .iter()
            .filter(|x| {
                x.groups.contains(&"cg")
                    && !x.diverged
                    && x.settings.cg_max_iterations
                        == r.plan.cg_caps.iter().copied().max().unwrap_or(0)
            })
            .collect();
        if let Some(tight) = cg
            .iter()
            .min_by(|a, b| a.settings.cg_tolerance.total_cmp(&b.settings.cg_tolerance))
        {
            if let Some(loose) = cg
                .iter()
                .filter(|x| x.rms_error <= 1.05 * tight.rms_error)
                .max_by(|a, b| a.settings.cg_tolerance.total_cmp(&b.settings.cg_tolerance))
            {
                let _ = writeln!(s, "- CG tolerance below {:.0e} does not improve the implicit error at dt {} (within 5% of {:.0e}'s {:.2e} m) and costs {:.1}x less than {:.0e}.", loose.settings.cg_tolerance, dt_str(loose.settings.dt()), tight.settings.cg_tolerance, tight.rms_error, tight.cost() / loose.cost(), tight.settings.cg_tolerance);
            }
        }
        let _ = writeln!(s);
    }

    // Full step sweep.
    let _ = writeln!(s, "## Step sweep ({n0}-vertex side, every run)\n");
    let _ = writeln!(s, "| scene | stiffness | integrator | dt | wall s per sim s | real-time factor | RMS error (m) | max error (m) | energy drift | sag error (m) |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for x in runs.iter().filter(|x| x.groups.contains(&"dt")) {
        let _ = writeln!(
            s,
            "| {} | x{} | {} | {} | {:.3} | {:.1} | {} | {} | {} | {} |",
            x.settings.scene.name(),
            x.settings.stiffness,
            x.settings.integrator.name(),
            dt_str(x.settings.dt()),
            x.cost(),
            x.realtime_factor,
            err_str(x, x.rms_error),
            err_str(x, x.max_error),
            err_str(x, x.energy_drift),
            err_str(x, x.sag_error)
        );
    }
    let _ = writeln!(
        s,
        "\nEnergy drift is (E_run - E_ref) at the end over total mass x g x cloth length."
    );
    write(out.join("summary.md"), &s)
}
