//! The node's adaptive quality (`src/ros/node/quality.rs`) through its simulation loop, on a
//! synthetic clock whose steps cost what a model of the solver says: the loop must settle at
//! the best quality that holds real time, stay there, report it in `/diagnostics`, say once
//! when even the lowest quality cannot hold real time, and change nothing when real time is met.
#![cfg(feature = "ros")]

use drape::ros::msg::DiagnosticArray;
use drape::ros::node::{Level, LoopConfig, Output, Quality, QualityBounds, SimLoop};
use drape::scene::Scene;

const T0: f64 = 1000.0;

/// The bundled robot towel, coarse so that a minute of it steps in seconds.
fn scene() -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/robot_towel.yaml");
    let mut s = Scene::load(path.as_ref()).expect("robot_towel scene");
    s.cloths[0].grid.resolution = [10, 10];
    s
}

fn adaptive_loop() -> SimLoop {
    let cfg = LoopConfig {
        quality: Some(QualityBounds::default()),
        ..LoopConfig::default()
    };
    SimLoop::new(scene(), cfg, T0).expect("loop")
}

/// A model of a step's wall time in units of `dt`: proportional to substeps times CG
/// iterations, `min(cap, 15 log10(1 / tol))` (75 at the scene's 1e-5, 30 at 1e-2), scaled so
/// the scene's own quality (2 substeps, 75 iterations) costs `full` times real time. The
/// default bounds' lowest quality (1 substep, 30 iterations) then costs `full / 5`.
fn cost(q: &Quality, full: f64) -> f64 {
    let iterations = f64::from(q.cg_max_iterations).min(15.0 * (1.0 / q.cg_tolerance).log10());
    full * f64::from(q.substeps) * iterations / 150.0
}

/// Drives the loop for `seconds` of clock time as its thread would: a step takes its modelled
/// wall time off the clock; when nothing is owed the clock jumps to the next thing due.
fn drive(l: &mut SimLoop, now: &mut f64, seconds: f64, out: &mut Vec<Output>) {
    let end = *now + seconds;
    while *now < end {
        let steps = l.stats().steps;
        l.tick(*now, out);
        if l.stats().steps > steps {
            *now += l.last_step_wall();
        } else {
            *now = l.next_wake().max(*now + 1e-6);
        }
    }
}

fn value<'a>(d: &'a DiagnosticArray, key: &str) -> &'a str {
    d.status[0]
        .values
        .iter()
        .find(|kv| kv.key == key)
        .map(|kv| kv.value.as_str())
        .unwrap_or_else(|| panic!("diagnostics without {key}"))
}

fn last_diagnostics(out: &[Output]) -> &DiagnosticArray {
    out.iter()
        .rev()
        .find_map(|o| match o {
            Output::Diagnostics(d) => Some(d),
            _ => None,
        })
        .expect("a diagnostics message")
}

fn logs(out: &[Output], level: Level, text: &str) -> usize {
    out.iter()
        .filter(
            |o| matches!(o, Output::Log { level: l, text: t } if *l == level && t.contains(text)),
        )
        .count()
}

