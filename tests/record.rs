//! `drape record` end to end: the bag it writes is read back by an independent reader (Python
//! `rosbags`) and compared with the same scene simulated in-process; an interrupted recording
//! still leaves a complete, readable file.
#![cfg(feature = "ros")]

use drape::scene::Scene;
use serde_json::Value;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

fn summarize(bag: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/summarize_bag.py");
    let out = Command::new("python3")
        .arg(script)
        .arg(bag)
        .output()
        .expect("python3 runs");
    match out.status.code() {
        Some(0) => serde_json::from_slice(&out.stdout).expect("json"),
        Some(2) => panic!(
            "the independent bag reader is missing: pip install -r tests/py/requirements.txt\n{}",
            String::from_utf8_lossy(&out.stderr)
        ),
        _ => panic!(
            "rosbags could not read {}: {}",
            bag.display(),
            String::from_utf8_lossy(&out.stderr)
        ),
    }
}

fn short_scene(dir: &Path) -> std::path::PathBuf {
    let base =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml"))
            .unwrap();
    let text = base.replacen("resolution: [32, 32]", "resolution: [12, 10]", 1);
    let path = dir.join("scene.yaml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn recorded_bag_matches_the_simulation() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = short_scene(dir.path());
    let bag = dir.path().join("out.mcap");
    let status = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["record", "--quiet", "--duration", "1.0", "--scene"])
        .arg(&scene_path)
        .arg("--out")
        .arg(&bag)
        .status()
        .unwrap();
    assert!(status.success());
    let s = summarize(&bag);

    // 30 Hz for 1 s: frames at t = 0, 1/30, ..., 1.
    let mesh = &s["/drape/mesh"];
    let points = &s["/drape/points"];
    assert_eq!(mesh["type"], "visualization_msgs/msg/Marker");
    assert_eq!(points["type"], "sensor_msgs/msg/PointCloud2");
    assert_eq!(mesh["count"], 31);
    assert_eq!(points["count"], 31);
    assert_eq!(points["first"], 0);
    assert_eq!(points["last"], 1_000_000_000);
    assert_eq!(points["stamp"], 1_000_000_000);
    assert_eq!(mesh["marker_type"], 11, "TRIANGLE_LIST");

    // The same scene in-process gives the same cloth (f32 rounding apart).
    let scene = Scene::load(&scene_path).unwrap();
    let mut sim = scene.build().unwrap();
    for _ in 0..60 {
        sim.step().unwrap();
    }
    assert_eq!(points["width"], sim.cloth.len());
    assert_eq!(points["point_step"], 24);
    assert_eq!(
        points["fields"],
        serde_json::json!(["x", "y", "z", "normal_x", "normal_y", "normal_z"])
    );
    assert_eq!(mesh["points"], 3 * sim.cloth.triangles.len());
    assert_eq!(points["frame_id"], "world");
    assert_eq!(points["finite"], true);
    let xyz = points["xyz"].as_array().unwrap();
    for (i, p) in xyz.iter().enumerate() {
        let p: Vec<f64> = p
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let x = sim.cloth.x[i];
        let err = (p[0] - x.x)
            .abs()
            .max((p[1] - x.y).abs())
            .max((p[2] - x.z).abs());
        // f32 has a 24-bit mantissa: |x| <= 2 m gives at most 2^-23 * 2 / 2 ~ 1.2e-7 of rounding.
        assert!(err < 2.5e-7, "vertex {i}: {p:?} vs {x}");
    }
}

