//! The node's simulation loop without DDS, on a synthetic clock: fixed publish rate, joint
//! states moving the robot and the cloth attached to it, bad inputs dropped and counted,
//! bounded backlog, reset, pause, and /robot_description reloads.
#![cfg(feature = "ros")]

use drape::robot::JointInput;
use drape::ros::msg::DiagnosticArray;
use drape::ros::node::{Command, LoopConfig, Output, SimLoop};
use drape::scene::Scene;

const T0: f64 = 1000.0;

fn scene() -> Scene {
    Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/config/robot_towel.yaml").as_ref())
        .expect("robot_towel scene")
}

fn urdf_text() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/urdf/drape_bot.urdf"))
        .expect("drape_bot.urdf")
}

fn new_loop() -> SimLoop {
    SimLoop::new(scene(), LoopConfig::default(), T0).expect("loop")
}

fn joints(names: &[&str], positions: &[f64]) -> Command {
    Command::Joints {
        stamp_ns: 0,
        input: JointInput {
            names: names.iter().map(|s| s.to_string()).collect(),
            positions: positions.to_vec(),
            velocities: None,
        },
    }
}

/// Ticks the clock from `from` to `to` in `step` increments, collecting outputs.
fn run(l: &mut SimLoop, from: f64, to: f64, step: f64, out: &mut Vec<Output>) {
    let n = ((to - from) / step).round() as usize;
    for k in 1..=n {
        l.advance_to(from + k as f64 * step, out);
    }
}

fn frames(out: &[Output]) -> Vec<(f64, Vec<u8>)> {
    out.iter()
        .filter_map(|o| match o {
            Output::Frame { points, .. } => Some((
                points.header.stamp.as_nanos() as f64 * 1e-9,
                points.data.clone(),
            )),
            _ => None,
        })
        .collect()
}

fn diagnostics(out: &[Output]) -> Vec<&DiagnosticArray> {
    out.iter()
        .filter_map(|o| match o {
            Output::Diagnostics(d) => Some(d),
            _ => None,
        })
        .collect()
}

fn value<'a>(d: &'a DiagnosticArray, key: &str) -> &'a str {
    d.status[0]
        .values
        .iter()
        .find(|kv| kv.key == key)
        .map(|kv| kv.value.as_str())
        .unwrap_or_else(|| panic!("diagnostics without {key}"))
}

#[test]
fn publishes_at_fixed_rate_on_synthetic_clock() {
    let mut l = new_loop();
    let dt = l.simulation().settings.dt;
    let mut out = Vec::new();
    l.sync_clock(T0);
    l.advance_to(T0, &mut out);
    run(&mut l, T0, T0 + 2.0, 0.005, &mut out);
    let f = frames(&out);
    // Instants T0, T0 + 1/30, ..., T0 + 2: 61 frames.
    assert_eq!(f.len(), 61, "frames");
    for w in f.windows(2) {
        let gap = w[1].0 - w[0].0;
        // Stamps are step boundaries at or before each publish instant.
        assert!((gap - 1.0 / 30.0).abs() <= dt + 1e-6, "gap {gap}");
    }
    assert_eq!(l.stats().steps, (2.0 / dt).round() as u64);
    let d = diagnostics(&out);
    assert_eq!(d.len(), 2, "1 Hz diagnostics over 2 s");
    let rtf: f64 = value(d[1], "real_time_factor").parse().unwrap();
    assert!(
        (rtf - 1.0).abs() < 0.05,
        "real-time factor {rtf} on a synthetic clock"
    );
    assert_eq!(l.frame_id(), "base_link");
}

