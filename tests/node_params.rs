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
use tiny_scene::{tiny_robot_scene, TINY_SCENE as SCENE};

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
            format!("{PARAMS}    robot_description: file\n"),
            vec![],
            format!("{file}: parameter `robot_description`"),
            "expected the URDF's XML text (`<robot ...>`), got `file`",
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

#[test]
fn an_empty_parameters_block_names_the_file() {
    if !netns::enter("an_empty_parameters_block_names_the_file") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let o = node(dir.path(), "drape:\n  ros__parameters:\n", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    let file = dir.path().join("params.yaml");
    assert_eq!(
        err.trim(),
        format!(
            "drape: error: {}: `drape: ros__parameters:` is empty: indent the parameters \
             under it (e.g. `scene: my_scene.yaml`)",
            file.display()
        )
    );
}

/// A URDF of one box link named `root`.
fn urdf(robot: &str, root: &str) -> String {
    format!(
        "<robot name=\"{robot}\">\n  <link name=\"{root}\">\n    <collision><geometry><box \
         size=\"0.1 0.1 0.1\"/></geometry></collision>\n  </link>\n</robot>\n"
    )
}

/// Runs `drape node ARGS` until it logs that it started (its line returned), then stops it
/// with SIGTERM and checks that it ends cleanly.
fn start_and_stop(args: &[&str]) -> String {
    use std::io::{BufRead, BufReader};
    let mut child = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .env("RUST_LOG", "info")
        .env("ROS_DOMAIN_ID", "41")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if line.contains("drape node: scene") {
                let _ = tx.send(line.clone());
            }
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    let started = rx.recv_timeout(std::time::Duration::from_secs(60));
    let pid = i32::try_from(child.id()).unwrap();
    assert_eq!(unsafe { libc::kill(pid, libc::SIGTERM) }, 0);
    let status = child.wait().unwrap();
    let log = reader.join().unwrap();
    let line = started.unwrap_or_else(|_| panic!("the node did not start ({status}):\n{log}"));
    assert!(status.success(), "{status}\n{log}");
    line
}

#[test]
fn the_scene_alone_on_the_command_line_runs_the_node() {
    if !netns::enter("the_scene_alone_on_the_command_line_runs_the_node") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.yaml");
    std::fs::write(&scene, SCENE).unwrap();
    let line = start_and_stop(&[
        "node",
        "--ros-args",
        "-p",
        &format!("scene:={}", scene.display()),
        "-p",
        "publish_rate:=10",
    ]);
    assert!(
        line.contains(&format!("scene {}", scene.display())),
        "{line}"
    );
    assert!(line.contains("10 Hz"), "{line}");
}

#[test]
fn robot_description_takes_the_urdf_text() {
    if !netns::enter("robot_description_takes_the_urdf_text") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bot.urdf"), urdf("file_bot", "file_root")).unwrap();
    let scene = dir.path().join("scene.yaml");
    std::fs::write(&scene, tiny_robot_scene("bot.urdf")).unwrap();
    let scene_arg = format!("scene:={}", scene.display());
    // The scene's URDF file when the parameter is empty; the output frame is its root link.
    let line = start_and_stop(&["node", "--ros-args", "-p", &scene_arg]);
    assert!(line.contains("frame `file_root`"), "{line}");
    // The parameter's XML instead, from the command line and from a parameters file.
    let xml = urdf("xml_bot", "xml_root");
    let given = format!("robot_description:={xml}");
    let line = start_and_stop(&["node", "--ros-args", "-p", &scene_arg, "-p", &given]);
    assert!(line.contains("frame `xml_root`"), "{line}");
    let indented: String = xml.lines().map(|l| format!("      {l}\n")).collect();
    let params = dir.path().join("p.yaml");
    std::fs::write(
        &params,
        format!("drape:\n  ros__parameters:\n    scene: scene.yaml\n    robot_description: |\n{indented}"),
    )
    .unwrap();
    let p = params.display().to_string();
    let line = start_and_stop(&["node", "--params", &p]);
    assert!(line.contains("frame `xml_root`"), "{line}");

    // A scene without a robot has nothing to load the URDF into: an error before DDS.
    std::fs::write(&scene, SCENE).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["node", "--ros-args", "-p", &scene_arg, "-p", &given])
        .env("RUST_LOG", "error")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("parameter `robot_description`: the scene")
            && err.contains("has no `robot:` section"),
        "{err}"
    );
}

