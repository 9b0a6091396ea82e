//! Property: random joint-state streams (NaN, infinities, missing and extra names, duplicates,
//! empty and mismatched arrays, out-of-order stamps) through `joint_input` + `joint_stream` +
//! `RobotDriver` never panic and never produce a non-finite link pose or cloth state.

use drape::robot::{joint_stream, JointInput, JointSource, Robot, RobotDriver, UrdfOptions};
use drape::scene::Scene;
use proptest::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn robot() -> &'static Robot {
    static R: OnceLock<Robot> = OnceLock::new();
    R.get_or_init(|| {
        let options = UrdfOptions {
            use_ros_env: false,
            ..Default::default()
        };
        Robot::from_urdf_file(&root().join("urdf/drape_bot.urdf"), &options)
            .expect("bundled robot loads")
    })
}

/// Joint names: real ones (incl. fixed/mimic), unknown ones and the empty string.
fn name() -> impl Strategy<Value = String> {
    let mut pool: Vec<String> = robot()
        .kinematics()
        .joints()
        .iter()
        .map(|j| j.name.clone())
        .collect();
    pool.extend(["bogus".to_string(), String::new(), "head_pan ".to_string()]);
    prop::sample::select(pool)
}

/// Any f64 a sender might put on the wire, weighted toward the nasty ones.
fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -4.0..4.0f64,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(1e300),
        1 => Just(-1e300),
        1 => any::<f64>(),
    ]
}

fn message() -> impl Strategy<Value = (u64, JointInput)> {
    (
        0u64..20_000_000_000,
        prop::collection::vec(name(), 0..6),
        prop::collection::vec(value(), 0..6),
        prop::option::of(prop::collection::vec(value(), 0..6)),
    )
        .prop_map(|(ns, names, positions, velocities)| {
            (
                ns,
                JointInput {
                    names,
                    positions,
                    velocities,
                },
            )
        })
}

/// Messages that are valid except for their stamps, so some survive validation.
fn good_message() -> impl Strategy<Value = (u64, JointInput)> {
    let names = ["right_shoulder_pitch", "right_elbow", "right_wrist"];
    (0u64..20_000_000_000, prop::array::uniform3(-3.0..3.0f64)).prop_map(move |(ns, p)| {
        (
            ns,
            JointInput {
                names: names.iter().map(|s| s.to_string()).collect(),
                positions: p.to_vec(),
                velocities: None,
            },
        )
    })
}

fn stream() -> impl Strategy<Value = Vec<(u64, JointInput)>> {
    prop::collection::vec(prop_oneof![message(), good_message()], 0..40)
}

/// Case count: the bounded default, or `PROPTEST_CASES` for a longer run.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(200), ..ProptestConfig::default() })]

    #[test]
    fn random_joint_streams_never_give_non_finite_link_poses(
        msgs in stream(),
        times in prop::collection::vec(-5.0..30.0f64, 1..8),
    ) {
        let r = robot();
        let n = msgs.len();
        let (stream, dropped) = joint_stream(r, msgs.clone());
        prop_assert_eq!(stream.len() + dropped, n);
        prop_assert!(stream.windows(2).all(|w| w[0].0 <= w[1].0), "stream goes back in time");
        for (_, q) in &stream {
            prop_assert!(q.positions.iter().all(|p| p.is_finite()));
        }
        let driver = RobotDriver::new(r.clone(), String::new(), JointSource::Stream(stream));
        for t in times {
            let q = driver.positions_at(t);
            for pose in r.link_poses(&q) {
                prop_assert!(pose.is_finite(), "non-finite link pose at t = {}", t);
            }
        }
        // Each message applied alone: rejected whole (state untouched) or applied finite.
        let kin = r.kinematics();
        let mut q = r.zero_positions();
        for (_, m) in &msgs {
            let before = q.clone();
            match m.apply(kin, &mut q) {
                Ok(()) => prop_assert!(q.positions.iter().all(|p| p.is_finite())),
                Err(_) => prop_assert_eq!(&q, &before),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(6), ..ProptestConfig::default() })]

    /// The whole pipeline: a random stream drives the towel scene's robot; the cloth stays finite.
    #[test]
    fn random_joint_streams_drive_a_cloth_scene_finite(msgs in stream()) {
        let mut scene = Scene::load(&root().join("config/robot_towel.yaml")).expect("scene loads");
        scene.cloths[0].grid.resolution = [6, 6];
        if let Some(r) = scene.robot.as_mut() {
            for a in &mut r.attach {
                if let Some(near) = a.near.as_mut() {
                    near.radius = 0.09;
                }
            }
        }
        let (mut sim, driver) = scene.build_with_robot().expect("scene builds");
        let mut driver = driver.expect("scene has a robot");
        let (stream, _) = joint_stream(driver.robot(), msgs);
        driver.set_source(JointSource::Stream(stream), 0.0);
        for _ in 0..20 {
            let t = sim.time() + sim.settings.dt;
            driver.advance(&mut sim, t);
            prop_assert!(driver.link_poses().iter().all(|p| p.is_finite()));
            if sim.step().is_err() {
                break;
            }
            prop_assert!(sim.cloth.x.iter().chain(&sim.cloth.v).all(|p| p.is_finite()));
        }
    }
}
