//! SVG plots: error versus cost with the Pareto front, cost versus resolution, error versus step.

use super::analysis::{dt_curve, orders, pareto};
use super::{RunRecord, StudyError, StudyResult, StudyScene};
use crate::integrate::IntegratorKind;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

const COLORS: [RGBColor; 4] = [
    RGBColor(214, 39, 40),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(31, 119, 180),
];

fn color(k: IntegratorKind) -> RGBColor {
    COLORS[k as usize]
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> StudyError {
    StudyError::Plot {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

/// Log-axis bounds padded by a factor of 1.5, or `None` with no finite positive value.
fn bounds(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(l, h), x| (l.min(x), h.max(x)));
    (hi > 0.0).then_some((lo / 1.5, hi * 1.5))
}

pub fn write_all(out: &Path, r: &StudyResult) -> Result<Vec<PathBuf>, StudyError> {
    let mut files = Vec::new();
    for &scene in &r.plan.scenes {
        let runs: Vec<&RunRecord> = r
            .runs
            .iter()
            .filter(|x| x.settings.scene == scene && x.settings.stiffness == 1.0)
            .collect();
        let p = out.join(format!("error_vs_cost_{}.svg", scene.name()));
        error_vs_cost(&p, scene, r.plan.base_n, &runs)?;
        files.push(p);
        for &k in &r.plan.stiffnesses {
            let p = out.join(format!("error_vs_dt_{}_k{k}.svg", scene.name()));
            error_vs_dt(&p, scene, k, r)?;
            files.push(p);
        }
        let p = out.join(format!("cost_vs_resolution_{}.svg", scene.name()));
        cost_vs_resolution(&p, scene, &runs)?;
        files.push(p);
    }
    Ok(files)
}

fn error_vs_cost(
    path: &Path,
    scene: StudyScene,
    n: usize,
    runs: &[&RunRecord],
) -> Result<(), StudyError> {
    let base: Vec<&RunRecord> = runs.iter().copied().filter(|r| r.settings.n == n).collect();
    let ok = |r: &&&RunRecord| !r.diverged && r.rms_error > 0.0 && r.cost() > 0.0;
    let xb = bounds(base.iter().filter(ok).map(|r| r.cost())).unwrap_or((1e-3, 1.0));
    let yb = bounds(base.iter().filter(ok).map(|r| r.rms_error)).unwrap_or((1e-6, 1.0));
    let root = SVGBackend::new(path, (800, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let diverged = base.iter().filter(|r| r.diverged).count();
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}, {} vertices: RMS error vs cost ({} diverged runs not shown)",
                scene.name(),
                base.first().map_or(0, |r| r.vertices),
                diverged
            ),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d((xb.0..xb.1).log_scale(), (yb.0..yb.1).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("wall seconds per simulated second")
        .y_desc("RMS position error (m)")
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for k in IntegratorKind::ALL {
        let pts: Vec<(f64, f64)> = base
            .iter()
            .filter(|r| r.settings.integrator == k)
            .filter(ok)
            .map(|r| (r.cost(), r.rms_error))
            .collect();
        let c = color(k);
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
            .map_err(|e| plot_err(path, e))?
            .label(k.name())
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, c.filled()));
    }
    let front: Vec<(f64, f64)> = pareto(&base)
        .into_iter()
        .map(|i| (base[i].cost(), base[i].rms_error))
        .collect();
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(2)))
        .map_err(|e| plot_err(path, e))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    chart
        .draw_series(
            front
                .iter()
                .map(|&p| Circle::new(p, 7, BLACK.stroke_width(1))),
        )
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

fn error_vs_dt(
    path: &Path,
    scene: StudyScene,
    stiffness: f64,
    r: &StudyResult,
) -> Result<(), StudyError> {
    let n = r.plan.base_n;
    let curves: Vec<(IntegratorKind, Vec<(f64, f64)>)> = IntegratorKind::ALL
        .iter()
        .map(|&k| (k, dt_curve(&r.runs, scene, n, stiffness, k)))
        .collect();
    let fits = orders(&r.runs, &[scene], n, &[stiffness]);
    let xb = bounds(curves.iter().flat_map(|c| c.1.iter().map(|p| p.0))).unwrap_or((1e-4, 0.1));
    let yb = bounds(curves.iter().flat_map(|c| c.1.iter().map(|p| p.1))).unwrap_or((1e-9, 1.0));
    let root = SVGBackend::new(path, (800, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}, stiffness x{stiffness}: RMS error vs time step (measured order p)",
                scene.name()
            ),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d((xb.0..xb.1).log_scale(), (yb.0..yb.1).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("time step dt (s)")
        .y_desc("RMS position error (m)")
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (k, pts) in &curves {
        let c = color(*k);
        let label = match fits.iter().find(|f| f.integrator == *k) {
            Some(f) => format!(
                "{} (p = {:.2}, theory {})",
                k.name(),
                f.order,
                super::analysis::theoretical_order(*k)
            ),
            None => format!("{} (no fit)", k.name()),
        };
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(|e| plot_err(path, e))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
            .map_err(|e| plot_err(path, e))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

/// Per integrator and resolution, the cheapest run that stayed stable.
fn cost_vs_resolution(
    path: &Path,
    scene: StudyScene,
    runs: &[&RunRecord],
) -> Result<(), StudyError> {
    let res: Vec<&RunRecord> = runs
        .iter()
        .copied()
        .filter(|r| r.groups.contains(&"resolution"))
        .collect();
    let mut curves = Vec::new();
    for k in IntegratorKind::ALL {
        let mut ns: Vec<usize> = res
            .iter()
            .filter(|r| r.settings.integrator == k)
            .map(|r| r.vertices)
            .collect();
        ns.sort_unstable();
        ns.dedup();
        let pts: Vec<(f64, f64)> = ns
            .iter()
            .filter_map(|&v| {
                res.iter()
                    .filter(|r| r.settings.integrator == k && r.vertices == v && !r.diverged)
                    .map(|r| r.cost())
                    .min_by(f64::total_cmp)
                    .map(|c| (v as f64, c))
            })
            .collect();
        curves.push((k, pts));
    }
    let xb = bounds(res.iter().map(|r| r.vertices as f64)).unwrap_or((100.0, 10000.0));
    let yb = bounds(curves.iter().flat_map(|c| c.1.iter().map(|p| p.1))).unwrap_or((1e-3, 10.0));
    let yb = (yb.0.min(0.5), yb.1.max(2.0));
    let root = SVGBackend::new(path, (800, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: cost of the cheapest stable run vs resolution",
                scene.name()
            ),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d((xb.0..xb.1).log_scale(), (yb.0..yb.1).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("vertices")
        .y_desc("wall seconds per simulated second")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (k, pts) in &curves {
        let c = color(*k);
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(|e| plot_err(path, e))?
            .label(k.name())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
            .map_err(|e| plot_err(path, e))?;
    }
    chart
        .draw_series(LineSeries::new(
            vec![(xb.0, 1.0), (xb.1, 1.0)],
            BLACK.mix(0.5).stroke_width(1),
        ))
        .map_err(|e| plot_err(path, e))?
        .label("real time")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.mix(0.5)));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}
