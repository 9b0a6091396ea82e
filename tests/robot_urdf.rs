//! URDF loading: the bundled robot, geometry conversion, mesh URI resolution and its errors.

use drape::robot::resolve::{resolve_uri, ResolveError, SearchPaths};
use drape::robot::{Geometry, Robot, RobotError, UrdfOptions};
use drape::Vec3;
use std::path::{Path, PathBuf};

fn no_env() -> UrdfOptions {
    UrdfOptions {
        use_ros_env: false,
        ..Default::default()
    }
}

fn bundled() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/drape_bot.urdf")
}

#[test]
fn bundled_robot_loads_with_primitives_and_mesh() {
    let robot = Robot::from_urdf_file(&bundled(), &no_env()).unwrap();
    assert_eq!(robot.name, "drape_bot");
    let shapes = robot.collision_shapes();
    assert_eq!(shapes.len(), robot.link_names().len());
    let head = &shapes[robot.link_index("head").unwrap()];
    assert!(matches!(&head[0].1, Geometry::Mesh(m) if m.indices.len() == 960));
    let torso = &shapes[robot.link_index("torso").unwrap()];
    assert_eq!(
        torso[0].1,
        Geometry::Box {
            half_extents: Vec3::new(0.15, 0.2, 0.3)
        }
    );
    assert!((torso[0].0.translation - Vec3::new(0.0, 0.0, 0.3)).length() < 1e-15);
    let upper = &shapes[robot.link_index("left_upper_arm").unwrap()];
    assert_eq!(
        upper[0].1,
        Geometry::Cylinder {
            radius: 0.05,
            length: 0.3
        }
    );
    // Arm reach: shoulder to tool frame is 0.3 + 0.25 + 0.1 m when straight.
    let poses = robot.link_poses(&robot.zero_positions());
    let shoulder = poses[robot.link_index("right_shoulder").unwrap()].translation;
    let tool = poses[robot.link_index("right_tool_frame").unwrap()].translation;
    assert!(((shoulder - tool).length() - 0.65).abs() < 1e-12);
    // Every actuated joint has limits and a velocity limit.
    for (_, j) in robot.kinematics().actuated_joints() {
        assert!(
            j.limits.is_some() && j.velocity_limit.is_some(),
            "{}",
            j.name
        );
    }
    let fb = robot.joint_index("right_finger_b_joint").unwrap();
    assert!(robot.kinematics().joints()[fb].mimic.is_some());
}

#[test]
fn urdf_string_with_trailing_nul_loads() {
    let xml = std::fs::read_to_string(bundled()).unwrap() + "\0\0";
    let dir = bundled().parent().unwrap().to_path_buf();
    let robot = Robot::from_urdf_str(&xml, Some(&dir), &no_env()).unwrap();
    assert_eq!(robot.link_names().len(), 16);
}

#[test]
fn malformed_xml_is_a_parse_error() {
    let err = Robot::from_urdf_str("<robot name='x'><link name='a'>", None, &no_env()).unwrap_err();
    assert!(matches!(err, RobotError::Parse { .. }), "{err:?}");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.urdf");
    std::fs::write(&p, "<robot").unwrap();
    let err = Robot::from_urdf_file(&p, &no_env()).unwrap_err();
    assert!(err.to_string().contains("broken.urdf"), "{err}");
}

fn one_mesh_link(filename: &str) -> String {
    format!(
        r#"<robot name="m"><link name="gripper_palm"><collision><geometry>
           <mesh filename="{filename}" scale="2 2 2"/></geometry></collision></link></robot>"#
    )
}

#[test]
fn missing_mesh_names_link_and_every_path_tried() {
    let dir = tempfile::tempdir().unwrap();
    let extra = dir.path().join("ws");
    let options = UrdfOptions {
        search_paths: vec![extra.clone()],
        ..no_env()
    };
    let err = Robot::from_urdf_str(
        &one_mesh_link("package://my_pkg/meshes/palm.stl"),
        Some(dir.path()),
        &options,
    )
    .unwrap_err();
    let RobotError::MeshNotFound { link, tried, .. } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(link, "gripper_palm");
    assert!(
        tried.contains(&extra.join("my_pkg/meshes/palm.stl")),
        "{tried:?}"
    );
    assert!(
        tried.contains(&dir.path().join("my_pkg/meshes/palm.stl")),
        "{tried:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("gripper_palm") && msg.contains(&extra.display().to_string()),
        "{msg}"
    );
}

