//! Numbers derived from the runs: convergence orders, Pareto fronts, stability limits and the
//! cost ratios the summary's conclusions quote.

use super::{RunRecord, StudyScene};
use crate::integrate::IntegratorKind;

/// Errors below this (0.1 nm) are treated as at the reference's own error floor and not used
/// for order fits: the reference (RK4, 8x smaller step) is itself only that accurate.
pub const ERROR_FLOOR: f64 = 1e-10;

/// Theoretical global order of each integrator's position error.
pub fn theoretical_order(k: IntegratorKind) -> f64 {
    match k {
        IntegratorKind::Rk4 => 4.0,
        _ => 1.0,
    }
}

/// A measured convergence order.
#[derive(Debug, Clone)]
pub struct OrderFit {
    pub scene: StudyScene,
    pub stiffness: f64,
    pub integrator: IntegratorKind,
    /// Slope of log(RMS error) against log(dt).
    pub order: f64,
    /// Step range of the fit (s).
    pub dt_range: (f64, f64),
    pub points: usize,
}

/// Stable (dt, rms error) points of one integrator's step sweep, largest step first.
pub fn dt_curve(
    runs: &[RunRecord],
    scene: StudyScene,
    n: usize,
    stiffness: f64,
    k: IntegratorKind,
) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| {
            r.groups.contains(&"dt")
                && r.settings.scene == scene
                && r.settings.n == n
                && r.settings.stiffness == stiffness
                && r.settings.integrator == k
                && !r.diverged
        })
        .map(|r| (r.settings.dt(), r.rms_error))
        .collect();
    pts.sort_by(|a, b| b.0.total_cmp(&a.0));
    pts
}

/// Least-squares slope on the asymptotic range: the smallest steps (up to four) whose error is
/// above [`ERROR_FLOOR`], stopping at the first step that does not improve on its neighbour.
pub fn fit_order(curve: &[(f64, f64)]) -> Option<(f64, (f64, f64), usize)> {
    let usable: Vec<(f64, f64)> = curve
        .iter()
        .copied()
        .filter(|&(_, e)| e.is_finite() && e > ERROR_FLOOR)
        .collect();
    // From the smallest step upwards while the error keeps growing with the step.
    let mut range: Vec<(f64, f64)> = Vec::new();
    for &p in usable.iter().rev() {
        if let Some(&(_, prev)) = range.last() {
            if p.1 <= prev {
                break;
            }
        }
        range.push(p);
        if range.len() == 4 {
            break;
        }
    }
    if range.len() < 2 {
        return None;
    }
    let n = range.len() as f64;
    let xs: Vec<f64> = range.iter().map(|p| p.0.ln()).collect();
    let ys: Vec<f64> = range.iter().map(|p| p.1.ln()).collect();
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    let lo = range.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = range.iter().map(|p| p.0).fold(0.0, f64::max);
    Some((sxy / sxx, (lo, hi), range.len()))
}

pub fn orders(
    runs: &[RunRecord],
    scenes: &[StudyScene],
    n: usize,
    stiffnesses: &[f64],
) -> Vec<OrderFit> {
    let mut out = Vec::new();
    for &scene in scenes {
        for &stiffness in stiffnesses {
            for k in IntegratorKind::ALL {
                let Some((order, dt_range, points)) =
                    fit_order(&dt_curve(runs, scene, n, stiffness, k))
                else {
                    continue;
                };
                out.push(OrderFit {
                    scene,
                    stiffness,
                    integrator: k,
                    order,
                    dt_range,
                    points,
                });
            }
        }
    }
    out
}

/// Indices of the runs on the error-versus-cost Pareto front (no run is both cheaper and more
/// accurate), cheapest first.
pub fn pareto(runs: &[&RunRecord]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..runs.len())
        .filter(|&i| {
            !runs[i].diverged && runs[i].rms_error.is_finite() && runs[i].cost().is_finite()
        })
        .collect();
    idx.sort_by(|&a, &b| runs[a].cost().total_cmp(&runs[b].cost()));
    let mut best = f64::INFINITY;
    idx.into_iter()
        .filter(|&i| {
            let keep = runs[i].rms_error < best;
            if keep {
                best = runs[i].rms_error;
            }
            keep
        })
        .collect()
}

