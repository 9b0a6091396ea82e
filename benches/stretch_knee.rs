//! What a stiffening material (`stretch_knee: 0.03`) costs against the same scene's linear one:
//! S1 (`benches/scenes/bench_s1.yaml`, a cloth dropped onto a sphere) and S2 (`bench_s2.yaml`,
//! hanging) at 64x64, and the robot scenes at their own resolution, each run linear then with
//! the knee over the same frames from the start, in one process.
//!
//! `cargo bench --bench stretch_knee` prints one row per scene: wall time per frame, CG
//! iterations and force evaluations per frame, the worst edge over rest at any frame end, and
//! the ratio of the knee's time to the linear one's.

use drape::robot::RobotDriver;
use drape::scene::Scene;
use drape::sim::Simulation;
use std::path::Path;
use std::time::Instant;

/// One run's figures.
struct Run {
    ms_per_frame: f64,
    cg_per_frame: f64,
    evaluations_per_frame: f64,
    worst_edge: f64,
}

fn load(path: &str, res: Option<usize>, knee: Option<f64>) -> (Simulation, Option<RobotDriver>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    let mut s = Scene::load(&path).expect("bundled scene");
    for c in &mut s.cloths {
        if let Some(r) = res {
            c.grid.resolution = [r, r];
        }
        c.material.stretch_knee = knee;
    }
    for g in &mut s.garments {
        g.material.stretch_knee = knee;
    }
    s.build_with_robot().expect("valid scene")
}

fn worst_edge(sim: &Simulation) -> f64 {
    1.0 + sim.cloth.max_edge_stretch()
}

fn run(path: &str, res: Option<usize>, knee: Option<f64>, frames: usize) -> Run {
    let (mut sim, mut driver) = load(path, res, knee);
    let (mut cg, mut fe, mut worst) = (0u64, 0u64, 0.0f64);
    let start = Instant::now();
    for _ in 0..frames {
        if let Some(d) = driver.as_mut() {
            let t = sim.time() + sim.settings.dt;
            d.advance(&mut sim, t);
        }
        let m = sim.step().expect("stable");
        cg += u64::from(m.cg_iterations);
        fe += u64::from(m.force_evaluations);
        worst = worst.max(worst_edge(&sim));
    }
    let wall = start.elapsed().as_secs_f64();
    let f = frames as f64;
    Run {
        ms_per_frame: wall * 1e3 / f,
        cg_per_frame: cg as f64 / f,
        evaluations_per_frame: fe as f64 / f,
        worst_edge: worst,
    }
}

fn main() {
    let scenes: [(&str, &str, Option<usize>, usize); 4] = [
        ("S1 64x64", "benches/scenes/bench_s1.yaml", Some(64), 120),
        ("S2 64x64", "benches/scenes/bench_s2.yaml", Some(64), 120),
        (
            "robot_towel 64x64",
            "config/robot_towel.yaml",
            Some(64),
            120,
        ),
        ("robot_cape", "config/robot_cape.yaml", None, 120),
    ];
    println!("| scene | frames | linear ms/frame | knee ms/frame | knee / linear | CG/frame (linear, knee) | force evaluations/frame (linear, knee) | worst edge (linear, knee) |");
    println!("|---|---|---|---|---|---|---|---|");
    for (label, path, res, frames) in scenes {
        let a = run(path, res, None, frames);
        let b = run(path, res, Some(0.03), frames);
        println!(
            "| {label} | {frames} | {:.1} | {:.1} | {:.2} | {:.1}, {:.1} | {:.2}, {:.2} | {:.4}, {:.4} |",
            a.ms_per_frame,
            b.ms_per_frame,
            b.ms_per_frame / a.ms_per_frame,
            a.cg_per_frame,
            b.cg_per_frame,
            a.evaluations_per_frame,
            b.evaluations_per_frame,
            a.worst_edge,
            b.worst_edge,
        );
    }
}
