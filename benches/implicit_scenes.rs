//! The implicit solver on the scenes that need it most, without DDS: the hanging cloth of the
//! step bench at 64x64 and the robot towel of the node (config/robot_towel.yaml at 64x64: 6 mm
//! spacing, stretch 1500, 2 substeps per 1/60 s frame, robot swinging it, continuous collision).
//!
//! `cargo bench --bench implicit_scenes` prints, before criterion's timings, the CG iterations
//! and Newton force evaluations per frame over a fixed run, so that time and work can be compared,
//! and the cost of one PCG iteration at 64x64 on S1 (`benches/scenes/bench_s1.yaml`, the cloth
//! on a sphere) and S2 (`bench_s2.yaml`, hanging): the solver's own count of flops and
//! least bytes streamed per iteration (block CSR 3x3 product, V-cycle levels, vector passes), the
//! measured wall time per iteration, this machine's memory bandwidth (a STREAM triad over
//! buffers far larger than cache, both cores) and the ratio of the time to the bandwidth bound.

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

/// STREAM's triad `a = b + s c` over three 32 MiB arrays on both cores: best of five, in bytes
/// per second (24 bytes moved per element, write-allocate not counted, as STREAM does).
fn triad_bandwidth() -> f64 {
    use rayon::prelude::*;
    let n = 4 << 20;
    let (mut a, b, c) = (vec![0.0f64; n], vec![1.0f64; n], vec![2.0f64; n]);
    let mut best = f64::INFINITY;
    for k in 0..5 {
        let s = 0.5 + k as f64;
        let t = Instant::now();
        a.par_chunks_mut(1 << 16)
            .zip(b.par_chunks(1 << 16))
            .zip(c.par_chunks(1 << 16))
            .for_each(|((a, b), c)| {
                for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                    *a = b + s * c;
                }
            });
        best = best.min(t.elapsed().as_secs_f64());
    }
    std::hint::black_box(&a);
    24.0 * n as f64 / best
}

/// Cost of one PCG iteration over `frames` frames of `name` at `res`x`res`.
fn iteration_cost(name: &str, res: usize, frames: usize, bandwidth: f64) {
    let (mut sim, mut driver) = load(name, res);
    let (mut its, mut time, mut flops, mut bytes) = (0u64, 0.0, 0.0, 0.0);
    for _ in 0..frames {
        frame(&mut sim, &mut driver);
        let m = sim.last_metrics();
        its += u64::from(m.cg_iterations);
        time += m.cg_time_s;
        flops += m.cg_flops;
        bytes += m.cg_bytes;
    }
    let k = its.max(1) as f64;
    let (t, f, b) = (time / k, flops / k, bytes / k);
    eprintln!(
        "{name} {res}x{res}: one PCG iteration = {:.2} Mflop, {:.2} MB streamed at the least; \
         measured {:.3} ms per iteration over {its} iterations; bandwidth bound {:.3} ms \
         ({:.1} GB/s triad); measured / bound = {:.2}",
        f * 1e-6,
        b * 1e-6,
        t * 1e3,
        b / bandwidth * 1e3,
        bandwidth * 1e-9,
        t / (b / bandwidth),
    );
}

fn scenes(c: &mut Criterion) {
    let bandwidth = triad_bandwidth();
    iteration_cost("../benches/scenes/bench_s1.yaml", 64, 120, bandwidth);
    iteration_cost("../benches/scenes/bench_s2.yaml", 64, 120, bandwidth);
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
