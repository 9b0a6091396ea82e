//! Bad node parameters (`src/ros/node/params.rs`) against the built `drape node`: a parameters
//! file or a `-p` override the node cannot use stops it before any DDS participant exists,
//! with one error line naming the file (or the command line) and the key, and the value's
//! problem (the value, the expected form or range) as the cause below it.
//!
//! The runs go inside a private network namespace all the same (tests/support/netns.rs): a
//! case that wrongly passed validation would start the node, and its discovery must not leave
//! the machine.
#![cfg(feature = "ros")]

#[path = "support/netns.rs"]
mod netns;

use drape::ros::node::params::{NodeParams, ParamError, ParamsError};
use std::path::Path;
use std::process::{Command, Output, Stdio};

#[path = "common/tiny_scene.rs"]
mod tiny_scene;
use tiny_scene::TINY_SCENE as SCENE;

const PARAMS: &str = "drape:\n  ros__parameters:\n    scene: scene.yaml\n    publish_rate: 20\n";

fn node(dir: &Path, params: &str, extra: &[&str]) -> Output {
    let file = dir.join("params.yaml");
    std::fs::write(&file, params).unwrap();
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .arg("node")
        .arg("--params")
        .arg(&file)
        .args(extra)
        .env("RUST_LOG", "error")
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

#[test]
fn bad_parameters_name_the_file_the_key_and_the_value() {
    if !netns::enter("bad_parameters_name_the_file_the_key_and_the_value") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.yaml"), SCENE).unwrap();
    let file = dir.path().join("params.yaml").display().to_string();
    let with = |from: &str, to: &str| PARAMS.replace(from, to);
    // (parameters file, extra arguments, the first line's origin and key, the cause's text)
    let cases: Vec<(String, Vec<&str>, String, &str)> = vec![
        (
            with("publish_rate: 20", "publish_rate: -3"),
            vec![],
            format!("{file}: parameter `publish_rate`"),
            "must be in (0, 1000] Hz, got -3",
        ),
        (
            with("publish_rate: 20", "publish_rat: 20"),
            vec![],
            format!("{file}: parameter `publish_rat`"),
            "unknown parameter",
        ),
        (
            format!("{PARAMS}    distro: kinetic\n"),
            vec![],
            format!("{file}: parameter `distro`"),
            "unknown ROS 2 distribution \"kinetic\"",
        ),
        (
            format!("{PARAMS}    quality:\n      levels: 1\n"),
            vec![],
            format!("{file}: parameter `quality.levels`"),
            "must be an integer in 2..=64, got 1",
        ),
        (
            format!("{PARAMS}    color: [1, 0.5, 2, 1]\n"),
            vec![],
            format!("{file}: parameter `color`"),
            "component 2 is outside [0, 1]",
        ),
        (
            format!("{PARAMS}    topics:\n      mesh: \"a b\"\n"),
            vec![],
            format!("{file}: parameter `topics.mesh`"),
            "`a b` is not a topic name",
        ),
        (
            format!("{PARAMS}    service_mapping: zenoh\n"),
            vec![],
            format!("{file}: parameter `service_mapping`"),
            "expected `enhanced` or `cyclone`, got `zenoh`",
        ),
        (
            with("scene: scene.yaml", "frame_id: base"),
            vec![],
            format!("{file}: parameter `scene`"),
            "missing: name the scene file",
        ),
        (
            PARAMS.to_string(),
            vec!["--ros-args", "-p", "paused:=maybe"],
            "command line: parameter `paused`".to_string(),
            "expected true or false, got String(\"maybe\")",
        ),
        (
            PARAMS.to_string(),
            vec!["--ros-args", "-r", "/joint_states:=/js"],
            "command line".to_string(),
            "remap `/joint_states:=/js` is not supported",
        ),
    ];
    for (params, extra, top, cause) in &cases {
        let o = node(dir.path(), params, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{top}: accepted\n{err}");
        let lines: Vec<&str> = err.trim().lines().collect();
        assert_eq!(lines[0], format!("drape: error: {top}"), "{err}");
        assert!(
            lines[1..]
                .iter()
                .any(|l| l.starts_with("  caused by: ") && l.contains(cause)),
            "{top}: no cause {cause:?}\n{err}"
        );
        assert!(
            lines[1..].iter().all(|l| l.starts_with("  caused by: ")),
            "one error and its causes: {err}"
        );
    }
}

#[test]
fn the_typed_cause_carries_the_value_and_its_range() {
    let text = PARAMS.replace("publish_rate: 20", "publish_rate: 5000");
    let e = NodeParams::from_yaml(&text, "p.yaml", "drape").unwrap_err();
    match &e {
        ParamsError::Invalid {
            origin,
            key,
            source: ParamError::Rate { value, max },
        } => {
            assert_eq!((origin.as_str(), key.as_str()), ("p.yaml", "publish_rate"));
            assert_eq!((*value, *max), (5000.0, 1000.0));
        }
        other => panic!("{other:?}"),
    }
    let text = format!("{PARAMS}    max_backlog_steps: 2.5\n");
    let e = NodeParams::from_yaml(&text, "p.yaml", "drape").unwrap_err();
    assert!(
        matches!(
            &e,
            ParamsError::Invalid {
                source: ParamError::NotAnIntegerIn {
                    min: 1,
                    max: 1000,
                    ..
                },
                ..
            }
        ),
        "{e:?}"
    );
}
