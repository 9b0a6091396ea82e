//! The implicit solver on the scenes that need it most, without DDS: the hanging cloth of the
//! step bench at 64x64 and the robot towel of the node (config/robot_towel.yaml at 64x64: 6 mm
//! spacing, stretch 1500, 2 substeps per 1/60 s frame, robot swinging it, continuous collision).
//!
//! `cargo bench --bench implicit_scenes` prints, before criterion's timings, the CG iterations
//! and Newton force evaluations per frame over a fixed run, so that time and work can be compared.

use criterion::{criterion_group, criterion_main, Criterion};
use drape::robot::RobotDriver;
use drape::scene::Scene;
use drape::sim::Simulation;
use std::path::Path;
use std::time::{Duration, Instant};

fn load(name: &str, res: usize) -> (Simulation, Option<RobotDriver>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(name);
    let mut s = Scene::load(&path).expect("bundled scene");
    s.cloths[0].grid.resolution = [res, res];
    s.build_with_robot().expect("valid scene")
}

fn frame(sim: &mut Simulation, driver: &mut Option<RobotDriver>) -> u32 {
    if let Some(d) = driver.as_mut() {
        let t = sim.time() + sim.settings.dt;
        d.advance(sim, t);
    }
    sim.step().expect("stable").cg_iterations
}

/// Work per frame over `frames` frames from the scene's start.
fn summary(name: &str, res: usize, frames: usize) {
    let (mut sim, mut driver) = load(name, res);
    let (mut cg, mut fe, mut sub, mut substeps) = (0u64, 0u64, 0u64, 0u64);
    let start = Instant::now();
    for _ in 0..frames {
        frame(&mut sim, &mut driver);
        let m = sim.last_metrics();
        cg += u64::from(m.cg_iterations);
        fe += u64::from(m.force_evaluations);
        sub += u64::from(m.subdivisions);
        substeps += u64::from(m.substeps);
    }
    let f = frames as f64;
    eprintln!(
        "{name} {res}x{res}: {:.2} ms/frame over {frames} frames, {:.1} substeps, {:.1} CG \
         iterations, {:.2} force evaluations per frame, {sub} subdivisions",
        start.elapsed().as_secs_f64() * 1e3 / f,
        substeps as f64 / f,
        cg as f64 / f,
        fe as f64 / f,
    );
}

fn scenes(c: &mut Criterion) {
    summary("hanging.yaml", 64, 60);
    summary("robot_towel.yaml", 64, 60);
    let mut g = c.benchmark_group("implicit_scenes");
    g.measurement_time(Duration::from_secs(5)).sample_size(10);
    for (name, id) in [
        ("hanging.yaml", "hanging_64x64"),
        ("robot_towel.yaml", "robot_towel_64x64"),
    ] {
        let (mut sim, mut driver) = load(name, 64);
        // Into the motion first (the robot starts swinging at 0.5 s).
        for _ in 0..40 {
            frame(&mut sim, &mut driver);
        }
        g.bench_function(id, |b| b.iter(|| frame(&mut sim, &mut driver)));
    }
    g.finish();
}

criterion_group!(benches, scenes);
criterion_main!(benches);