#[cfg(unix)]
#[test]
fn interrupted_recording_leaves_a_complete_bag() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = short_scene(dir.path());
    for signal in ["-INT", "-TERM"] {
        let bag = dir.path().join(format!("int{signal}.mcap"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_drape"))
            .args(["record", "--quiet", "--duration", "100000", "--scene"])
            .arg(&scene_path)
            .arg("--out")
            .arg(&bag)
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        let killed = Command::new("kill")
            .arg(signal)
            .arg(child.id().to_string())
            .status()
            .unwrap();
        assert!(killed.success());
        let status = child.wait().unwrap();
        assert!(status.success(), "{signal}: recorder exited with {status}");
        let s = summarize(&bag);
        let n = s["/drape/points"]["count"].as_u64().unwrap();
        assert!(n > 1, "{signal}: only {n} frames");
        assert_eq!(s["/drape/mesh"]["count"].as_u64().unwrap(), n);
    }
}

#[test]
fn unwritable_output_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = short_scene(dir.path());
    let out = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["record", "--quiet", "--scene"])
        .arg(&scene_path)
        .args(["--out", "/nonexistent-dir/x.mcap"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent-dir/x.mcap"), "{err}");
}

/// A full disk: `/dev/full` fails every write, and (when this process may mount, as root in CI) a
/// 64 KiB tmpfs fills up mid-run. Both must end with a non-zero exit and an error that names the
/// output file and the cause, not a panic.
#[cfg(target_os = "linux")]
#[test]
fn full_disk_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = short_scene(dir.path());
    let record = |out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_drape"))
            .args(["record", "--quiet", "--duration", "5", "--scene"])
            .arg(&scene_path)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    let check = |out: &Path, o: std::process::Output| {
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{}: recorder succeeded", out.display());
        assert!(!err.contains("panicked"), "{err}");
        assert!(err.contains(&out.display().to_string()), "{err}");
        assert!(err.contains("No space left on device"), "{err}");
    };
    let dev_full = Path::new("/dev/full");
    check(dev_full, record(dev_full));

    let mnt = dir.path().join("tiny");
    std::fs::create_dir(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"])
        .arg(&mnt)
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        eprintln!("cannot mount a tmpfs here (not root?): only /dev/full was checked");
        return;
    }
    /// Unmounts even when an assertion fails.
    struct Unmount<'a>(&'a Path);
    impl Drop for Unmount<'_> {
        fn drop(&mut self) {
            let _ = Command::new("umount").arg(self.0).status();
        }
    }
    let _guard = Unmount(&mnt);
    let out = mnt.join("bag.mcap");
    check(&out, record(&out));
}

/// A tetrahedron, ASCII STL.
const TETRA_STL: &str = "solid tetra\n\
facet normal 0 0 -1\n outer loop\n  vertex 0 0 0\n  vertex 0 1 0\n  vertex 1 0 0\n endloop\nendfacet\n\
facet normal 0 -1 0\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 0 1\n endloop\nendfacet\n\
facet normal -1 0 0\n outer loop\n  vertex 0 0 0\n  vertex 0 0 1\n  vertex 0 1 0\n endloop\nendfacet\n\
facet normal 1 1 1\n outer loop\n  vertex 1 0 0\n  vertex 0 1 0\n  vertex 0 0 1\n endloop\nendfacet\n\
endsolid tetra\n";

fn drape(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .env("RUST_LOG", "error")
        .output()
        .unwrap()
}

