//! The parameters file and ROS argument rules, one test per rule.

use super::*;

const FILE: &str = "
drape:
  ros__parameters:
    scene: robot_towel.yaml
    robot_description_from_topic: true
    publish_rate: 20
    use_sim_time: true
    distro: humble
    service_mapping: cyclone
    topics:
      mesh: cloth/mesh
";

#[test]
fn reads_nested_ros_parameters() {
    let p = NodeParams::from_yaml(FILE, "f.yaml", "drape").unwrap();
    assert_eq!(p.scene, PathBuf::from("robot_towel.yaml"));
    assert!(p.robot_description_from_topic);
    assert!(p.robot_description.is_empty());
    assert_eq!(p.publish_rate, 20.0);
    assert!(p.use_sim_time);
    assert_eq!(p.distro, Some(Distro::Humble));
    assert_eq!(p.service_wire, ServiceWire::Cyclone);
    assert_eq!(p.topics.mesh, "cloth/mesh");
    assert_eq!(p.topics.points, "~/points");
    // Other node names and the wildcard.
    let renamed = FILE.replace("drape:", "/robots/cloth:");
    assert!(NodeParams::from_yaml(&renamed, "f", "cloth").is_ok());
    let wild = FILE.replace("drape:", "/**:");
    assert!(NodeParams::from_yaml(&wild, "f", "other").is_ok());
}

#[test]
fn errors_name_file_and_key() {
    let e = NodeParams::from_yaml(FILE, "f.yaml", "nobody").unwrap_err();
    assert!(e.to_string().contains("nobody"), "{e}");
    let bad = FILE.replace("publish_rate: 20", "publish_rate: -1");
    let e = NodeParams::from_yaml(&bad, "f.yaml", "drape").unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("f.yaml") && msg.contains("publish_rate"),
        "{msg}"
    );
    // The value and the range it must be in are fields of the cause, which the chain prints.
    assert!(
        matches!(&e, ParamsError::Invalid { origin, key, source: ParamError::Rate { value, max } }
            if origin == "f.yaml" && key == "publish_rate" && *value == -1.0 && *max == 1000.0),
        "{e:?}"
    );
    let line = crate::input::error_line(&e);
    assert_eq!(
        line,
        "f.yaml: parameter `publish_rate`: must be in (0, 1000] Hz, got -1"
    );
    let distro = FILE.replace("distro: humble", "distro: kinetic");
    let e = NodeParams::from_yaml(&distro, "f.yaml", "drape").unwrap_err();
    assert!(
        matches!(&e, ParamsError::Invalid { key, source: ParamError::Distro(d), .. }
            if key == "distro" && d.0 == "kinetic"),
        "{e:?}"
    );
    let mapping = FILE.replace("service_mapping: cyclone", "service_mapping: zenoh");
    let e = NodeParams::from_yaml(&mapping, "f.yaml", "drape").unwrap_err();
    assert!(
        crate::input::error_line(&e).ends_with(
            "parameter `service_mapping`: expected `enhanced` or `cyclone`, got `zenoh`"
        ),
        "{e}"
    );
    let typo = FILE.replace("publish_rate", "publish_rat");
    let e = NodeParams::from_yaml(&typo, "f.yaml", "drape").unwrap_err();
    assert!(e.to_string().contains("publish_rat"), "{e}");
    let bad_topic = FILE.replace("mesh: cloth/mesh", "colour: x");
    assert!(NodeParams::from_yaml(&bad_topic, "f", "drape").is_err());
    let no_scene = FILE.replace("scene: robot_towel.yaml", "frame_id: base");
    let e = NodeParams::from_yaml(&no_scene, "f", "drape").unwrap_err();
    assert!(e.to_string().contains("scene"), "{e}");
    assert!(NodeParams::from_yaml("drape: [", "f", "drape").is_err());
}

#[test]
fn ros_args_and_overrides() {
    let a = parse_ros_args(&[
        "--ros-args",
        "--params-file",
        "p.yaml",
        "-r",
        "__ns:=/robot1",
        "-r",
        "__node:=cloth",
        "-p",
        "publish_rate:=15.0",
    ])
    .unwrap();
    assert_eq!(a.params_files, [PathBuf::from("p.yaml")]);
    assert_eq!(a.namespace.as_deref(), Some("/robot1"));
    assert_eq!(a.node_name.as_deref(), Some("cloth"));
    let mut p = NodeParams::from_yaml(FILE, "f", "drape").unwrap();
    p.apply_overrides(&a.overrides).unwrap();
    assert_eq!(p.publish_rate, 15.0);
    assert!(matches!(
        parse_ros_args(&["-r", "/joint_states:=/js"]),
        Err(ParamsError::Args(ArgsError::Remap { remap })) if remap == "/joint_states:=/js"
    ));
    assert!(parse_ros_args(&["--params-file"]).is_err());
    assert!(parse_ros_args(&["-p", "x"]).is_err());
    assert!(parse_ros_args(&["--enclave", "x"]).is_err());
    assert!(p
        .apply_overrides(&[("publish_rate".into(), "fast".into())])
        .is_err());
}

