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
