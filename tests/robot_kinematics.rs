//! Forward kinematics against hand-computed poses: planar arm, prismatic with rotated origin,
//! mimic chains, limit clamping, free joints; and tree validation errors.

use drape::robot::{Robot, RobotError, TreeError, UrdfOptions};
use drape::{Pose, Vec3};
use glam::DQuat;

const TOL: f64 = 1e-12;

fn load(xml: &str) -> Robot {
    Robot::from_urdf_str(xml, None, &UrdfOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn links(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!(r#"<link name="{n}"/>"#))
        .collect()
}

fn joint(
    name: &str,
    ty: &str,
    parent: &str,
    child: &str,
    xyz: &str,
    rpy: &str,
    extra: &str,
) -> String {
    format!(
        r#"<joint name="{name}" type="{ty}"><parent link="{parent}"/><child link="{child}"/>
           <origin xyz="{xyz}" rpy="{rpy}"/>{extra}</joint>"#
    )
}

const L1: f64 = 0.4;
const L2: f64 = 0.3;

fn planar_arm() -> Robot {
    let lim = r#"<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>"#;
    load(&format!(
        r#"<robot name="arm">{}{}{}{}</robot>"#,
        links(&["base", "l1", "l2", "tip"]),
        joint("j1", "revolute", "base", "l1", "0 0 0", "0 0 0", lim),
        joint(
            "j2",
            "revolute",
            "l1",
            "l2",
            &format!("{L1} 0 0"),
            "0 0 0",
            lim
        ),
        joint(
            "tip_fixed",
            "fixed",
            "l2",
            "tip",
            &format!("{L2} 0 0"),
            "0 0 0",
            ""
        ),
    ))
}

#[test]
fn two_link_planar_arm_matches_closed_form() {
    let robot = planar_arm();
    let tip = robot.link_index("tip").unwrap();
    let (j1, j2) = (
        robot.joint_index("j1").unwrap(),
        robot.joint_index("j2").unwrap(),
    );
    for &(a, b) in &[(0.0, 0.0), (0.5, -1.2), (2.9, 2.9), (-1.0, 0.3)] {
        let mut q = robot.zero_positions();
        q.positions[j1] = a;
        q.positions[j2] = b;
        let p = robot.link_poses(&q)[tip];
        let want = Vec3::new(
            L1 * a.cos() + L2 * (a + b).cos(),
            L1 * a.sin() + L2 * (a + b).sin(),
            0.0,
        );
        assert!(
            (p.translation - want).length() < TOL,
            "{a} {b}: {} vs {want}",
            p.translation
        );
        let yaw = DQuat::from_rotation_z(a + b);
        assert!(p.rotation.angle_between(yaw) < 1e-7, "{a} {b}");
        assert_eq!(
            robot.link_poses(&q)[robot.link_index("base").unwrap()],
            Pose::IDENTITY
        );
    }
}

#[test]
fn prismatic_axis_is_expressed_in_the_rotated_joint_frame() {
    let robot = load(&format!(
        r#"<robot name="p">{}{}</robot>"#,
        links(&["a", "b"]),
        joint(
            "slide",
            "prismatic",
            "a",
            "b",
            "1 0 0",
            "0 0 1.5707963267948966",
            r#"<axis xyz="2 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/>"#
        ),
    ));
    let mut q = robot.zero_positions();
    q.positions[0] = 0.25;
    let p = robot.link_poses(&q)[1];
    // Axis normalised to x, then yawed 90 degrees: motion along parent +y.
    assert!(
        (p.translation - Vec3::new(1.0, 0.25, 0.0)).length() < TOL,
        "{}",
        p.translation
    );
}

fn gripper(mimic_b: &str, mimic_c: &str) -> Robot {
    let lim = r#"<limit lower="0" upper="0.04" effort="1" velocity="1"/>"#;
    load(&format!(
        r#"<robot name="g">{}{}{}{}</robot>"#,
        links(&["palm", "a", "b", "c"]),
        joint(
            "ja",
            "prismatic",
            "palm",
            "a",
            "0 0 0",
            "0 0 0",
            &format!(r#"<axis xyz="0 1 0"/>{lim}"#)
        ),
        joint(
            "jb",
            "prismatic",
            "palm",
            "b",
            "0 0 0",
            "0 0 0",
            &format!(r#"<axis xyz="0 -1 0"/>{lim}{mimic_b}"#)
        ),
        joint(
            "jc",
            "continuous",
            "palm",
            "c",
            "0 0 0",
            "0 0 0",
            &format!(r#"<axis xyz="1 0 0"/>{mimic_c}"#)
        ),
    ))
}

#[test]
fn mimic_joints_follow_their_source_through_chains() {
    let robot = gripper(
        r#"<mimic joint="ja" multiplier="-2" offset="0.1"/>"#,
        r#"<mimic joint="jb" multiplier="3" offset="0.5"/>"#,
    );
    let mut q = robot.zero_positions();
    q.positions[0] = 0.03;
    q.positions[1] = 99.0; // ignored: jb is a mimic
    q.positions[2] = -99.0; // ignored: jc is a mimic
    let poses = robot.link_poses(&q);
    let vb = -2.0 * 0.03 + 0.1;
    assert!((poses[2].translation - Vec3::new(0.0, -vb, 0.0)).length() < TOL);
    let vc = 3.0 * vb + 0.5;
    assert!(poses[3].rotation.angle_between(DQuat::from_rotation_x(vc)) < 1e-7);
    let m = robot.kinematics().joints()[2].mimic.unwrap();
    assert_eq!(m.joint, 0, "chain resolved to the independent joint");
    let names: Vec<_> = robot
        .kinematics()
        .actuated_joints()
        .map(|(_, j)| j.name.as_str())
        .collect();
    assert_eq!(names, ["ja"]);
}

#[test]
fn limits_are_clamped_and_reported_continuous_is_not() {
    let robot = gripper("", "");
    let mut q = robot.zero_positions();
    q.positions[0] = 0.5; // above 0.04
    q.positions[1] = -0.01; // below 0
    q.positions[2] = 10.0; // continuous: any angle
    let mut out = Vec::new();
    let report = robot.link_poses_into(&q, &mut out);
    assert_eq!(report.clamped, vec![0, 1]);
    assert!((out[1].translation - Vec3::new(0.0, 0.04, 0.0)).length() < TOL);
    assert!(out[2].translation.length() < TOL);
    assert!(out[3].rotation.angle_between(DQuat::from_rotation_x(10.0)) < 1e-7);
    q.positions[0] = 0.02;
    q.positions[1] = 0.0;
    assert!(robot.link_poses_into(&q, &mut out).is_clean());
}

#[test]
fn free_joints_use_supplied_pose_or_identity_and_report() {
    let robot = load(&format!(
        r#"<robot name="f">{}{}</robot>"#,
        links(&["world", "body"]),
        joint("free", "floating", "world", "body", "0 0 1", "0 0 0", ""),
    ));
    let mut q = robot.zero_positions();
    let mut out = Vec::new();
    let report = robot.link_poses_into(&q, &mut out);
    assert_eq!(report.free_defaulted, vec![0]);
    assert!((out[1].translation - Vec3::Z).length() < TOL);
    let mut map = std::collections::HashMap::new();
    map.insert(
        "free".to_string(),
        Pose::from_xyz_rpy([1.0, 0.0, 0.0], [0.0, 0.0, 0.3]),
    );
    drape::robot::apply_free_poses(robot.kinematics(), &map, &mut q).unwrap();
    let mut bad = map.clone();
    bad.insert("nope".to_string(), Pose::IDENTITY);
    assert!(drape::robot::apply_free_poses(robot.kinematics(), &bad, &mut q.clone()).is_err());
    let report = robot.link_poses_into(&q, &mut out);
    assert!(report.is_clean());
    assert!((out[1].translation - Vec3::new(1.0, 0.0, 1.0)).length() < TOL);
}

#[test]
fn fk_reuses_the_output_buffer() {
    let robot = planar_arm();
    let q = robot.zero_positions();
    let mut out = Vec::new();
    robot.link_poses_into(&q, &mut out);
    let ptr = out.as_ptr();
    robot.link_poses_into(&q, &mut out);
    assert_eq!(ptr, out.as_ptr());
}

#[test]
fn joint_positions_lerp_interpolates_between_states() {
    let robot = planar_arm();
    let mut a = robot.zero_positions();
    let mut b = robot.zero_positions();
    a.positions[0] = 0.2;
    b.positions[0] = 1.0;
    let mid = a.lerp(&b, 0.25);
    assert!((mid.positions[0] - 0.4).abs() < TOL);
}

fn tree_err(xml: &str) -> TreeError {
    match Robot::from_urdf_str(xml, None, &UrdfOptions::default()) {
        Err(RobotError::Tree { source, .. }) => source,
        other => panic!("expected a tree error, got {other:?}"),
    }
}

#[test]
fn invalid_trees_are_rejected_with_names() {
    let two_roots = format!(r#"<robot name="x">{}</robot>"#, links(&["a", "b"]));
    assert!(matches!(tree_err(&two_roots), TreeError::SeveralRoots(r) if r.len() == 2));
    let cycle = format!(
        r#"<robot name="x">{}{}{}{}</robot>"#,
        links(&["r", "a", "b"]),
        joint("ra", "fixed", "r", "a", "0 0 0", "0 0 0", ""),
        joint("ab", "fixed", "a", "b", "0 0 0", "0 0 0", ""),
        joint("ba", "fixed", "b", "a", "0 0 0", "0 0 0", ""),
    );
    assert!(matches!(tree_err(&cycle), TreeError::TwoParents { link, .. } if link == "a"));
    let unknown = format!(
        r#"<robot name="x">{}{}</robot>"#,
        links(&["a"]),
        joint("j", "fixed", "a", "ghost", "0 0 0", "0 0 0", "")
    );
    assert!(matches!(tree_err(&unknown), TreeError::UnknownLink { link, .. } if link == "ghost"));
}

#[test]
fn mimic_errors_and_zero_axis() {
    let lim = r#"<limit lower="0" upper="1" effort="1" velocity="1"/>"#;
    let xml = |ma: &str, mb: &str, axis: &str| {
        format!(
            r#"<robot name="x">{}{}{}</robot>"#,
            links(&["p", "a", "b"]),
            joint(
                "ja",
                "prismatic",
                "p",
                "a",
                "0 0 0",
                "0 0 0",
                &format!(r#"<axis xyz="{axis}"/>{lim}{ma}"#)
            ),
            joint(
                "jb",
                "prismatic",
                "p",
                "b",
                "0 0 0",
                "0 0 0",
                &format!(r#"<axis xyz="1 0 0"/>{lim}{mb}"#)
            ),
        )
    };
    let e = tree_err(&xml("", r#"<mimic joint="nope"/>"#, "1 0 0"));
    assert!(matches!(e, TreeError::UnknownMimic { target, .. } if target == "nope"));
    let e = tree_err(&xml(
        r#"<mimic joint="jb"/>"#,
        r#"<mimic joint="ja"/>"#,
        "1 0 0",
    ));
    assert!(matches!(e, TreeError::MimicCycle(_)), "{e:?}");
    let e = tree_err(&xml("", "", "0 0 0"));
    assert!(matches!(e, TreeError::BadAxis { joint, .. } if joint == "ja"));
}

/// The slew time is the slowest commanded joint's distance over its velocity limit, on the
/// positions FK uses: a command past a limit counts only to the limit, mimic joints follow
/// their source, and a joint without a velocity limit (continuous `jc`) takes no time.
#[test]
fn slew_time_is_the_slowest_joint_at_its_velocity_limit() {
    let robot = gripper(r#"<mimic joint="ja" multiplier="-2" offset="0.1"/>"#, "");
    let kin = robot.kinematics();
    let from = robot.zero_positions();
    let mut to = robot.zero_positions();
    to.positions[0] = 0.03;
    assert!(
        (kin.slew_time(&from, &to) - 0.03).abs() < TOL,
        "ja at 1 m/s"
    );
    to.positions[0] = 0.5; // past the 0.04 upper limit: moves 0.04
    assert!((kin.slew_time(&from, &to) - 0.04).abs() < TOL);
    to.positions[1] = 99.0; // jb is a mimic: ignored
    to.positions[2] = 10.0; // jc has no velocity limit
    assert!((kin.slew_time(&from, &to) - 0.04).abs() < TOL);
    assert_eq!(kin.slew_time(&from, &from), 0.0);
}