#[test]
fn joint_states_move_attached_vertices_with_their_link() {
    let mut l = new_loop();
    let mut out = Vec::new();
    l.sync_clock(T0);
    let x0 = l.simulation().cloth.x.clone();
    let names = ["right_shoulder_pitch", "right_elbow"];
    // Sweep the shoulder from the scene's -1.5 to -0.9 over 1 s at 50 Hz.
    for k in 0..=50 {
        let t = T0 + k as f64 * 0.02;
        let s = -1.5 + 0.6 * k as f64 / 50.0;
        assert!(l.handle(joints(&names, &[s, -0.2]), t, &mut out));
        l.advance_to(t, &mut out);
    }
    run(&mut l, T0 + 1.0, T0 + 1.2, 0.005, &mut out);
    assert_eq!(l.stats().joint_states, 51);
    assert_eq!(l.stats().dropped.total(), 0);
    let d = l.driver().expect("robot");
    let robot = d.robot();
    let j = robot.joint_index("right_shoulder_pitch").unwrap();
    assert!((d.joint_positions().positions[j] + 0.9).abs() < 1e-12);
    let sim = l.simulation();
    let mut attached = 0;
    for (v, k) in &sim.cloth.kinematic {
        if let drape::cloth::Kinematic::Attached { frame, local } = k {
            let link = (0..robot.link_names().len())
                .find(|&li| d.frame_of(li) == Some(*frame))
                .expect("attachment frame bound to a link");
            let want = d.link_poses()[link].transform_point(*local);
            let got = sim.cloth.x[*v as usize];
            assert!(
                (got - want).length() < 1e-9,
                "vertex {v} left its link: {got} vs {want}"
            );
            attached += 1;
        }
    }
    assert!(
        attached > 0,
        "the towel scene attaches vertices to the palm"
    );
    // The held corner moved with the arm.
    let moved = sim
        .cloth
        .x
        .iter()
        .zip(&x0)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(moved > 0.05, "cloth moved only {moved} m");
}

#[test]
fn bad_joint_states_are_dropped_and_counted_while_publishing_continues() {
    let mut l = new_loop();
    let mut out = Vec::new();
    l.sync_clock(T0);
    let good = ["right_elbow"];
    let stamped = |ns: i64, p: f64| Command::Joints {
        stamp_ns: ns,
        input: JointInput {
            names: vec!["right_elbow".into()],
            positions: vec![p],
            velocities: None,
        },
    };
    l.handle(stamped(5_000_000_000, -0.3), T0, &mut out);
    let q_good = l.driver().unwrap().joint_positions().clone();
    let bad = [
        joints(&good, &[f64::NAN]),
        joints(&good, &[0.1, 0.2]),
        joints(&["no_such_joint"], &[0.1]),
        stamped(4_000_000_000, 0.5),
        joints(&good, &[f64::INFINITY]),
    ];
    for (k, c) in bad.into_iter().enumerate() {
        l.handle(c, T0 + 0.1 * k as f64, &mut out);
    }
    run(&mut l, T0, T0 + 1.0, 0.01, &mut out);
    // The robot kept the last good command.
    let j = l
        .driver()
        .unwrap()
        .robot()
        .joint_index("right_elbow")
        .unwrap();
    assert_eq!(
        l.driver().unwrap().joint_positions().positions[j],
        -0.3,
        "a bad message moved the robot"
    );
    assert_ne!(q_good.positions[j], 0.5);
    let s = l.stats();
    assert_eq!(
        (
            s.dropped.non_finite,
            s.dropped.wrong_length,
            s.dropped.unknown_joint,
            s.dropped.out_of_order
        ),
        (2, 1, 1, 1)
    );
    assert_eq!(frames(&out).len(), 31, "publishing continued");
    let d = diagnostics(&out);
    assert_eq!(value(d[0], "dropped_joint_states"), "5");
    assert_eq!(d[0].status[0].level, 1, "WARN after drops");
    // Warnings were logged for the first drops.
    let warnings = out
        .iter()
        .filter(|o| matches!(o, Output::Log { text, .. } if text.contains("dropped")))
        .count();
    assert_eq!(warnings, 5);
}

