//! The bundled robot scenes: attachments follow their links exactly, cloth stays out of the
//! links, the cloth moves with the robot, and `drape record` bags carry the robot. Link poses are
//! checked against FK from an independently loaded robot, and clearance against analytic
//! distances to the URDF shapes (URDF axes, not the obstacles' parry axes).

use drape::cloth::Kinematic;
use drape::robot::{Geometry, JointPositions, Robot, UrdfOptions};
use drape::scene::Scene;
use drape::sim::Simulation;
use drape::{Pose, Vec3};
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn load(name: &str) -> Scene {
    Scene::load(&root().join("config").join(name)).expect("bundled scene loads")
}

fn urdf_robot() -> Robot {
    Robot::from_urdf_file(&root().join("urdf/drape_bot.urdf"), &UrdfOptions::default())
        .expect("bundled robot loads")
}

/// Joint positions the scene's trajectory asks for at `t`, applied on the zero configuration.
fn scene_q(scene: &Scene, robot: &Robot, t: f64) -> JointPositions {
    let mut q = robot.zero_positions();
    let tr = scene.robot.as_ref().and_then(|r| r.trajectory.as_ref());
    if let Some(tr) = tr {
        tr.input_at(t).apply(robot.kinematics(), &mut q).unwrap();
    }
    q
}

/// (vertex, link, offset in the link frame) of every link-attached vertex, from the t = 0 state.
fn attachments(sim: &Simulation, robot: &Robot, poses0: &[Pose]) -> Vec<(usize, usize, Vec3)> {
    sim.cloth
        .kinematic
        .iter()
        .filter_map(|(i, k)| match k {
            Kinematic::Attached { frame, .. } => {
                let name = sim.frames.names[*frame].strip_prefix("robot:")?;
                let link = robot.link_index(name)?;
                let i = *i as usize;
                Some((
                    i,
                    link,
                    poses0[link].inverse_transform_point(sim.cloth.x[i]),
                ))
            }
            Kinematic::Pinned(_) => None,
        })
        .collect()
}

#[test]
fn attached_vertices_stay_exactly_on_their_links() {
    let robot = urdf_robot();
    for name in ["robot_towel.yaml", "robot_cape.yaml"] {
        let scene = load(name);
        let (mut sim, driver) = scene.build_with_robot().unwrap();
        let mut driver = driver.expect("scene has a robot");
        let poses0 = robot.link_poses(&scene_q(&scene, &robot, 0.0));
        let att = attachments(&sim, &robot, &poses0);
        assert!(
            att.len() >= 2,
            "{name}: only {} attached vertices",
            att.len()
        );
        let links: std::collections::HashSet<_> = att.iter().map(|a| a.1).collect();
        // The towel hangs from the moving palm, the cape from the still torso.
        let moving = name == "robot_towel.yaml";
        if !moving {
            assert_eq!(links.len(), 1, "the cape hangs from the torso alone");
        }
        let mut worst: f64 = 0.0;
        let mut moved: f64 = 0.0;
        for _ in 0..60 {
            let t = sim.time() + sim.settings.dt;
            driver.advance(&mut sim, t);
            sim.step().unwrap();
            let poses = robot.link_poses(&scene_q(&scene, &robot, t));
            for &(i, link, local) in &att {
                let want = poses[link].transform_point(local);
                worst = worst.max((sim.cloth.x[i] - want).length());
                moved = moved.max((want - poses0[link].transform_point(local)).length());
            }
        }
        assert!(
            worst < 1e-6,
            "{name}: attached vertex off its link by {worst} m"
        );
        assert!(
            !moving || moved > 0.05,
            "{name}: the attachments barely moved ({moved} m)"
        );
    }
}

/// Signed distance from a point in the shape's frame to a URDF shape (z-axis cylinders).
fn urdf_distance(g: &Geometry, p: Vec3) -> Option<f64> {
    Some(match g {
        Geometry::Sphere { radius } => p.length() - radius,
        Geometry::Box { half_extents } => {
            let q = p.abs() - *half_extents;
            q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
        }
        Geometry::Cylinder { radius, length } => {
            let r = (p.x * p.x + p.y * p.y).sqrt() - radius;
            let h = p.z.abs() - 0.5 * length;
            let out = (r.max(0.0).powi(2) + h.max(0.0).powi(2)).sqrt();
            out + r.max(h).min(0.0)
        }
        Geometry::Capsule { radius, length } => {
            let z = p.z.clamp(-0.5 * length, 0.5 * length);
            (p - Vec3::new(0.0, 0.0, z)).length() - radius
        }
        Geometry::Mesh(_) => return None,
    })
}