#[test]
fn package_uri_cannot_escape_the_package() {
    let dir = tempfile::tempdir().unwrap();
    let err = Robot::from_urdf_str(
        &one_mesh_link("package://pkg/../../etc/passwd"),
        Some(dir.path()),
        &no_env(),
    )
    .unwrap_err();
    assert!(
        matches!(&err, RobotError::PackageEscape { link, .. } if link == "gripper_palm"),
        "{err:?}"
    );
    let paths = SearchPaths::default();
    assert_eq!(
        resolve_uri("package://../etc/passwd", None, &paths),
        Err(ResolveError::Escape)
    );
    assert_eq!(
        resolve_uri("package://pkg//etc/passwd", None, &paths),
        Err(ResolveError::Escape)
    );
}

fn write_tetra(path: &Path) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, "solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n").unwrap();
}

#[test]
fn package_uri_resolves_via_search_paths_ament_prefix_and_urdf_tree() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    // ROS_PACKAGE_PATH-style entry that *is* the package.
    write_tetra(&root.join("src/pkg_a/meshes/x.stl"));
    // AMENT_PREFIX_PATH-style install: <prefix>/share/<pkg>.
    write_tetra(&root.join("install/share/pkg_b/meshes/x.stl"));
    let paths = SearchPaths {
        extra: vec![],
        ros_package_path: vec![root.join("src/pkg_a")],
        ament_prefixes: vec![root.join("install")],
    };
    assert_eq!(
        resolve_uri("package://pkg_a/meshes/x.stl", None, &paths).unwrap(),
        root.join("src/pkg_a/meshes/x.stl")
    );
    assert_eq!(
        resolve_uri("package://pkg_b/./meshes/../meshes/x.stl", None, &paths).unwrap(),
        root.join("install/share/pkg_b/meshes/x.stl")
    );
    // pybullet layout: package:// relative to the URDF's folder; plain and file:// paths too.
    write_tetra(&root.join("robot/meshes/m.stl"));
    let urdf_dir = root.join("robot");
    let none = SearchPaths::default();
    assert!(resolve_uri("package://meshes/m.stl", Some(&urdf_dir), &none).is_ok());
    assert!(resolve_uri("meshes/m.stl", Some(&urdf_dir), &none).is_ok());
    let abs = format!("file://{}", root.join("robot/meshes/m.stl").display());
    assert!(resolve_uri(&abs, None, &none).is_ok());
    assert!(matches!(
        resolve_uri("http://x/m.stl", None, &none),
        Err(ResolveError::Unsupported(_))
    ));
    // And through a full load, with the scale applied.
    let robot =
        Robot::from_urdf_str(&one_mesh_link("meshes/m.stl"), Some(&urdf_dir), &no_env()).unwrap();
    let Geometry::Mesh(m) = &robot.collision_shapes()[0][0].1 else {
        panic!("expected a mesh")
    };
    assert_eq!(m.aabb().unwrap().1, Vec3::new(2.0, 2.0, 0.0));
}

#[test]
fn broken_mesh_error_names_link_and_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.stl"), b"garbage").unwrap();
    let err =
        Robot::from_urdf_str(&one_mesh_link("bad.stl"), Some(dir.path()), &no_env()).unwrap_err();
    let msg = err.to_string();
    assert!(
        matches!(err, RobotError::Mesh { .. })
            && msg.contains("gripper_palm")
            && msg.contains("bad.stl"),
        "{msg}"
    );
}

#[test]
fn visual_fallback_is_opt_in_and_bad_primitives_are_rejected() {
    let xml = r#"<robot name="v"><link name="a"><visual><geometry><sphere radius="0.1"/></geometry></visual></link></robot>"#;
    let robot = Robot::from_urdf_str(xml, None, &no_env()).unwrap();
    assert!(robot.collision_shapes()[0].is_empty());
    let options = UrdfOptions {
        visual_fallback: true,
        ..no_env()
    };
    let robot = Robot::from_urdf_str(xml, None, &options).unwrap();
    assert_eq!(
        robot.collision_shapes()[0][0].1,
        Geometry::Sphere { radius: 0.1 }
    );
    let bad = r#"<robot name="v"><link name="arm"><collision><geometry><cylinder radius="-1" length="1"/></geometry></collision></link></robot>"#;
    let err = Robot::from_urdf_str(bad, None, &no_env()).unwrap_err();
    assert!(
        matches!(&err, RobotError::BadGeometry { link, .. } if link == "arm"),
        "{err:?}"
    );
}