#[test]
fn a_slow_scene_settles_at_the_best_quality_that_holds_real_time() {
    let full = 3.0;
    let mut l = adaptive_loop();
    let dt = l.simulation().settings.dt;
    let ladder = l.quality_ladder().to_vec();
    // Going down one level at a time, the controller stops at the first level under 0.9 of
    // real time; with this model that level costs over 0.5, so it never probes upwards.
    let expected = ladder
        .iter()
        .position(|q| cost(q, full) <= 0.9)
        .expect("the lowest quality holds real time");
    assert!(
        expected > 0 && expected < ladder.len() - 1,
        "the model should settle between the ends: level {expected} of {}",
        ladder.len()
    );
    assert!(cost(&ladder[expected], full) > 0.5);
    l.set_step_cost(move |q| cost(q, full) * dt);
    let (mut now, mut out) = (T0, Vec::new());
    l.sync_clock(now);
    drive(&mut l, &mut now, 10.0, &mut out);
    assert_eq!(l.quality().level, expected);
    assert_eq!(logs(&out, Level::Info, "quality lowered"), expected);
    // Settled: another 20 s change nothing.
    out.clear();
    drive(&mut l, &mut now, 20.0, &mut out);
    assert_eq!(
        logs(&out, Level::Info, "quality"),
        0,
        "quality changed after settling"
    );
    assert_eq!(l.quality().level, expected);
    // The simulation runs at that quality: substeps and the CG cap reached the solver.
    let q = ladder[expected];
    assert_eq!(l.simulation().settings.substeps, q.substeps);
    let m = l.simulation().last_metrics();
    assert!(m.cg_iterations <= m.substeps * q.cg_max_iterations);
    let d = last_diagnostics(&out);
    assert_eq!(d.status[0].level, 0, "{}", d.status[0].message);
    assert_eq!(value(d, "quality_level"), expected.to_string());
    assert_eq!(value(d, "quality_substeps"), q.substeps.to_string());
    assert_eq!(
        value(d, "quality_cg_max_iterations"),
        q.cg_max_iterations.to_string()
    );
    let tol: f64 = value(d, "quality_cg_tolerance").parse().unwrap();
    assert!((tol / q.cg_tolerance - 1.0).abs() < 1e-12);
    let lin: f64 = value(d, "quality_linearisation_tolerance").parse().unwrap();
    assert_eq!(lin, q.linearisation_tolerance);
    // Real time held: each step costs under dt, so the loop waits for the clock and a 1 s
    // window covers 60 or 61 steps; the factor is 1 within one step per window (1/60).
    let rtf: f64 = value(d, "real_time_factor").parse().unwrap();
    assert!((rtf - 1.0).abs() <= dt + 1e-3, "real-time factor {rtf}");
}

#[test]
fn real_time_out_of_reach_is_said_once_with_its_factor() {
    // The lowest quality costs 8 / 5 = 1.6 times real time: factor 1 / 1.6 = 0.625.
    let full = 8.0;
    let mut l = adaptive_loop();
    let dt = l.simulation().settings.dt;
    let lowest = l.quality_ladder().len() - 1;
    l.set_step_cost(move |q| cost(q, full) * dt);
    let (mut now, mut out) = (T0, Vec::new());
    l.sync_clock(now);
    drive(&mut l, &mut now, 30.0, &mut out);
    assert_eq!(l.quality().level, lowest);
    assert_eq!(logs(&out, Level::Warn, "cannot hold real time"), 1);
    assert_eq!(logs(&out, Level::Warn, "real-time factor 0.62"), 1);
    let d = last_diagnostics(&out);
    assert_eq!(d.status[0].level, 1, "WARN: {}", d.status[0].message);
    assert!(d.status[0].message.contains("lowest allowed quality"));
    assert_eq!(value(d, "real_time_factor_at_lowest_quality"), "0.625");
    assert_eq!(value(d, "quality_level"), lowest.to_string());
    // The loop runs as fast as the lowest quality allows: one step per 1.6 dt of clock.
    let rtf: f64 = value(d, "real_time_factor").parse().unwrap();
    assert!((rtf - 0.625).abs() <= dt + 1e-3, "real-time factor {rtf}");
}

#[test]
fn real_time_met_keeps_the_scene_quality_bit_for_bit() {
    // Steps at 0.7 of real time: adaptive and fixed loops step the same cloth.
    let run = |quality: Option<QualityBounds>| {
        let cfg = LoopConfig {
            quality,
            ..LoopConfig::default()
        };
        let mut l = SimLoop::new(scene(), cfg, T0).expect("loop");
        let dt = l.simulation().settings.dt;
        l.set_step_cost(move |q| cost(q, 0.7) * dt);
        let (mut now, mut out) = (T0, Vec::new());
        l.sync_clock(now);
        drive(&mut l, &mut now, 5.0, &mut out);
        (l, out)
    };
    let (adaptive, out) = run(Some(QualityBounds::default()));
    let (fixed, _) = run(None);
    assert_eq!(adaptive.quality().level, 0);
    assert_eq!(logs(&out, Level::Info, "quality"), 0);
    assert!(adaptive.stats().steps >= 299);
    assert_eq!(adaptive.stats().steps, fixed.stats().steps);
    assert_eq!(adaptive.simulation().cloth.x, fixed.simulation().cloth.x);
    let d = last_diagnostics(&out);
    assert_eq!(value(d, "quality_adaptive"), "true");
    assert_eq!(value(d, "quality_substeps"), "2");
    assert_eq!(d.status[0].message, "running");
}
