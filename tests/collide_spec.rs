//! Scene-file collision specs: parsing, validation key paths, building obstacles.

use drape::collide::{
    validate_obstacles, CollisionSpec, DetectionMode, MotionSpec, ObstacleSpec, ResponseMode,
    ShapeSpec,
};
use drape::Vec3;

const OBSTACLES: &str = r#"
- name: ball
  shape: { type: sphere, radius: 0.3 }
  pose: { xyz: [0, 0, 1], rpy: [0, 0, 0] }
  friction: 0.4
- name: table
  shape: { type: box, half_extents: [0.5, 0.4, 0.02] }
- name: rod
  shape: { type: cylinder, radius: 0.01, half_height: 0.3 }
  motion: { type: velocity, linear: [1, 0, 0], angular: [0, 0, 0] }
- name: arm
  shape: { type: capsule, radius: 0.05, half_height: 0.2 }
  motion: { type: external }
- name: floor
  shape: { type: plane, normal: [0, 0, 1] }
- name: bowl
  shape: { type: mesh, path: bowl.stl, scale: [0.01, 0.01, 0.01] }
  motion:
    type: waypoints
    points:
      - { t: 0.0, pose: { xyz: [0, 0, 0] } }
      - { t: 1.0, pose: { xyz: [0, 0, 1], rpy: [0, 0, 1.57] } }
"#;

fn parse(yaml: &str) -> Vec<ObstacleSpec> {
    serde_yaml_ng::from_str(yaml).unwrap()
}

fn tetra(_: &str) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), String> {
    Ok((
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    ))
}

#[test]
fn parses_every_shape_and_motion() {
    let specs = parse(OBSTACLES);
    assert_eq!(specs.len(), 6);
    validate_obstacles(&specs, "obstacles").unwrap();
    assert_eq!(specs[3].motion, MotionSpec::External);
    let built: Vec<_> = specs.iter().map(|s| s.build(tetra).unwrap()).collect();
    assert_eq!(built[0].friction, Some(0.4));
    assert!((built[0].pose.translation - Vec3::new(0.0, 0.0, 1.0)).length() < 1e-12);
    // Mesh scaled by 0.01: its local box is 1 cm.
    let aabb = built[5].shape.compute_local_aabb();
    assert!((aabb.maxs.x - 0.01).abs() < 1e-6, "{aabb:?}");
    let end = built[5].motion.pose_at(&built[5].initial_pose, 2.0);
    assert!((end.translation.z - 1.0).abs() < 1e-12);
}

#[test]
fn validation_errors_name_key_paths() {
    let cases = [
        ("- name: a\n  shape: { type: sphere, radius: 0 }", "obstacles[0].shape.radius"),
        ("- name: a\n  shape: { type: box, half_extents: [1, -1, 1] }", "obstacles[0].shape.half_extents[1]"),
        ("- name: a\n  shape: { type: capsule, radius: 1, half_height: .nan }", "obstacles[0].shape.half_height"),
        ("- name: a\n  shape: { type: plane, normal: [0, 0, 0] }", "obstacles[0].shape.normal"),
        ("- name: a\n  shape: { type: mesh, path: '' }", "obstacles[0].shape.path"),
        ("- name: a\n  shape: { type: sphere, radius: 1 }\n  friction: -0.1", "obstacles[0].friction"),
        (
            "- name: a\n  shape: { type: sphere, radius: 1 }\n- name: a\n  shape: { type: sphere, radius: 1 }",
            "obstacles[1].name",
        ),
        (
            "- name: a\n  shape: { type: sphere, radius: 1 }\n  motion: { type: waypoints, points: [ { t: 1, pose: {} }, { t: 0.5, pose: {} } ] }",
            "obstacles[0].motion.points[1].t",
        ),
        ("- name: a\n  shape: { type: sphere, radius: 1 }\n  pose: { xyz: [0, .inf, 0] }", "obstacles[0].pose.xyz"),
    ];
    for (yaml, path) in cases {
        let err = validate_obstacles(&parse(yaml), "obstacles").unwrap_err();
        assert_eq!(err.path, path, "{yaml}");
        assert!(err.to_string().starts_with(path));
    }
}

#[test]
fn unknown_keys_are_rejected() {
    let bad = "- name: a\n  shape: { type: sphere, radius: 1, radiuss: 2 }";
    assert!(serde_yaml_ng::from_str::<Vec<ObstacleSpec>>(bad).is_err());
    let bad = "- name: a\n  shape: { type: sphere, radius: 1 }\n  colour: red";
    let e = serde_yaml_ng::from_str::<Vec<ObstacleSpec>>(bad)
        .unwrap_err()
        .to_string();
    assert!(e.contains("colour"), "{e}");
    let bad = "mode: continous";
    assert!(serde_yaml_ng::from_str::<CollisionSpec>(bad).is_err());
}

#[test]
fn collision_spec_defaults_and_validation() {
    let spec: CollisionSpec = serde_yaml_ng::from_str("self_collision: true").unwrap();
    assert_eq!(spec.mode, DetectionMode::Continuous);
    assert_eq!(spec.response, ResponseMode::Both);
    assert_eq!(spec.self_iterations, 8);
    spec.validate("collision").unwrap();
    let spec: CollisionSpec = serde_yaml_ng::from_str(
        "mode: proximity\nresponse: filter\nself_collision: true\nself_iterations: 0",
    )
    .unwrap();
    spec.validate("collision").unwrap();
    let spec: CollisionSpec =
        serde_yaml_ng::from_str("self_collision: true\nself_iterations: 0").unwrap();
    assert_eq!(
        spec.validate("collision").unwrap_err().path,
        "collision.self_iterations"
    );
    let s = spec.settings();
    assert!(s.self_collision && s.mode == DetectionMode::Continuous);
}

#[test]
fn mesh_load_failure_names_obstacle_and_path() {
    let spec = ObstacleSpec {
        name: "bowl".into(),
        shape: ShapeSpec::Mesh {
            path: "missing.stl".into(),
            scale: [1.0; 3],
        },
        pose: Default::default(),
        motion: MotionSpec::Static,
        friction: None,
    };
    let e = spec
        .build(|p: &str| Err::<(Vec<Vec3>, Vec<[u32; 3]>), _>(format!("{p}: no such file")))
        .unwrap_err()
        .to_string();
    assert!(e.contains("bowl") && e.contains("missing.stl"), "{e}");
}
