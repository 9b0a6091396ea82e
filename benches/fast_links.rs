//! What fast-contact splitting and the guard's strain check cost, as ratios measured
//! in one run:
//!
//! - the bundled scenes with both on over both off (`Simulation::set_fast_contact`): they should
//!   cost nothing where nothing moves fast (the split count is printed, exact);
//! - the fast-rod scene (1 m sheet, 40 x 40 vertices, free, implicit at 60 Hz, a 5 mm capsule at
//!   the sheet's middle height) with the rod at 20 m/s over the same scene with the rod at rest:
//!   at most 10x.
//!
//! `cargo bench --bench fast_links` prints one line per scene: ms per frame (best of the
//! repeats), the ratio and the substeps and splits per frame; for the rod also its CG
//! iterations and CG time per frame. `DRAPE_BENCH_ROD_ONLY=1` runs the rod alone.

use drape::robot::RobotDriver;
use drape::scene::Scene;
use drape::sim::Simulation;
use std::path::Path;
use std::time::Instant;

const REPEATS: usize = 3;

/// The bundled scenes and how many frames each runs.
const SCENES: [(&str, usize); 10] = [
    ("hanging.yaml", 60),
    ("sphere_drape.yaml", 60),
    ("table.yaml", 60),
    ("chair.yaml", 60),
    ("crumple.yaml", 30),
    ("flag.yaml", 60),
    ("robot_towel.yaml", 60),
    ("robot_cape.yaml", 60),
    ("robot_drape_arm.yaml", 60),
    ("robot_pick_towel.yaml", 60),
];

fn bundled(name: &str) -> (Simulation, Option<RobotDriver>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(name);
    let s = Scene::load(&path).expect("bundled scene");
    s.build_with_robot().expect("valid scene")
}

fn rod(speed: f64) -> (Simulation, Option<RobotDriver>) {
    let yaml = format!(
        r#"
name: fast_link
duration: 1.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666 }}
cloths:
  - name: sheet
    grid: {{ size: [1.0, 1.0], resolution: [40, 40], pose: {{ xyz: [0.0, 0.0, 1.0], rpy: [1.5707963267948966, 0.0, 0.0] }} }}
    material: {{ density: 0.2, stretch: 1000.0, shear: 100.0, bend_warp: 1.0e-5, bend_weft: 1.0e-5, thickness: 0.004 }}
obstacles:
  - name: rod
    shape: {{ type: capsule, radius: 0.005, half_height: 0.8 }}
    pose: {{ xyz: [0.0, -0.05, 1.0], rpy: [0.0, 0.0, 1.5707963267948966] }}
    motion: {{ type: velocity, linear: [0.0, {speed}, 0.0], angular: [0.0, 0.0, 0.0] }}
collision: {{ mode: continuous }}
"#
    );
    let s = Scene::from_yaml(&yaml, "fast_link").expect("valid scene");
    s.build_with_robot().expect("valid scene")
}

/// One scene's timing: ms per frame (best of the repeats), and per frame of the last repeat
/// its substeps, splits, CG iterations and CG milliseconds.
struct Timing {
    ms: f64,
    substeps: f64,
    splits: f64,
    cg: f64,
    cg_ms: f64,
}

/// Runs `frames` frames of a freshly built scene `REPEATS` times, fast contact on or off.
fn time(
    build: &dyn Fn() -> (Simulation, Option<RobotDriver>),
    frames: usize,
    fast: bool,
) -> Timing {
    let mut best = f64::INFINITY;
    let (mut substeps, mut splits, mut cg, mut cg_s) = (0u64, 0u64, 0u64, 0.0);
    for _ in 0..REPEATS {
        let (mut sim, mut driver) = build();
        sim.set_fast_contact(fast);
        (substeps, splits, cg, cg_s) = (0, 0, 0, 0.0);
        let start = Instant::now();
        for _ in 0..frames {
            if let Some(d) = driver.as_mut() {
                let t = sim.time() + sim.settings.dt;
                d.advance(&mut sim, t);
            }
            let m = sim.step().expect("stable");
            substeps += u64::from(m.substeps);
            splits += u64::from(m.contact_splits);
            cg += u64::from(m.cg_iterations);
            cg_s += m.cg_time_s;
        }
        best = best.min(start.elapsed().as_secs_f64() * 1e3 / frames as f64);
    }
    let f = frames as f64;
    Timing {
        ms: best,
        substeps: substeps as f64 / f,
        splits: splits as f64 / f,
        cg: cg as f64 / f,
        cg_ms: cg_s * 1e3 / f,
    }
}

fn main() {
    // `DRAPE_BENCH_ROD_ONLY=1`: the rod's line alone (for a profiler).
    let scenes: &[(&str, usize)] = if std::env::var_os("DRAPE_BENCH_ROD_ONLY").is_some() {
        &[]
    } else {
        &SCENES
    };
    println!("bundled scenes, fast contact on / off:");
    for &(name, frames) in scenes {
        let build = || bundled(name);
        let off = time(&build, frames, false).ms;
        let Timing {
            ms: on,
            substeps,
            splits,
            ..
        } = time(&build, frames, true);
        println!(
            "  {name}: {on:.2} / {off:.2} ms per frame = {:.3}, {substeps:.2} substeps and \
             {splits:.2} splits per frame",
            on / off
        );
    }
    let frames = 9;
    let rest = time(&|| rod(0.0), frames, true);
    let fast = time(&|| rod(20.0), frames, true);
    println!(
        "5 mm rod through the 40 x 40 sheet: 20 m/s {:.2} ms per frame, at rest {:.2}: \
         ratio {:.2} (at most 10), {:.2} substeps and {:.2} splits per frame; CG iterations per \
         frame {:.1} (at rest {:.1}), CG time {:.2} ms per frame (at rest {:.2})",
        fast.ms,
        rest.ms,
        fast.ms / rest.ms,
        fast.substeps,
        fast.splits,
        fast.cg,
        rest.cg,
        fast.cg_ms,
        rest.cg_ms
    );
}