/// `record` and `check` take the scene as SCENE or `--scene SCENE`, and find a robot's
/// `package://` mesh in a `--package-path` folder that is nowhere near the URDF.
#[test]
fn scene_either_way_and_package_path() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = dir.path().join("scenes");
    let pkgs = dir.path().join("pkgs");
    std::fs::create_dir_all(pkgs.join("tetra_pkg/meshes")).unwrap();
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::write(pkgs.join("tetra_pkg/meshes/tetra.stl"), TETRA_STL).unwrap();
    std::fs::write(
        scenes.join("bot.urdf"),
        "<robot name=\"bot\"><link name=\"base\"><collision><geometry><mesh \
         filename=\"package://tetra_pkg/meshes/tetra.stl\" scale=\"0.1 0.1 0.1\"/></geometry>\
         </collision></link></robot>\n",
    )
    .unwrap();
    let scene = scenes.join("scene.yaml");
    let base = std::fs::read_to_string(short_scene(dir.path())).unwrap();
    std::fs::write(&scene, format!("{base}robot:\n  urdf: bot.urdf\n")).unwrap();
    let (s, p) = (scene.as_os_str(), pkgs.as_os_str());
    let os = |a: &str| std::ffi::OsString::from(a);

    // Without the package folder the mesh is not found, and the error says where it looked.
    for cmd in [
        ["check"].as_slice(),
        ["record", "--out", "x.mcap"].as_slice(),
    ] {
        let mut args: Vec<std::ffi::OsString> = cmd.iter().map(|a| os(a)).collect();
        args.push(s.into());
        let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
        let o = drape(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{cmd:?}: found the mesh\n{err}");
        assert!(
            err.contains("package://tetra_pkg/meshes/tetra.stl"),
            "{err}"
        );
    }
    let check = drape(&[
        os("check").as_os_str(),
        s,
        os("--package-path").as_os_str(),
        p,
    ]);
    let out = String::from_utf8_lossy(&check.stdout);
    assert!(
        check.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&check.stderr)
    );
    assert!(out.contains("link base: mesh 4 triangles"), "{out}");

    // The two spellings of the scene record the same bag, byte for byte.
    let bags = [dir.path().join("a.mcap"), dir.path().join("b.mcap")];
    let tail = |bag: &Path| {
        vec![
            os("--out"),
            bag.as_os_str().into(),
            os("--duration"),
            os("0.1"),
            os("--quiet"),
            os("--package-path"),
            p.into(),
        ]
    };
    let mut positional = vec![os("record"), s.into()];
    positional.extend(tail(&bags[0]));
    let mut option = vec![os("record"), os("--scene"), s.into()];
    option.extend(tail(&bags[1]));
    for args in [positional, option] {
        let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
        let o = drape(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let [a, b] = bags.map(|b| std::fs::read(b).unwrap());
    assert!(!a.is_empty());
    assert!(a == b, "the bags differ");

    // Both at once is an error, not a silent choice.
    let o = drape(&[os("check").as_os_str(), s, os("--scene").as_os_str(), s]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot be used with"));
}

/// Every argument of every command has help text (`render` aside: its arguments are its own
/// module's); the developer tools are under `drape dev` and hidden from the main help, and
/// their old spellings still run.
#[test]
fn help_names_every_argument_and_groups_developer_tools() {
    let help = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_drape"))
            .args(args)
            .arg("-h")
            .output()
            .unwrap();
        assert!(o.status.success(), "{args:?}");
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let main = help(&[]);
    let commands: Vec<&str> = main
        .lines()
        .skip_while(|l| *l != "Commands:")
        .skip(1)
        .take_while(|l| !l.is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(
        commands,
        ["record", "node", "check", "dev", "render", "sweep", "help"],
        "{main}"
    );
    let mut paths: Vec<Vec<&str>> = vec![
        vec!["record"],
        vec!["node"],
        vec!["check"],
        vec!["dev", "study"],
        vec!["dev", "hard-cases"],
        vec!["study"],
        vec!["hard-cases"],
    ];
    for s in ["plan", "run", "collect"] {
        paths.push(vec!["sweep", s]);
    }
    paths.push(vec!["sweep", "emit", "slurm"]);
    paths.push(vec!["sweep", "emit", "k8s"]);
    for path in &paths {
        let text = help(path);
        let mut args = 0;
        for line in text
            .lines()
            .skip_while(|l| *l != "Arguments:" && *l != "Options:")
        {
            let t = line.trim_start();
            if !(t.starts_with('-') || t.starts_with('[') || t.starts_with('<')) {
                continue;
            }
            args += 1;
            // clap puts the help two spaces after the argument; without help there is none.
            assert!(t.contains("  "), "{path:?}: `{t}` has no help text\n{text}");
        }
        assert!(args > 1, "{path:?}\n{text}");
    }
    assert!(help(&["study"]).contains("Usage: drape study [OPTIONS] --out <OUT>"));
    assert!(help(&["hard-cases"]).contains("Usage: drape hard-cases [OPTIONS] --out <OUT>"));
}