/// Stability boundary of one integrator at one resolution: the largest step that ran to the end
/// and the smallest that diverged (either may be missing).
#[derive(Debug, Clone)]
pub struct Stability {
    pub scene: StudyScene,
    pub n: usize,
    pub stiffness: f64,
    pub integrator: IntegratorKind,
    pub largest_stable: Option<f64>,
    pub smallest_unstable: Option<f64>,
}

pub fn stability(runs: &[RunRecord]) -> Vec<Stability> {
    let mut keys: Vec<(StudyScene, usize, f64, IntegratorKind)> = Vec::new();
    for r in runs {
        let k = (
            r.settings.scene,
            r.settings.n,
            r.settings.stiffness,
            r.settings.integrator,
        );
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.sort_by(|a, b| {
        (a.0, a.1, b.2.to_bits(), a.3 as u8).cmp(&(b.0, b.1, a.2.to_bits(), b.3 as u8))
    });
    keys.into_iter()
        .map(|(scene, n, stiffness, integrator)| {
            let same = runs.iter().filter(|r| {
                r.settings.scene == scene
                    && r.settings.n == n
                    && r.settings.stiffness == stiffness
                    && r.settings.integrator == integrator
            });
            let mut st = Stability {
                scene,
                n,
                stiffness,
                integrator,
                largest_stable: None,
                smallest_unstable: None,
            };
            for r in same {
                let dt = r.settings.dt();
                if r.diverged {
                    st.smallest_unstable =
                        Some(st.smallest_unstable.map_or(dt, |u: f64| u.min(dt)));
                } else {
                    st.largest_stable = Some(st.largest_stable.map_or(dt, |u: f64| u.max(dt)));
                }
            }
            st
        })
        .collect()
}

/// Largest `omega = sqrt(lambda_max(M^-1 K))` bound of the scene's elastic effects (rad/s).
pub fn omega_max(scene: StudyScene, n: usize, stiffness: f64) -> Option<f64> {
    let sim = scene.scene(n, stiffness).ok()?.build().ok()?;
    sim.effects()
        .stiffness(&sim.cloth.mass)
        .iter()
        .map(|b| b.omega_sq)
        .fold(None, |a: Option<f64>, w| Some(a.map_or(w, |a| a.max(w))))
        .map(f64::sqrt)
}

/// Median of finite values.
pub fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    })
}

/// The cheapest stable run of `k` in `scene` at resolution `n` whose RMS error is at most `tol`.
pub fn cheapest_within(
    runs: &[RunRecord],
    scene: StudyScene,
    n: usize,
    k: Option<IntegratorKind>,
    tol: f64,
) -> Option<&RunRecord> {
    runs.iter()
        .filter(|r| {
            r.settings.scene == scene
                && r.settings.n == n
                && r.settings.stiffness == 1.0
                && k.is_none_or(|k| r.settings.integrator == k)
                && !r.diverged
                && r.rms_error <= tol
        })
        .min_by(|a, b| a.cost().total_cmp(&b.cost()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_slope_and_skips_floor_and_preasymptotic_points() {
        // error = 3 dt^2 on the small steps, a saturated point at the largest step, one at the floor.
        let mut c: Vec<(f64, f64)> = (0..3)
            .map(|k| {
                let dt = 0.1 / f64::from(1 << k);
                (dt, 3.0 * dt * dt)
            })
            .collect();
        c.insert(0, (0.2, 0.01)); // below the 0.12 a pure power law would give: not asymptotic
        c.push((1e-6, 1e-12));
        let (p, (lo, hi), n) = fit_order(&c).expect("fit");
        assert!((p - 2.0).abs() < 1e-9, "order {p}");
        assert_eq!(n, 3);
        assert!((lo - 0.025).abs() < 1e-15 && (hi - 0.1).abs() < 1e-15);
    }

    #[test]
    fn fit_needs_two_points() {
        assert!(fit_order(&[(0.1, 1.0)]).is_none());
        assert!(fit_order(&[(0.1, 1e-12), (0.05, 1e-13)]).is_none());
    }
}