#[test]
fn backlog_is_bounded_and_reported() {
    let cfg = LoopConfig {
        max_backlog_steps: 4,
        ..LoopConfig::default()
    };
    let mut l = SimLoop::new(scene(), cfg, T0).unwrap();
    let dt = l.simulation().settings.dt;
    let mut out = Vec::new();
    l.sync_clock(T0);
    // The clock jumps 3 s ahead (a stalled process): 4 steps run, the rest is forgiven.
    l.advance_to(T0 + 3.0, &mut out);
    assert_eq!(l.stats().steps, 4);
    assert_eq!(l.dropped_steps(), (3.0 / dt).round() as u64 - 4);
    assert!(
        (l.clock_of_state() - (T0 + 3.0)).abs() < dt,
        "stamps stay with the clock"
    );
    let d = diagnostics(&out);
    assert_eq!(d.len(), 1);
    let rtf: f64 = value(d[0], "real_time_factor").parse().unwrap();
    assert!(rtf < 0.1, "real-time factor {rtf}");
    assert_eq!(d[0].status[0].level, 1, "WARN when slower than real time");
}

#[test]
fn reset_restores_the_initial_cloth_and_pause_holds_time() {
    let mut l = new_loop();
    let mut out = Vec::new();
    l.sync_clock(T0);
    let x0 = l.simulation().cloth.x.clone();
    run(&mut l, T0, T0 + 0.5, 0.01, &mut out);
    assert_ne!(l.simulation().cloth.x, x0, "the towel falls");
    // Pause: time stands still, frames keep coming, no backlog on resume.
    l.handle(Command::Pause(true), T0 + 0.5, &mut out);
    let (t_sim, steps) = (l.simulation().time(), l.stats().steps);
    let before = frames(&out).len();
    run(&mut l, T0 + 0.5, T0 + 1.5, 0.01, &mut out);
    assert_eq!((l.simulation().time(), l.stats().steps), (t_sim, steps));
    assert_eq!(frames(&out).len() - before, 30);
    l.handle(Command::Pause(false), T0 + 1.5, &mut out);
    l.advance_to(T0 + 1.5, &mut out);
    assert_eq!(l.dropped_steps(), 0);
    assert_eq!(l.stats().steps, steps, "no catch-up burst after resume");
    out.clear();
    l.handle(Command::Reset { id: 7 }, T0 + 1.5, &mut out);
    assert!(
        matches!(
            &out[..],
            [Output::ResetDone {
                id: 7,
                result: Ok(_)
            }]
        ),
        "{out:?}"
    );
    assert_eq!(l.simulation().cloth.x, x0);
    assert_eq!(l.simulation().time(), 0.0);
    assert_eq!(l.stats().resets, 1);
}

#[test]
fn robot_description_reloads_and_bad_one_keeps_the_robot() {
    let mut l = new_loop();
    let mut out = Vec::new();
    l.sync_clock(T0);
    let name0 = l.driver().unwrap().robot().name.clone();
    l.handle(
        Command::RobotDescription("<robot name=\"x\"".into()),
        T0,
        &mut out,
    );
    assert_eq!(l.stats().description_failures, 1);
    assert_eq!(l.driver().unwrap().robot().name, name0);
    // A URDF without the link the towel hangs from cannot be used either.
    let no_palm = urdf_text().replace("right_palm", "right_paw");
    l.handle(Command::RobotDescription(no_palm), T0, &mut out);
    assert_eq!(l.stats().description_failures, 2);
    let renamed = urdf_text().replacen(&format!("name=\"{name0}\""), "name=\"from_topic\"", 1);
    assert_ne!(renamed, urdf_text());
    l.handle(Command::RobotDescription(renamed), T0, &mut out);
    assert_eq!(l.stats().descriptions_loaded, 1);
    assert_eq!(l.driver().unwrap().robot().name, "from_topic");
    let errors = out
        .iter()
        .filter(|o| matches!(o, Output::Log { text, .. } if text.contains("rejected")))
        .count();
    assert_eq!(errors, 2);
    // Still publishing.
    out.clear();
    run(&mut l, T0, T0 + 0.2, 0.01, &mut out);
    assert_eq!(frames(&out).len(), 7);
}

