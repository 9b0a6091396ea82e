//! Telemetry in every recorded bag: each frame has its `/diagnostics` quality at the same time,
//! read back by drape's reader and by rosbags; `drape record` prints the run summary table and
//! writes it as JSON with `--summary`.
#![cfg(feature = "ros")]

use drape::ros::msg::{DiagnosticArray, PointCloud2};
use drape::ros::read_topic;
use drape::ros::telemetry::RunSummary;
use std::path::Path;
use std::process::Command;

fn scene(dir: &Path) -> std::path::PathBuf {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sphere_drape.yaml"),
    )
    .unwrap();
    let path = dir.join("scene.yaml");
    std::fs::write(&path, base).unwrap();
    path
}

#[test]
fn every_frame_has_its_telemetry_and_the_summary_matches() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = scene(dir.path());
    let bag = dir.path().join("out.mcap");
    let json = dir.path().join("summary.json");
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["record", "--quiet", "--duration", "0.5", "--scene"])
        .arg(&scene_path)
        .arg("--out")
        .arg(&bag)
        .arg("--summary")
        .arg(&json)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout);
    for row in [
        "frames",
        "CG iterations / step",
        "worst penetration",
        "real-time factor",
    ] {
        assert!(table.contains(row), "summary table lacks {row}: {table}");
    }
    let summary: RunSummary =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();

    let mesh = read_topic::<PointCloud2>(&bag, "/drape/points").unwrap();
    let diag = read_topic::<DiagnosticArray>(&bag, "/diagnostics").unwrap();
    assert_eq!(diag.skipped, 0);
    assert_eq!(mesh.messages.len() as u64, summary.frames);
    assert_eq!(diag.messages.len(), mesh.messages.len());
    let mut steps = 0;
    let mut worst_pen = 0.0f64;
    for ((tm, _), (td, d)) in mesh.messages.iter().zip(&diag.messages) {
        assert_eq!(tm, td, "telemetry at the frame's time");
        let s = &d.status[0];
        let get = |k: &str| -> f64 {
            s.values
                .iter()
                .find(|kv| kv.key == k)
                .unwrap_or_else(|| panic!("no {k} at {td}"))
                .value
                .parse()
                .unwrap()
        };
        for k in [
            "substeps",
            "subdivisions",
            "contact_splits",
            "contact_splits_refused",
            "cg_iterations",
            "cg_residual_max",
            "contacts",
            "deepest_penetration_m",
            "max_edge_stretch",
            "energy_j",
        ] {
            assert!(get(k).is_finite(), "{k}");
        }
        assert!(
            !s.values.iter().any(|kv| kv.key == "step_wall_time_ms"),
            "wall time stays out of the bag by default"
        );
        steps += get("steps") as u64;
        worst_pen = worst_pen.max(get("deepest_penetration_m"));
    }
    assert_eq!(steps, summary.steps);
    assert_eq!(worst_pen, summary.worst_penetration_m);
    assert!(summary.contacts_max > 0, "the sheet lands on the sphere");
    assert!(summary.cg_iterations_mean > 0.0 && summary.wall_s > 0.0);

    // The independent reader sees the same topic and type.
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/summarize_bag.py");
    let py = Command::new("python3")
        .arg(script)
        .arg(&bag)
        .output()
        .unwrap();
    assert!(
        py.status.success(),
        "rosbags (pip install -r tests/py/requirements.txt): {}",
        String::from_utf8_lossy(&py.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&py.stdout).unwrap();
    assert_eq!(
        v["/diagnostics"]["type"],
        "diagnostic_msgs/msg/DiagnosticArray"
    );
    assert_eq!(v["/diagnostics"]["count"], mesh.messages.len());
}

#[test]
fn wall_time_in_the_bag_only_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = scene(dir.path());
    let bag = dir.path().join("wall.mcap");
    let ok = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args([
            "record",
            "--quiet",
            "--duration",
            "0.1",
            "--wall-time-in-bag",
            "--scene",
        ])
        .arg(&scene_path)
        .arg("--out")
        .arg(&bag)
        .status()
        .unwrap();
    assert!(ok.success());
    let diag = read_topic::<DiagnosticArray>(&bag, "/diagnostics").unwrap();
    assert!(diag.messages.iter().all(|(_, d)| d.status[0]
        .values
        .iter()
        .any(|kv| kv.key == "step_wall_time_ms")));
}