/// Runs a scene for `frames` frames and returns the deepest penetration into the links'
/// thickness layer (analytic, primitive shapes) as a fraction of the thickness, and the largest
/// reported by the collision stage (m).
fn penetration(name: &str, frames: usize) -> (f64, f64) {
    let robot = urdf_robot();
    let scene = load(name);
    let thickness = scene.cloths[0].material.thickness;
    let (mut sim, driver) = scene.build_with_robot().unwrap();
    let mut driver = driver.unwrap();
    let kinematic: std::collections::HashSet<u32> =
        sim.cloth.kinematic.iter().map(|(i, _)| *i).collect();
    let (mut worst, mut reported): (f64, f64) = (0.0, 0.0);
    let mut contacts = 0;
    for _ in 0..frames {
        let t = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, t);
        let m = sim.step().unwrap();
        reported = reported.max(m.deepest_penetration);
        contacts += m.contacts;
        let poses = robot.link_poses(&scene_q(&scene, &robot, t));
        for (link, shapes) in robot.collision_shapes().iter().enumerate() {
            for (local, g) in shapes {
                let pose = poses[link].mul(local);
                for (i, x) in sim.cloth.x.iter().enumerate() {
                    if kinematic.contains(&(i as u32)) {
                        continue;
                    }
                    if let Some(d) = urdf_distance(g, pose.inverse_transform_point(*x)) {
                        worst = worst.max((thickness - d) / thickness);
                    }
                }
            }
        }
    }
    assert!(contacts > 0, "{name}: the cloth never touched the robot");
    (worst, reported)
}

#[test]
fn cloth_draped_on_the_moving_arm_stays_out_of_it() {
    // 2 s: the cloth lands on the arm (1 s) and the arm lifts and turns through it.
    let (worst, reported) = penetration("robot_drape_arm.yaml", 120);
    assert!(
        worst < 0.1,
        "penetration {:.1}% of thickness",
        worst * 100.0
    );
    assert!(reported < 0.1 * 0.008, "stage reports {reported} m");
}

#[test]
fn cape_stays_out_of_the_swinging_arms() {
    let (worst, reported) = penetration("robot_cape.yaml", 120);
    assert!(
        worst < 0.1,
        "penetration {:.1}% of thickness",
        worst * 100.0
    );
    assert!(reported < 0.1 * 0.008, "stage reports {reported} m");
}

/// robot_cape.yaml at 48x48 with self-collision on (its full-resolution hard case,
/// `self_cape_under_swinging_arms`, run here to t = 2.6 s): at t = 2.45-2.5 s the left forearm
/// sweeps through the cape's hem at about 0.7 m/s, carrying the hem held against it by
/// friction. That friction is solved with the cloth (a drag towards the forearm's velocity), so
/// the hem's neighbours follow within the same solve. Applied by the collision stage after the
/// solve, it would move each held vertex alone by up to its whole slip over the substep (a good
/// part of the spacing) and stretch the hem's edges in every substep of the sweep. Bound: the
/// case's own, the impact stretch bound at the arms' 1.2 m/s plus 10 %
/// (`src/hard/self_contact.rs`, `cape_swinging`), on every frame.
#[test]
fn the_forearm_sweeping_the_cape_drags_its_hem_without_stretching_it() {
    use drape::hard::{catalogue, Resolution};
    let (_, build) = catalogue()
        .into_iter()
        .find(|(n, _)| *n == "self_cape_under_swinging_arms")
        .expect("the hard case");
    let case = build(Resolution::Full).expect("builds");
    let bound = case.criteria.max_stretch.expect("a stretch bound");
    let (mut sim, mut driver) = (case.sim, case.driver.expect("robot scene"));
    let dt = sim.settings.dt;
    let mut worst = (0.0f64, 0.0);
    while sim.time() < 2.6 {
        let t = sim.time() + dt;
        driver.advance(&mut sim, t);
        sim.step().expect("no divergence");
        let stretch = 1.0 + sim.cloth.max_edge_stretch();
        if stretch > worst.0 {
            worst = (stretch, sim.time());
        }
    }
    assert!(
        worst.0 <= bound,
        "largest edge {:.3}x rest at t = {:.3} s (bound {bound:.3})",
        worst.0,
        worst.1
    );
}