/// The live `wind` parameter: setting the constant wind of the flag scene to zero gives exactly
/// the run of the same scene written with zero wind, also after a reset (the scene the reset
/// rebuilds from carries the new wind); a scene without wind refuses it with a warning.
#[test]
fn live_wind_changes_the_flag_and_survives_reset() {
    let flag = || {
        Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/config/flag.yaml").as_ref())
            .expect("flag scene")
    };
    let mut calm = flag();
    calm.wind.as_mut().expect("flag has wind").velocity = drape::Vec3::ZERO;
    let run_for = |mut l: SimLoop, cmd: Option<Command>| {
        let mut out = Vec::new();
        l.sync_clock(T0);
        if let Some(c) = cmd {
            l.handle(c, T0, &mut out);
        }
        run(&mut l, T0, T0 + 0.5, 0.01, &mut out);
        let first = l.simulation().cloth.x.clone();
        l.handle(Command::Reset { id: 1 }, T0 + 0.5, &mut out);
        run(&mut l, T0 + 0.5, T0 + 1.0, 0.01, &mut out);
        (first, l.simulation().cloth.x.clone())
    };
    let windy = run_for(
        SimLoop::new(flag(), LoopConfig::default(), T0).unwrap(),
        None,
    );
    let set = run_for(
        SimLoop::new(flag(), LoopConfig::default(), T0).unwrap(),
        Some(Command::Wind([0.0; 3])),
    );
    let written = run_for(SimLoop::new(calm, LoopConfig::default(), T0).unwrap(), None);
    assert_ne!(windy.0, set.0, "the wind change moved nothing");
    assert_eq!(
        set.0, written.0,
        "live zero wind differs from a scene with zero wind"
    );
    assert_eq!(set.1, written.1, "the live wind did not survive the reset");

    let mut towel = new_loop();
    let mut out = Vec::new();
    towel.handle(Command::Wind([5.0, 0.0, 0.0]), T0, &mut out);
    assert!(
        out.iter()
            .any(|o| matches!(o, Output::Log { text, .. } if text.contains("names no wind"))),
        "{out:?}"
    );
}

fn towel(res: usize) -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/robot_towel.yaml");
    let mut scene = Scene::load(path.as_ref()).expect("robot_towel scene");
    scene.cloths[0].grid.resolution = [res, res];
    scene
}

fn shoulder(s: f64) -> Command {
    Command::Joints {
        stamp_ns: 0,
        input: JointInput {
            names: vec!["right_shoulder_pitch".into()],
            positions: vec![s],
            velocities: None,
        },
    }
}

fn frame_count(out: &[Output]) -> usize {
    out.iter()
        .filter(|o| matches!(o, Output::Frame { .. }))
        .count()
}

/// Publish instants fall on even steps (T0, T0 + 2 dt, ...). A changed command before an
/// odd step publishes right after that step instead of a step later; an unchanged one does
/// not; and the number of frames per second stays the rate.
#[test]
fn a_step_reaching_a_new_command_publishes_a_step_early() {
    let mut l = SimLoop::new(towel(6), LoopConfig::default(), T0).expect("loop");
    let dt = l.simulation().settings.dt;
    let mut out = Vec::new();
    l.sync_clock(T0);
    l.advance_to(T0, &mut out);
    assert_eq!(frame_count(&out), 1);
    // The scene's own pose, re-sent: nothing new to show, no early frame.
    let q = l.driver().expect("robot").joint_positions().clone();
    let j = l
        .driver()
        .unwrap()
        .robot()
        .joint_index("right_shoulder_pitch");
    let s0 = q.positions[j.expect("shoulder")];
    l.handle(shoulder(s0), T0 + 0.5 * dt, &mut out);
    l.advance_to(T0 + dt, &mut out);
    assert_eq!(frame_count(&out), 1, "unchanged command published early");
    l.advance_to(T0 + 2.0 * dt, &mut out);
    assert_eq!(frame_count(&out), 2);
    // A new pose before the odd step at T0 + 3 dt: out right after it.
    l.handle(shoulder(s0 + 0.05), T0 + 2.5 * dt, &mut out);
    l.advance_to(T0 + 3.0 * dt, &mut out);
    assert_eq!(
        frame_count(&out),
        3,
        "new pose not published after the step reaching it"
    );
    // The instant at T0 + 4 dt was taken: none there; the grid resumes at T0 + 6 dt.
    l.advance_to(T0 + 4.0 * dt, &mut out);
    assert_eq!(frame_count(&out), 3);
    let mut t = T0 + 4.0 * dt;
    while t < T0 + 1.0 - 1e-9 {
        t += 0.5 * dt;
        l.advance_to(t, &mut out);
    }
    // Instants T0, T0 + 1/30, ..., T0 + 1: 31 frames, one of them early.
    assert_eq!(frame_count(&out), 31);
}

