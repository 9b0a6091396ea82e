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

/// Log-axis bounds padded by a factor of 1.5, or `None` with no finite positive value.
fn bounds(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(l, h), x| (l.min(x), h.max(x)));
    (hi > 0.0).then_some((lo / 1.5, hi * 1.5))
}

/// One curve or point set of a log-log chart.
struct Series {
    label: String,
    color: RGBColor,
    points: Vec<(f64, f64)>,
    /// Join the points with a line.
    line: bool,
    /// Marker radius; markers are filled unless `hollow`.
    marker: Option<u32>,
    hollow: bool,
}

impl Series {
    /// Filled markers joined by a line, as for one integrator's curve.
    fn curve(label: String, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label,
            color,
            points,
            line: true,
            marker: Some(4),
            hollow: false,
        }
    }
}

/// What a log-log chart shows besides its series.
struct Axes<'a> {
    caption: String,
    x_desc: &'a str,
    y_desc: &'a str,
    /// Format of the x tick labels ("{:.0e}" for decades, "{:.0}" for counts).
    x_decimal: bool,
    x: (f64, f64),
    y: (f64, f64),
    legend: SeriesLabelPosition,
}

/// Draws one SVG log-log chart: every plot of the study is one of these.
fn draw_loglog(path: &Path, axes: Axes, series: &[Series]) -> Result<(), StudyError> {
    let err = |source| StudyError::Plot {
        path: path.to_path_buf(),
        source,
    };
    let root = SVGBackend::new(path, (800, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&axes.caption, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (axes.x.0..axes.x.1).log_scale(),
            (axes.y.0..axes.y.1).log_scale(),
        )
        .map_err(err)?;
    let x_fmt = |x: &f64| {
        if axes.x_decimal {
            format!("{x:.0}")
        } else {
            format!("{x:.0e}")
        }
    };
    chart
        .configure_mesh()
        .x_desc(axes.x_desc)
        .y_desc(axes.y_desc)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()
        .map_err(err)?;
    for s in series {
        let c = s.color;
        let (line, marker) = (s.line, s.marker);
        let style = if s.hollow {
            c.stroke_width(1)
        } else {
            c.filled()
        };
        let r = marker.unwrap_or(4);
        let circles = s.points.iter().map(|&p| Circle::new(p, r, style));
        if line {
            chart
                .draw_series(LineSeries::new(s.points.clone(), c.stroke_width(2)))
                .map_err(err)?
                .label(s.label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                });
            if marker.is_some() {
                chart.draw_series(circles).map_err(err)?;
            }
        } else {
            chart
                .draw_series(circles)
                .map_err(err)?
                .label(s.label.as_str())
                .legend(move |(x, y)| Circle::new((x + 8, y), r, style));
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(axes.legend)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
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
    let diverged = base.iter().filter(|r| r.diverged).count();
    let mut series: Vec<Series> = IntegratorKind::ALL
        .iter()
        .map(|&k| Series {
            label: k.name().into(),
            color: color(k),
            points: base
                .iter()
                .filter(|r| r.settings.integrator == k)
                .filter(ok)
                .map(|r| (r.cost(), r.rms_error))
                .collect(),
            line: false,
            marker: Some(4),
            hollow: false,
        })
        .collect();
    let front: Vec<(f64, f64)> = pareto(&base)
        .into_iter()
        .map(|i| (base[i].cost(), base[i].rms_error))
        .collect();
    series.push(Series {
        marker: Some(7),
        hollow: true,
        ..Series::curve("Pareto front".into(), BLACK, front)
    });
    let axes = Axes {
        caption: format!(
            "{}, {} vertices: RMS error vs cost ({} diverged runs not shown)",
            scene.name(),
            base.first().map_or(0, |r| r.vertices),
            diverged
        ),
        x_desc: "wall seconds per simulated second",
        y_desc: "RMS position error (m)",
        x_decimal: false,
        x: bounds(base.iter().filter(ok).map(|r| r.cost())).unwrap_or((1e-3, 1.0)),
        y: bounds(base.iter().filter(ok).map(|r| r.rms_error)).unwrap_or((1e-6, 1.0)),
        legend: SeriesLabelPosition::UpperRight,
    };
    draw_loglog(path, axes, &series)
}

fn error_vs_dt(
    path: &Path,
    scene: StudyScene,
    stiffness: f64,
    r: &StudyResult,
) -> Result<(), StudyError> {
    let n = r.plan.base_n;
    let fits = orders(&r.runs, &[scene], n, &[stiffness]);
    let series: Vec<Series> = IntegratorKind::ALL
        .iter()
        .map(|&k| {
            let label = match fits.iter().find(|f| f.integrator == k) {
                Some(f) => format!(
                    "{} (p = {:.2}, theory {})",
                    k.name(),
                    f.order,
                    super::analysis::theoretical_order(k)
                ),
                None => format!("{} (no fit)", k.name()),
            };
            Series::curve(label, color(k), dt_curve(&r.runs, scene, n, stiffness, k))
        })
        .collect();
    let axes = Axes {
        caption: format!(
            "{}, stiffness x{stiffness}: RMS error vs time step (measured order p)",
            scene.name()
        ),
        x_desc: "time step dt (s)",
        y_desc: "RMS position error (m)",
        x_decimal: false,
        x: bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.0))).unwrap_or((1e-4, 0.1)),
        y: bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.1))).unwrap_or((1e-9, 1.0)),
        legend: SeriesLabelPosition::LowerRight,
    };
    draw_loglog(path, axes, &series)
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
    let mut series = Vec::new();
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
        series.push(Series::curve(k.name().into(), color(k), pts));
    }
    let x = bounds(res.iter().map(|r| r.vertices as f64)).unwrap_or((100.0, 10000.0));
    let y =
        bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.1))).unwrap_or((1e-3, 10.0));
    series.push(Series {
        marker: None,
        ..Series::curve(
            "real time".into(),
            RGBColor(128, 128, 128),
            vec![(x.0, 1.0), (x.1, 1.0)],
        )
    });
    let axes = Axes {
        caption: format!(
            "{}: cost of the cheapest stable run vs resolution",
            scene.name()
        ),
        x_desc: "vertices",
        y_desc: "wall seconds per simulated second",
        x_decimal: true,
        x,
        y: (y.0.min(0.5), y.1.max(2.0)),
        legend: SeriesLabelPosition::UpperLeft,
    };
    draw_loglog(path, axes, &series)
}