#[test]
fn towel_moves_with_the_arm() {
    let scene = load("robot_towel.yaml");
    let (mut driven, driver) = scene.build_with_robot().unwrap();
    let mut driver = driver.unwrap();
    let mut still = scene.build().unwrap();
    let held = driven.cloth.kinematic[0].0 as usize;
    let mut farthest: f64 = 0.0;
    for _ in 0..90 {
        let t = driven.time() + driven.settings.dt;
        driver.advance(&mut driven, t);
        driven.step().unwrap();
        still.step().unwrap();
        let hand = driven.cloth.x[held];
        farthest = driven
            .cloth
            .x
            .iter()
            .map(|x| (*x - hand).length())
            .fold(farthest, f64::max);
    }
    let mean = |s: &Simulation| s.cloth.x.iter().sum::<Vec3>() / s.cloth.len() as f64;
    let shift = (mean(&driven) - mean(&still)).length();
    assert!(
        shift > 0.1,
        "towel moved only {shift} m more than with a still arm"
    );
    // Still hanging from the hand: no vertex farther from a held one than the diagonal + 10%.
    let diagonal = 0.4 * 2f64.sqrt();
    assert!(
        farthest < 1.1 * diagonal,
        "a vertex is {farthest} m from the held corner"
    );
}

fn scene_copy(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(root().join("config").join(name)).unwrap();
    let urdf = root().join("urdf/drape_bot.urdf");
    let text = text.replace("../urdf/drape_bot.urdf", &urdf.display().to_string());
    let path = dir.join(name);
    std::fs::write(&path, edit(text)).unwrap();
    path
}

#[test]
fn unknown_joint_in_the_trajectory_is_a_key_path_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = scene_copy(dir.path(), "robot_towel.yaml", |t| {
        t.replacen("right_elbow,", "right_elbo,", 1)
    });
    let scene = Scene::load(&path).unwrap();
    let err = scene
        .build_with_robot()
        .err()
        .expect("bad joint name fails");
    // The joint is in the cause (the trajectory's error), as the command line prints it.
    let msg = drape::input::error_line(&err);
    assert!(msg.contains("robot.trajectory.names[1]"), "{msg}");
    assert!(msg.contains("right_elbo"), "{msg}");

    // A link attachment to a missing link names its key too.
    let path = scene_copy(dir.path(), "robot_towel.yaml", |t| {
        t.replacen("link: right_palm", "link: right_plam", 1)
    });
    let msg = Scene::load(&path)
        .unwrap()
        .build_with_robot()
        .err()
        .expect("bad link fails")
        .to_string();
    assert!(msg.contains("robot.attach[0].link"), "{msg}");
}

#[test]
fn robot_section_rejects_unknown_keys() {
    let dir = tempfile::tempdir().unwrap();
    let path = scene_copy(dir.path(), "robot_towel.yaml", |t| {
        t.replacen("  attach:\n", "  atach:\n", 1)
    });
    let msg = drape::input::error_chain(&Scene::load(&path).expect_err("typo fails"));
    assert!(msg.contains("atach"), "{msg}");
}

#[cfg(feature = "ros")]
mod bags {
    use super::*;
    use drape::ros::msg::{Header, JointState, Time};
    use drape::ros::{read_joint_states, BagWriter, Distro};
    use serde_json::Value;
    use std::process::Command;

