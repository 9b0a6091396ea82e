//! What holding cloth by contact costs against holding it by the grasp rule:
//! `config/robot_pinch_towel.yaml` (the fingers pinch the towel; only contact and friction hold
//! it) against the same scene with a `grasps:` rule whose pads sit between the fingers (the
//! vertices there are attached while the fingers are closed; the fingers close to a 16 mm gap,
//! as a rule's user closes them, not onto the cloth they hold), self-collision off and on, over
//! the whole run (approach, close, lift, carry, release) and over the frames the fingers are
//! closed, in one process.
//!
//! `cargo bench --bench pinch` prints one row per variant: wall time per frame over the run and
//! over the closed frames, CG iterations per frame, and the pinch's time over the rule's.

#[path = "../tests/common/finger_rule.rs"]
mod finger_rule;

use drape::robot::RobotDriver;
use drape::scene::Scene;
use drape::sim::Simulation;
use std::path::Path;
use std::time::Instant;

/// Where the rule's fingers stop closing (m each side): under its `close_below`, and a 16 mm gap,
/// twice the cloth's contact distance, so they do not squeeze the cloth they hold.
const RULE_CLOSED: f64 = 0.008;

/// The fingers are closed on the towel from here to here (s; the scene's trajectory).
const CLOSED: (f64, f64) = (1.4, 3.2);

struct Run {
    ms_per_frame: f64,
    closed_ms_per_frame: f64,
    cg_per_frame: f64,
    /// Over the closed frames, ms per frame in the linear solves and in the collision stage.
    closed_cg_ms: f64,
    closed_collision_ms: f64,
}

fn load(rule: bool, self_collision: bool) -> (Simulation, RobotDriver, f64) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/robot_pinch_towel.yaml");
    let mut s = Scene::load(&path).expect("bundled scene");
    s.collision.self_collision = self_collision;
    if rule {
        let robot = s.robot.as_mut().expect("a robot");
        let trajectory = robot.trajectory.as_mut().expect("a trajectory");
        let finger = (trajectory.names.iter())
            .position(|n| n == "right_finger_a_joint")
            .expect("the finger in the trajectory");
        for p in &mut trajectory.points {
            p.positions[finger] = p.positions[finger].max(RULE_CLOSED);
        }
        robot.grasps.push(finger_rule::between_the_fingers());
    }
    let duration = s.duration;
    let (sim, driver) = s.build_with_robot().expect("valid scene");
    (sim, driver.expect("a robot"), duration)
}

fn run(rule: bool, self_collision: bool) -> Run {
    let (mut sim, mut driver, duration) = load(rule, self_collision);
    let dt = sim.settings.dt;
    let frames = (duration / dt).round() as usize;
    let (mut cg, mut closed_s, mut closed_frames) = (0u64, 0.0, 0usize);
    let (mut closed_cg_s, mut closed_collision_s) = (0.0, 0.0);
    let start = Instant::now();
    for _ in 0..frames {
        let t = sim.time() + dt;
        let clock = Instant::now();
        driver.advance(&mut sim, t);
        let m = sim.step().expect("stable");
        if (CLOSED.0..=CLOSED.1).contains(&t) {
            closed_s += clock.elapsed().as_secs_f64();
            closed_frames += 1;
            closed_cg_s += m.cg_time_s;
            closed_collision_s += m.collision_time_s;
        }
        cg += u64::from(m.cg_iterations);
    }
    let wall = start.elapsed().as_secs_f64();
    let per_closed = 1e3 / closed_frames.max(1) as f64;
    Run {
        ms_per_frame: wall * 1e3 / frames as f64,
        closed_ms_per_frame: closed_s * per_closed,
        cg_per_frame: cg as f64 / frames as f64,
        closed_cg_ms: closed_cg_s * per_closed,
        closed_collision_ms: closed_collision_s * per_closed,
    }
}

fn main() {
    println!("| self-collision | rule ms/frame | pinch ms/frame | pinch / rule | closed frames: rule ms, pinch ms, pinch / rule | closed frames' solves ms (rule, pinch) | closed frames' collision ms (rule, pinch) | CG/frame (rule, pinch) |");
    println!("|---|---|---|---|---|---|---|---|");
    for self_collision in [false, true] {
        let rule = run(true, self_collision);
        let pinch = run(false, self_collision);
        println!(
            "| {} | {:.2} | {:.2} | {:.2} | {:.2}, {:.2}, {:.2} | {:.2}, {:.2} | {:.2}, {:.2} | {:.1}, {:.1} |",
            if self_collision { "on" } else { "off" },
            rule.ms_per_frame,
            pinch.ms_per_frame,
            pinch.ms_per_frame / rule.ms_per_frame,
            rule.closed_ms_per_frame,
            pinch.closed_ms_per_frame,
            pinch.closed_ms_per_frame / rule.closed_ms_per_frame,
            rule.closed_cg_ms,
            pinch.closed_cg_ms,
            rule.closed_collision_ms,
            pinch.closed_collision_ms,
            rule.cg_per_frame,
            pinch.cg_per_frame,
        );
    }
}