/// A joint state the robot cannot reach within a step is reached at its joint's URDF velocity
/// limit: drape_bot's shoulder (2 rad/s) commanded 0.3 rad away moves 2 rad/s x dt each step
/// and arrives after 0.15 s, not at the end of the next step (as it does with the limits off).
#[test]
fn a_joint_state_jump_is_reached_at_the_joint_velocity_limit() {
    for limits in [true, false] {
        let cfg = LoopConfig {
            joint_velocity_limits: limits,
            ..LoopConfig::default()
        };
        let mut l = SimLoop::new(towel(6), cfg, T0).expect("loop");
        let dt = l.simulation().settings.dt;
        let mut out = Vec::new();
        l.sync_clock(T0);
        l.advance_to(T0, &mut out);
        let d = l.driver().expect("robot");
        let j = d.robot().joint_index("right_shoulder_pitch").unwrap();
        let v = d.robot().kinematics().joints()[j].velocity_limit.unwrap();
        assert_eq!(v, 2.0);
        let s0 = d.joint_positions().positions[j];
        l.handle(shoulder(s0 + 0.3), T0, &mut out);
        for k in 1..=12 {
            l.advance_to(T0 + k as f64 * dt, &mut out);
            let s = l.driver().unwrap().joint_positions().positions[j];
            let want = if limits {
                s0 + (v * k as f64 * dt).min(0.3)
            } else {
                s0 + 0.3
            };
            assert!(
                (s - want).abs() < 1e-9,
                "limits {limits}, step {k}: {s} against {want}"
            );
        }
    }
}

/// A tangle is not silent: two sheets built crossing each other (a state the fail-safe cannot
/// undo: the step starts intersecting) show in `/diagnostics` as WARN with the exact count of
/// intersecting triangle pairs and the pairs the fail-safe gave up on.
#[test]
fn a_tangled_cloth_is_reported_in_diagnostics() {
    let sheet = |name: &str, xyz: &str, rpy: &str| {
        format!(
            "  - name: {name}
    grid: {{ size: [0.3, 0.3], resolution: [8, 8], pose: {{ xyz: {xyz}, rpy: {rpy} }} }}
    pins: [ {{ region: top_left }}, {{ region: top_right }}, {{ region: bottom_left }}, {{ region: bottom_right }} ]
    material: {{ density: 0.2, stretch: 500.0, shear: 50.0, thickness: 0.004 }}
"
        )
    };
    let text = format!(
        "name: crossed
duration: 1.0
effects: [gravity, stretch, shear]
solver: {{ integrator: implicit, dt: 0.016666666666666666 }}
cloths:
{}{}collision: {{ mode: continuous, self_collision: true, count_self_intersections: true }}
",
        sheet("flat", "[0.0, 0.0, 0.5]", "[0.0, 0.0, 0.0]"),
        sheet(
            "upright",
            "[0.0, 0.0, 0.5]",
            "[1.5707963267948966, 0.0, 0.0]"
        ),
    );
    let scene = Scene::from_yaml(&text, "crossed.yaml").expect("scene");
    let mut l = SimLoop::new(scene, LoopConfig::default(), T0).expect("loop");
    let mut out = Vec::new();
    l.sync_clock(T0);
    run(&mut l, T0, T0 + 1.5, 0.01, &mut out);
    let d = diagnostics(&out);
    let last = d.last().expect("diagnostics");
    let s = &last.status[0];
    assert_eq!(
        s.level,
        drape::ros::msg::DiagnosticStatus::WARN,
        "{}",
        s.message
    );
    assert!(s.message.contains("cloth tangled"), "{}", s.message);
    let n: usize = value(last, "self_intersections").parse().expect("counted");
    assert!(n > 0);
    let stretch: f64 = value(last, "max_edge_stretch").parse().expect("a number");
    assert!(stretch.is_finite() && stretch >= 0.0, "{stretch}");
}