/// Stand-ins for ROS 2's `launch` modules (not installed here): they record what the launch
/// file builds, so the command it would run can be read back and run.
const LAUNCH_STUBS: &str = r#"
import ast, importlib.util, json, sys, types

path, overrides = sys.argv[1], json.loads(sys.argv[2])
ast.parse(open(path, encoding="utf-8").read(), path)

class LaunchConfiguration:
    def __init__(self, name): self.name = name
    def perform(self, context): return context[self.name]
class DeclareLaunchArgument:
    def __init__(self, name, default_value=None, description=None):
        self.name, self.default_value = name, default_value
class ExecuteProcess:
    def __init__(self, cmd, **kw): self.cmd = cmd
class OpaqueFunction:
    def __init__(self, function): self.function = function
class LaunchDescription:
    def __init__(self, entities): self.entities = entities

launch = types.ModuleType("launch"); launch.LaunchDescription = LaunchDescription
actions = types.ModuleType("launch.actions")
actions.DeclareLaunchArgument, actions.ExecuteProcess, actions.OpaqueFunction = \
    DeclareLaunchArgument, ExecuteProcess, OpaqueFunction
subs = types.ModuleType("launch.substitutions"); subs.LaunchConfiguration = LaunchConfiguration
sys.modules.update({"launch": launch, "launch.actions": actions, "launch.substitutions": subs})

spec = importlib.util.spec_from_file_location("drape_launch", path)
m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)
ld = m.generate_launch_description()
ctx = {e.name: e.default_value for e in ld.entities if isinstance(e, DeclareLaunchArgument)}
unknown = set(overrides) - set(ctx)
assert not unknown, f"no launch argument {unknown}"
ctx.update(overrides)
cmds = [a.cmd for e in ld.entities if isinstance(e, OpaqueFunction) for a in e.function(ctx)]
print(json.dumps(cmds))
"#;

/// The commands `launch/drape.launch.py` runs with these launch arguments.
fn launch_commands(overrides: &str) -> Vec<Vec<String>> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("launch/drape.launch.py");
    let o = Command::new("python3")
        .args(["-c", LAUNCH_STUBS])
        .arg(&file)
        .arg(overrides)
        .output()
        .expect("python3 runs");
    assert!(
        o.status.success(),
        "{}: {}",
        file.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v.as_array()
        .unwrap()
        .iter()
        .map(|c| {
            c.as_array()
                .unwrap()
                .iter()
                .map(|a| a.as_str().unwrap().to_string())
                .collect()
        })
        .collect()
}

#[test]
fn the_launch_file_runs_the_node_with_its_parameters_file() {
    if !netns::enter("the_launch_file_runs_the_node_with_its_parameters_file") {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cmds = launch_commands("{}");
    let params = root.join("config/node.yaml").display().to_string();
    assert_eq!(
        cmds,
        [[
            "drape",
            "node",
            "--ros-args",
            "--params-file",
            &params,
            "-r",
            "__ns:=/",
            "-p",
            "use_sim_time:=false"
        ]]
    );
    // Its command, with this build's drape, a namespace and the robot's URDF as
    // robot_description, starts the node.
    let urdf = root.join("urdf/drape_bot.urdf").display().to_string();
    let overrides = serde_json::json!({ "drape": env!("CARGO_BIN_EXE_drape"),
        "namespace": "/robot1", "urdf": urdf });
    let cmds = launch_commands(&overrides.to_string());
    assert_eq!(cmds.len(), 1);
    let cmd = &cmds[0];
    assert_eq!(cmd[0], env!("CARGO_BIN_EXE_drape"));
    assert!(cmd.iter().any(|a| a == "__ns:=/robot1"), "{cmd:?}");
    let description = std::fs::read_to_string(&urdf).unwrap();
    assert!(cmd.contains(&format!("robot_description:={description}")));
    let args: Vec<&str> = cmd[1..].iter().map(String::as_str).collect();
    let line = start_and_stop(&args);
    assert!(line.contains("frame `base_link`"), "{line}");
}