#[test]
fn adaptive_quality_and_its_bounds() {
    let mut p = NodeParams::from_yaml(FILE, "f", "drape").unwrap();
    assert!(p.adaptive_quality);
    assert_eq!(p.quality, QualityBounds::default());
    let text = format!(
        "{FILE}    adaptive_quality: false\n    quality: {{ min_substeps: 2, \
         max_cg_tolerance: 0.001, min_cg_max_iterations: 80, max_linearisation_tolerance: 0.5, \
         levels: 4 }}\n"
    );
    let q = NodeParams::from_yaml(&text, "f", "drape").unwrap();
    assert!(!q.adaptive_quality);
    assert_eq!(
        q.quality,
        QualityBounds {
            min_substeps: 2,
            max_cg_tolerance: 1e-3,
            min_cg_max_iterations: 80,
            max_linearisation_tolerance: 0.5,
            levels: 4
        }
    );
    for (key, value) in [
        ("quality.min_substeps", "0"),
        ("quality.max_cg_tolerance", "1.5"),
        ("quality.levels", "1"),
        ("quality.max_linearisation_tolerance", "0"),
        ("quality.max_linearisation_tolerance", ".nan"),
        ("adaptive_quality", "fast"),
        ("real_time_preview", "true"),
    ] {
        let e = p
            .apply_overrides(&[(key.into(), value.into())])
            .unwrap_err()
            .to_string();
        assert!(e.contains(key), "{e}");
    }
}

#[test]
fn joint_velocity_limits_on_by_default() {
    let p = NodeParams::from_yaml(FILE, "f", "drape").unwrap();
    assert!(p.joint_velocity_limits);
    let off = format!("{FILE}    joint_velocity_limits: false\n");
    assert!(
        !NodeParams::from_yaml(&off, "f", "drape")
            .unwrap()
            .joint_velocity_limits
    );
    let mut p = p;
    let e = p
        .apply_overrides(&[("joint_velocity_limits".into(), "fast".into())])
        .unwrap_err()
        .to_string();
    assert!(e.contains("joint_velocity_limits"), "{e}");
}

#[test]
fn robot_description_holds_urdf_text() {
    let urdf = "<robot name=\"r\">\n  <link name=\"a\"/> <!-- # not a comment -->\n</robot>";
    let mut p = NodeParams::from_yaml(FILE, "f", "drape").unwrap();
    // `-p` takes the XML as it is (a YAML reading would cut it at ` #`).
    p.apply_overrides(&[("robot_description".into(), urdf.into())])
        .unwrap();
    assert_eq!(p.robot_description, urdf);
    let text = format!("{FILE}    robot_description: |\n      <robot name=\"r\"/>\n");
    let q = NodeParams::from_yaml(&text, "f", "drape").unwrap();
    assert_eq!(q.robot_description.trim(), "<robot name=\"r\"/>");
    // A word where the URDF belongs (a file name, `topic`) says what the parameter holds.
    for word in ["topic", "file", "robot.urdf"] {
        let bad = format!("{FILE}    robot_description: {word}\n");
        let e = NodeParams::from_yaml(&bad, "f.yaml", "drape").unwrap_err();
        assert!(
            matches!(&e, ParamsError::Invalid { key, source: ParamError::NotUrdf { got }, .. }
                if key == "robot_description" && got == word),
            "{e:?}"
        );
        assert!(
            crate::input::error_line(&e).contains("robot_description_from_topic"),
            "{e}"
        );
    }
}

#[test]
fn an_empty_parameters_block_is_named_with_its_file() {
    let e = NodeParams::from_yaml("drape:\n  ros__parameters:\n", "p.yaml", "drape").unwrap_err();
    assert_eq!(
        e.to_string(),
        "p.yaml: `drape: ros__parameters:` is empty: indent the parameters under it (e.g. \
         `scene: my_scene.yaml`)"
    );
    let e = NodeParams::from_yaml("/**:\n  ros__parameters: [1]\n", "p.yaml", "drape").unwrap_err();
    assert!(
        matches!(&e, ParamsError::NotAMapping { section, empty: false, .. } if section == "/**"),
        "{e:?}"
    );
}

#[test]
fn files_merge_in_order_and_overrides_complete_them() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    let fa = a.join("p.yaml");
    let fb = b.join("p.yaml");
    std::fs::write(
        &fa,
        "drape:\n  ros__parameters:\n    scene: s.yaml\n    publish_rate: 10\n    package_paths: [pkgs]\n",
    )
    .unwrap();
    std::fs::write(&fb, "drape:\n  ros__parameters:\n    paused: true\n").unwrap();
    let p = NodeParams::from_sources(&[fa.clone(), fb.clone()], &[], "drape").unwrap();
    // The second file keeps what it does not set; paths stay relative to the file that set them.
    assert_eq!(
        (p.scene.clone(), p.publish_rate, p.paused),
        (a.join("s.yaml"), 10.0, true)
    );
    assert_eq!(p.package_paths, [a.join("pkgs")]);
    // A file without the scene, completed by `-p` (relative to the working directory).
    let o = [("scene".to_string(), "x/s.yaml".to_string())];
    let p = NodeParams::from_sources(std::slice::from_ref(&fb), &o, "drape").unwrap();
    assert_eq!(p.scene, PathBuf::from("x/s.yaml"));
    // `-p` alone.
    let p = NodeParams::from_sources(&[], &o, "drape").unwrap();
    assert_eq!((p.scene, p.publish_rate), (PathBuf::from("x/s.yaml"), 30.0));
    // Still no scene: named against the command line.
    let o = [("paused".to_string(), "true".to_string())];
    let e = NodeParams::from_sources(&[], &o, "drape").unwrap_err();
    assert_eq!(
        crate::input::error_line(&e),
        "command line: parameter `scene`: missing: name the scene file"
    );
}
