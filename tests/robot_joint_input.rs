//! Joint inputs are validated whole (bad updates leave the state untouched) and trajectories
//! interpolate linearly between points.

use drape::robot::{
    JointInput, JointInputError, JointTrajectory, Robot, TrajectoryError, UrdfOptions,
};
use std::path::Path;

fn robot() -> Robot {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/drape_bot.urdf");
    let options = UrdfOptions {
        use_ros_env: false,
        ..Default::default()
    };
    Robot::from_urdf_file(&p, &options).unwrap()
}

fn input(names: &[&str], positions: &[f64]) -> JointInput {
    JointInput {
        names: names.iter().map(|s| s.to_string()).collect(),
        positions: positions.to_vec(),
        velocities: None,
    }
}

#[test]
fn valid_input_is_applied_by_name() {
    let robot = robot();
    let mut q = robot.zero_positions();
    input(&["left_elbow", "head_pan"], &[-1.0, 0.5])
        .apply(robot.kinematics(), &mut q)
        .unwrap();
    assert_eq!(q.positions[robot.joint_index("left_elbow").unwrap()], -1.0);
    assert_eq!(q.positions[robot.joint_index("head_pan").unwrap()], 0.5);
    // Empty velocity arrays mean "not provided" in ROS.
    let mut with_v = input(&["head_pan"], &[0.1]);
    with_v.velocities = Some(vec![]);
    with_v.apply(robot.kinematics(), &mut q).unwrap();
}

#[test]
fn bad_inputs_are_rejected_and_leave_state_untouched() {
    let robot = robot();
    let kin = robot.kinematics();
    let mut q = robot.zero_positions();
    q.positions[robot.joint_index("head_pan").unwrap()] = 0.3;
    let before = q.clone();
    let cases: Vec<(JointInput, JointInputError)> = vec![
        (
            input(&["head_pan", "wrist_x"], &[1.0, 2.0]),
            JointInputError::UnknownJoint("wrist_x".into()),
        ),
        (
            input(&["head_pan", "left_elbow"], &[1.0, f64::NAN]),
            JointInputError::NotFinite {
                name: "left_elbow".into(),
                what: "position",
                value: f64::NAN,
            },
        ),
        (
            input(&["head_pan", "left_elbow"], &[1.0]),
            JointInputError::LengthMismatch {
                names: 2,
                values: 1,
                what: "positions",
            },
        ),
        (input(&[], &[]), JointInputError::Empty),
        (
            input(&["head_pan", "head_pan"], &[1.0, 1.0]),
            JointInputError::Duplicate("head_pan".into()),
        ),
        (
            JointInput {
                velocities: Some(vec![1.0, 2.0]),
                ..input(&["head_pan"], &[1.0])
            },
            JointInputError::LengthMismatch {
                names: 1,
                values: 2,
                what: "velocities",
            },
        ),
        (
            JointInput {
                velocities: Some(vec![f64::INFINITY]),
                ..input(&["head_pan"], &[1.0])
            },
            JointInputError::NotFinite {
                name: "head_pan".into(),
                what: "velocity",
                value: f64::INFINITY,
            },
        ),
    ];
    for (inp, want) in cases {
        let err = inp.apply(kin, &mut q).unwrap_err();
        // NaN != NaN, so compare the rendered messages.
        assert_eq!(err.to_string(), want.to_string());
        assert_eq!(q, before, "state changed by rejected input {inp:?}");
    }
}

const SCENE_SNIPPET: &str = "
names: [head_pan, right_finger_a_joint]
points:
  - {t: 0.0, positions: [0.0, 0.0]}
  - {t: 2.0, positions: [1.0, 0.04]}
  - {t: 3.0, positions: [-1.0, 0.04]}
";

#[test]
fn trajectory_parses_validates_and_interpolates() {
    let robot = robot();
    let traj: JointTrajectory = serde_yaml_ng::from_str(SCENE_SNIPPET).unwrap();
    traj.validate(robot.kinematics()).unwrap();
    assert_eq!(traj.positions_at(-1.0), vec![0.0, 0.0]);
    assert_eq!(traj.positions_at(0.5), vec![0.25, 0.01]);
    assert_eq!(traj.positions_at(2.0), vec![1.0, 0.04]);
    assert_eq!(traj.positions_at(2.75), vec![-0.5, 0.04]);
    assert_eq!(traj.positions_at(10.0), vec![-1.0, 0.04]);
    let mut q = robot.zero_positions();
    traj.input_at(1.0)
        .apply(robot.kinematics(), &mut q)
        .unwrap();
    assert_eq!(q.positions[robot.joint_index("head_pan").unwrap()], 0.5);
}

#[test]
fn bad_trajectories_name_the_point() {
    let robot = robot();
    let kin = robot.kinematics();
    let mut traj: JointTrajectory = serde_yaml_ng::from_str(SCENE_SNIPPET).unwrap();
    traj.points[2].t = 2.0;
    assert_eq!(
        traj.validate(kin),
        Err(TrajectoryError::Time { index: 2, t: 2.0 })
    );
    let mut traj: JointTrajectory = serde_yaml_ng::from_str(SCENE_SNIPPET).unwrap();
    traj.points[1].positions.pop();
    assert!(matches!(
        traj.validate(kin),
        Err(TrajectoryError::Length { index: 1, .. })
    ));
    let mut traj: JointTrajectory = serde_yaml_ng::from_str(SCENE_SNIPPET).unwrap();
    traj.names[0] = "neck_yaw".into();
    let err = traj.validate(kin).unwrap_err();
    assert!(
        err.to_string().contains("neck_yaw") && err.to_string().contains("point 0"),
        "{err}"
    );
    assert!(
        serde_yaml_ng::from_str::<JointTrajectory>("names: []\npoints: []\nextra: 1\n").is_err()
    );
    let empty: JointTrajectory = serde_yaml_ng::from_str("names: []\npoints: []\n").unwrap();
    assert_eq!(empty.validate(kin), Err(TrajectoryError::NoPoints));
}

/// A segment faster than a joint's URDF velocity limit is found, with the factor; a
/// trajectory within or at the limits has none. drape_bot's elbow (2.5 rad/s): 1 rad in 0.2 s
/// is 2x.
#[test]
fn a_trajectory_faster_than_a_velocity_limit_is_found() {
    let robot = robot();
    let kin = robot.kinematics();
    let traj = |t1: f64| -> JointTrajectory {
        serde_yaml_ng::from_str(&format!(
            "names: [head_pan, right_elbow]
points:
  - {{ t: 0.0, positions: [0.0, 0.0] }}
  - {{ t: 1.0, positions: [0.1, 0.0] }}
  - {{ t: {t1}, positions: [0.1, -1.0] }}"
        ))
        .unwrap()
    };
    let fast = traj(1.2);
    fast.validate(kin).unwrap();
    let o = fast.overspeed(kin).expect("2x the elbow's limit");
    assert_eq!(o.joint, "right_elbow");
    assert_eq!((o.from_t, o.to_t, o.limit), (1.0, 1.2, 2.5));
    assert!((o.factor - 2.0).abs() < 1e-9, "{}", o.factor);
    assert!(o.to_string().contains("right_elbow"), "{o}");
    assert_eq!(
        traj(1.5).overspeed(kin),
        None,
        "1 rad in 0.5 s: within 2.5 rad/s"
    );
    assert_eq!(
        traj(1.4).overspeed(kin),
        None,
        "1 rad in 0.4 s: at the limit"
    );
}
