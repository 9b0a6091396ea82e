//! Self-collision cost, as ratios measured in one run: every bundled scene for
//! `SELFCOL_BENCH_SECONDS` simulated seconds (default 1, 0 = its full duration) with and without
//! `self_collision: true`, in ms per frame and their ratio (target: at most 2x), and the
//! crumpling cloth (config/crumple.yaml) at 64x64 and 128x128: the collision stage in ms per
//! step with self-collision on and off, the self-collision share (targets per step: at 64x64
//! under 5 ms, and under 3 ms for the stricter target, at 128x128 under 12 ms; after the first
//! frame, whose one-time setup is printed apart), with the exact counts (candidate pairs, repulsions,
//! CCD passes and hits, impact zones and the largest zone's vertices) per step.
//!
//! `cargo bench --bench self_collision`; run it on an idle machine. `SELFCOL_BENCH_SCENES=a.yaml,b.yaml`
//! keeps those scenes of the table (`none`: none), `SELFCOL_BENCH_CRUMPLE=64` those crumple
//! resolutions (`none`: none).

#[path = "../tests/common/self_check.rs"]
mod self_check;

use drape::scene::Scene;
use self_check::{bundled, SCENES};
use std::time::Instant;

struct Cost {
    ms_per_frame: f64,
    /// The collision stage over the steps after the first frame's.
    collision_ms_per_step: f64,
    /// The first frame's collision stage: one-time setup (the rest shape's exemptions and near
    /// lists, the hierarchy) with its steps.
    first_frame_collision_ms: f64,
    steps: u64,
    counts: drape::collide::SelfContactReport,
}

/// Steps `scene` (built after the clock starts: sewing is part of a garment scene's cost).
fn cost(scene: &Scene, seconds: f64) -> Cost {
    let start = Instant::now();
    let (mut sim, mut driver) = scene.build_with_robot().expect("bundled scene builds");
    let secs = if seconds > 0.0 {
        seconds
    } else {
        scene.duration
    };
    let frames = (secs / sim.settings.dt).round().max(1.0) as usize;
    let (mut coll, mut timed, mut steps, mut first) = (0.0, 0u64, 0u64, 0.0);
    let mut counts = drape::collide::SelfContactReport::default();
    for frame in 0..frames {
        if let Some(d) = driver.as_mut() {
            let t = sim.time() + sim.settings.dt;
            d.advance(&mut sim, t);
        }
        let m = sim.step().expect("stable");
        if frame == 0 && frames > 1 {
            first = m.collision_time_s;
        } else {
            coll += m.collision_time_s;
            timed += u64::from(m.substeps);
        }
        steps += u64::from(m.substeps);
        counts.add(&m.self_contact);
    }
    Cost {
        ms_per_frame: start.elapsed().as_secs_f64() * 1e3 / frames as f64,
        collision_ms_per_step: coll * 1e3 / timed.max(1) as f64,
        first_frame_collision_ms: first * 1e3,
        steps,
        counts,
    }
}

fn per_step(c: &Cost) -> String {
    let s = c.steps.max(1) as f64;
    let k = &c.counts;
    format!(
        "per step: {:.0} candidates ({:.0} node tests), {:.1} repulsions, {:.2} CCD passes, {:.2} CCD hits; \
         {} zones at most, largest {} vertices; {} rest-exempt pairs",
        k.candidates as f64 / s,
        k.node_tests as f64 / s,
        k.repulsions as f64 / s,
        k.ccd_passes as f64 / s,
        k.ccd_hits as f64 / s,
        k.zones,
        k.largest_zone,
        k.exempt
    )
}

/// Whether `item` is in the comma-separated list of environment variable `key` (unset or empty:
/// every item).
fn chosen(key: &str, item: &str) -> bool {
    match std::env::var(key) {
        Ok(l) if !l.is_empty() => l.split(',').any(|s| s == item),
        _ => true,
    }
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let seconds: f64 = std::env::var("SELFCOL_BENCH_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    println!("scene: ms/frame with self-collision, without, ratio (target <= 2)");
    let mut worst: f64 = 0.0;
    for name in SCENES.iter().filter(|n| chosen("SELFCOL_BENCH_SCENES", n)) {
        let mut on = bundled(name, 1);
        // The stage's own exact intersection count (crumple.yaml has it on) is a metric, not
        // part of the self-collision cost.
        on.collision.count_self_intersections = false;
        let mut off = on.clone();
        off.collision.self_collision = false;
        let (a, b) = (cost(&on, seconds), cost(&off, seconds));
        let ratio = a.ms_per_frame / b.ms_per_frame;
        worst = worst.max(ratio);
        println!(
            "{name}: {:.2} / {:.2} ms, ratio {ratio:.2}; {}",
            a.ms_per_frame,
            b.ms_per_frame,
            per_step(&a)
        );
    }
    println!("largest ratio: {worst:.2}");
    for (res, target) in [(64usize, "5 (3 strict)"), (128, "12")]
        .into_iter()
        .filter(|r| chosen("SELFCOL_BENCH_CRUMPLE", &r.0.to_string()))
    {
        let mut on = bundled("crumple.yaml", 1);
        on.cloths[0].grid.resolution = [res, res];
        on.collision.count_self_intersections = false;
        let mut off = on.clone();
        off.collision.self_collision = false;
        let secs = if seconds > 0.0 {
            seconds.max(1.0)
        } else {
            on.duration
        };
        let (a, b) = (cost(&on, secs), cost(&off, secs));
        let share = a.collision_ms_per_step - b.collision_ms_per_step;
        println!(
            "crumple {res}x{res}: collision stage {:.2} ms/step with self-collision, {:.2} without: \
             self-collision {share:.2} ms/step (target < {target}; after the first frame, whose \
             collision stage took {:.0} ms with setup, {:.0} without); frames {:.1} / {:.1} ms, \
             ratio {:.2}; {}",
            a.collision_ms_per_step,
            b.collision_ms_per_step,
            a.first_frame_collision_ms,
            b.first_frame_collision_ms,
            a.ms_per_frame,
            b.ms_per_frame,
            a.ms_per_frame / b.ms_per_frame,
            per_step(&a)
        );
    }
}