    fn summarize(bag: &Path) -> Value {
        let out = Command::new("python3")
            .arg(root().join("tests/py/summarize_bag.py"))
            .arg(bag)
            .output()
            .expect("python3 runs");
        assert!(
            out.status.success(),
            "summarize_bag.py: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    }

    fn record(scene: &Path, bag: &Path, extra: &[&str]) {
        let out = Command::new(env!("CARGO_BIN_EXE_drape"))
            .args(["record", "--quiet", "--scene"])
            .arg(scene)
            .arg("--out")
            .arg(bag)
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "drape record: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }

    #[test]
    fn towel_bag_carries_the_robot() {
        let dir = tempfile::tempdir().unwrap();
        let scene = scene_copy(dir.path(), "robot_towel.yaml", |t| t);
        let bag = dir.path().join("towel.mcap");
        record(&scene, &bag, &["--duration", "0.5"]);
        let s = summarize(&bag);
        // 30 Hz for 0.5 s: t = 0, 1/30, ..., 0.5.
        assert_eq!(s["/tf"]["type"], "tf2_msgs/msg/TFMessage");
        assert_eq!(s["/tf"]["count"], 16);
        assert_eq!(s["/joint_states"]["type"], "sensor_msgs/msg/JointState");
        assert_eq!(s["/joint_states"]["count"], 16);
        assert_eq!(s["/robot_description"]["type"], "std_msgs/msg/String");
        assert_eq!(s["/robot_description"]["count"], 1);
        assert_eq!(s["/drape/points"]["frame_id"], "base_link");

        // /robot_description is offered transient-local (durability 1) so it replays latched.
        let bytes = std::fs::read(&bag).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let desc = summary
            .channels
            .values()
            .find(|c| c.topic == "/robot_description")
            .unwrap();
        let qos = &desc.metadata["offered_qos_profiles"];
        assert!(qos.contains("durability: 1"), "{qos}");
        let tf = summary
            .channels
            .values()
            .find(|c| c.topic == "/tf")
            .unwrap();
        assert!(tf.metadata["offered_qos_profiles"].contains("durability: 2"));
    }

    #[test]
    fn joints_from_a_bag_drive_the_arm() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("joints.mcap");
        // 1 s ramp of the shoulder from -1.5 to -0.5 rad at 50 Hz, starting at t = 7 s of the
        // bag's clock, with an unknown joint and a NaN message that must be dropped.
        let t0 = 7_000_000_000u64;
        let mut w = BagWriter::create(&input).unwrap();
        let topic = w
            .add_topic::<JointState>("/joint_states", Distro::Jazzy, None)
            .unwrap();
        let msg = |names: &[&str], pos: Vec<f64>, ns: u64| JointState {
            header: Header::new(Time::from_nanos(ns), ""),
            name: names.iter().map(|s| s.to_string()).collect(),
            position: pos,
            ..JointState::default()
        };
        for k in 0..=50u64 {
            let ns = t0 + k * 20_000_000;
            let q = -1.5 + k as f64 / 50.0;
            w.write(topic, ns, &msg(&["right_shoulder_pitch"], vec![q], ns))
                .unwrap();
            if k == 20 {
                w.write(topic, ns + 1, &msg(&["no_such_joint"], vec![0.0], ns + 1))
                    .unwrap();
                let nan = msg(&["right_shoulder_pitch"], vec![f64::NAN], ns + 2);
                w.write(topic, ns + 2, &nan).unwrap();
            }
        }
        w.finish().unwrap();

        let scene = scene_copy(dir.path(), "robot_towel.yaml", |t| t);
        let bag = dir.path().join("out.mcap");
        let input_arg = input.display().to_string();
        record(&scene, &bag, &["--duration", "1.0", "--joints", &input_arg]);
        let states = read_joint_states(&bag).unwrap();
        assert_eq!(states.len(), 31);
        let robot = urdf_robot();
        let j = robot.joint_index("right_shoulder_pitch").unwrap();
        let kin_names: Vec<_> = states[0].1.name.clone();
        let col = kin_names
            .iter()
            .position(|n| n == &robot.kinematics().joints()[j].name)
            .unwrap();
        for (ns, s) in &states {
            let t = *ns as f64 * 1e-9;
            let want = -1.5 + t; // the bag's ramp, not the scene's trajectory
            let got = s.position[col];
            assert!((got - want).abs() < 1e-9, "t = {t}: {got} vs {want}");
        }
    }
}

/// A link that stopped is a still obstacle again: after the arm jumps and holds, each link's
/// obstacle ends every frame exactly on its target, so the next frame sees no motion (no fast-
/// contact test, no moving-contact springs) however fast the flung towel moves past it. The
/// interpolated end pose used to differ from the target by round-off, and the held arm kept
/// splitting the steps after a jump (3 splits and 3 refusals per frame at 64x64).
#[test]
fn a_link_that_stopped_is_still_in_the_next_frame() {
    use drape::robot::JointSource;
    let mut scene = load("robot_towel.yaml");
    scene.cloths[0].grid.resolution = [16, 16];
    scene.solver.guard.max_contact_split_levels = Some(2);
    let (mut sim, driver) = scene.build_with_robot().unwrap();
    let mut driver = driver.unwrap();
    let j = driver.robot().joint_index("right_shoulder_pitch").unwrap();
    let dt = sim.settings.dt;
    let mut q = driver.joint_positions().clone();
    let mut after_jump = (0u32, 0u32);
    let mut held = Vec::new();
    for k in 0..8 {
        let t = sim.time();
        let q0 = q.clone();
        if k == 1 {
            q.positions[j] += 0.3;
        }
        driver.set_source(JointSource::Stream(vec![(t, q0), (t + dt, q.clone())]), t);
        driver.advance(&mut sim, t + dt);
        let m = sim.step().unwrap();
        let poses: Vec<Pose> = (sim.collision().unwrap().obstacles().iter())
            .map(|o| o.pose)
            .collect();
        if k == 1 {
            held = poses;
        } else if k > 1 {
            assert!(poses == held, "frame {k}: a held link's obstacle drifted");
        }
        if k >= 2 {
            after_jump.0 += m.contact_splits;
            after_jump.1 += m.contact_splits_refused;
        }
        if k == 1 {
            assert!(
                m.max_speed > 1.0,
                "the jump flings the towel ({} m/s)",
                m.max_speed
            );
        }
    }
    assert_eq!(
        after_jump,
        (0, 0),
        "splits and refusals while the arm holds still"
    );
}
