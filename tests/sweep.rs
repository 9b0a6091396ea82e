//! `drape sweep`: plans, bad sweep files, a 200-job local run with `-j 2` checked by independent
//! readers (pandas, rosbags), reruns that complete only what is missing, killed jobs, and the
//! same bag bytes on 1 and 2 threads.
#![cfg(feature = "ros")]

use drape::sweep::{collect, Status, Sweep};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn drape() -> Command {
    Command::new(env!("CARGO_BIN_EXE_drape"))
}

fn config(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(name)
        .display()
        .to_string()
}

/// A sweep file over a bundled scene, made tiny: `body` adds grid/random sections.
fn sweep_file(dir: &Path, scene: &str, body: &str) -> PathBuf {
    let text = format!(
        "name: test\nscene: {}\nout: out\nseed: 3\n{body}",
        config(scene)
    );
    let path = dir.join("sweep.yaml");
    std::fs::write(&path, text).unwrap();
    path
}

const TINY: &str = "set:\n  duration: 0.1\n  cloths[0].grid.resolution: [5, 5]\n";

fn check_sweep(out: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/check_sweep.py");
    let o = Command::new("python3")
        .arg(script)
        .arg(out)
        .output()
        .unwrap();
    match o.status.code() {
        Some(0) => serde_json::from_slice(&o.stdout).expect("json"),
        Some(2) => panic!(
            "the independent readers are missing: pip install -r tests/py/requirements.txt\n{}",
            String::from_utf8_lossy(&o.stderr)
        ),
        _ => panic!(
            "check_sweep.py failed on {}: {}{}",
            out.display(),
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn plan_counts_grid_times_samples_and_is_stable() {
    let dir = tempfile::tempdir().unwrap();
    let f = sweep_file(
        dir.path(),
        "three_corner_normal.yaml",
        &format!(
            "{TINY}samples: 3\ngrid:\n  cloths[0].material.stretch: [1000, 2000]\n  \
             cloths[0].material.bend_warp: [1.0e-4, 1.0e-3]\nrandom:\n  \
             cloths[0].grid.pose.xyz: {{ jitter: [0.01, 0.01, 0.0] }}\n  \
             solver.substeps: {{ integer: [1, 2] }}\n"
        ),
    );
    let s = Sweep::load(&f).unwrap();
    assert_eq!(s.job_count(), 12);
    let j5 = s.job(5).unwrap();
    // Grid point 5 / 3 = 1: stretch 1000 (first key slowest), bend_warp 1e-3; draw 2.
    assert_eq!(j5.params[0].1.as_f64(), Some(1000.0));
    assert_eq!(j5.params[1].1.as_f64(), Some(1e-3));
    assert_eq!(s.job(5).unwrap(), j5, "draws depend only on seed and index");
    let xyz = j5.params[2].1.as_sequence().unwrap();
    assert!((xyz[0].as_f64().unwrap()).abs() <= 0.01);
    assert_eq!(xyz[2].as_f64(), Some(1.0), "zero amplitude keeps the value");
    let o = drape()
        .args(["sweep", "plan"])
        .arg(&f)
        .args(["--show", "2"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("12 jobs"), "{text}");
    assert!(text.contains("cloths[0].material.stretch=1000"), "{text}");
    assert!(text.contains("10 more"), "{text}");
}

#[test]
fn bad_sweep_files_name_the_key_before_any_job_runs() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "grid:\n  cloths[0].material.stiffnes: [1, 2]\n",
            "grid.cloths[0].material.stiffnes",
            "unknown field",
        ),
        (
            "grid:\n  cloths[0].material.stretch: [1000, soft]\n",
            "grid.cloths[0].material.stretch",
            "invalid type",
        ),
        (
            "grid:\n  cloths[2].material.stretch: [1000]\n",
            "grid.cloths[2].material.stretch",
            "out of range",
        ),
        (
            "random:\n  cloths[0].material.stretch: { uniform: [5000, 1000] }\n",
            "random.cloths[0].material.stretch",
            "empty range",
        ),
        (
            "grid:\n  solver.substeps: []\n",
            "grid.solver.substeps",
            "empty list",
        ),
        (
            "random:\n  cloths[0].material.stretch: { uniform: [-10, -1] }\n",
            "random.cloths[0].material.stretch",
            "must be",
        ),
        (
            "random:\n  job.time_scale: { uniform: [0.5, 2] }\n",
            "random.job.time_scale",
            "no robot trajectory",
        ),
        // Each typed cause below prints its value and what was expected.
        (
            "grid:\n  job.time_scale: [0]\n",
            "grid.job.time_scale",
            "value 0\n  caused by: must be a number > 0, got 0",
        ),
        (
            "grid:\n  job.joints: [no_such.mcap]\n",
            "grid.job.joints",
            "no such bag: ",
        ),
        (
            "grid:\n  job.speed: [1]\n",
            "grid.job.speed",
            "unknown job key `job.speed`",
        ),
        (
            "grid:\n  cloths[0]..stretch: [1]\n",
            "grid.cloths[0]..stretch",
            "`cloths[0]..stretch`: a key is missing before `.stretch`",
        ),
        (
            "random:\n  solver.dt: 0.1\n",
            "random.solver.dt",
            "expected a draw ({ uniform: [lo, hi] }",
        ),
        (
            "random:\n  solver.substeps: { integer: [1.5, 3] }\n",
            "random.solver.substeps",
            "integer: expected [lo, hi] integers\n  caused by: ",
        ),
        (
            "random:\n  solver.substeps: { integer: [3, 1] }\n",
            "random.solver.substeps",
            "empty range [3, 1]: needs lo <= hi",
        ),
        (
            "random:\n  cloths[0].grid.pose.xyz: { jitter: [0.1, 0.1] }\n",
            "random.cloths[0].grid.pose.xyz",
            "jitter needs one amplitude or one per element (the scene's value has 3, the jitter 2)",
        ),
        (
            "grid:\n  cloths[0].name.first: [x]\n",
            "grid.cloths[0].name.first",
            "`cloths[0].name` is a string, not a section with key `first`",
        ),
    ];
    for (body, key, reason) in cases {
        let f = sweep_file(
            dir.path(),
            "three_corner_normal.yaml",
            &format!("{TINY}{body}"),
        );
        let o = drape()
            .args(["sweep", "run", "--local", "--quiet"])
            .arg(&f)
            .output()
            .unwrap();
        let err = stderr(&o);
        assert!(!o.status.success(), "{body}: accepted");
        assert!(
            err.contains(key),
            "{body}: error does not name {key}: {err}"
        );
        assert!(
            err.contains(reason),
            "{body}: error lacks {reason:?}: {err}"
        );
        // One error: its line, then the causes the command line prints below it.
        let lines: Vec<&str> = err.trim().lines().collect();
        assert!(lines[0].starts_with("drape: error: "), "{err}");
        assert!(
            lines[1..].iter().all(|l| l.starts_with("  caused by: ")),
            "one error and its causes: {err}"
        );
        assert!(!dir.path().join("out").exists(), "{body}: something ran");
    }
    // An index past the end.
    let f = sweep_file(dir.path(), "three_corner_normal.yaml", TINY);
    let o = drape()
        .args(["sweep", "run", "--index", "1"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("out of range: the sweep has 1 jobs"),
        "{}",
        stderr(&o)
    );
}

/// The sweep's errors as types: the key, and a cause with the value and the expected range.
#[test]
fn sweep_errors_carry_the_key_and_the_value() {
    use drape::sweep::{ApplyError, KeyError, RangeError, SweepError};
    let dir = tempfile::tempdir().unwrap();
    let f = sweep_file(
        dir.path(),
        "three_corner_normal.yaml",
        &format!("{TINY}random:\n  cloths[0].material.stretch: {{ uniform: [5000, 1000] }}\n"),
    );
    let SweepError::Key {
        origin,
        key,
        source,
    } = Sweep::load(&f).unwrap_err()
    else {
        panic!("not a key error");
    };
    assert_eq!(origin, f.display().to_string());
    assert_eq!(key, "random.cloths[0].material.stretch");
    assert!(
        matches!(
            *source,
            KeyError::Range(RangeError::Empty {
                lo: 5000.0,
                hi: 1000.0
            })
        ),
        "{source:?}"
    );
    let f = sweep_file(
        dir.path(),
        "three_corner_normal.yaml",
        &format!("{TINY}grid:\n  job.time_scale: [-2]\n"),
    );
    let SweepError::Key { key, source, .. } = Sweep::load(&f).unwrap_err() else {
        panic!("not a key error");
    };
    assert_eq!(key, "grid.job.time_scale");
    match *source {
        KeyError::Value {
            value,
            source: ApplyError::BadTimeScale { value: v2 },
        } => assert_eq!((value.as_str(), v2.as_str()), ("-2", "-2")),
        other => panic!("{other:?}"),
    }
}

/// The acceptance run: 200 jobs of a bundled scene with `-j 2`; every bag opens in rosbags with
/// its telemetry on every frame; deleting one job and rerunning redoes only that job.
#[test]
fn two_hundred_jobs_locally_then_a_rerun_completes_only_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let f = sweep_file(
        dir.path(),
        "three_corner_soft_bending.yaml",
        &format!(
            "{TINY}samples: 50\ngrid:\n  cloths[0].material.stretch: [1000, 3000]\n  \
             effects: [[gravity, stretch, shear, bending, damping], [gravity, stretch, shear, bending, damping, wind]]\n\
             random:\n  wind.velocity: {{ choice: [[1, 0, 0], [0, 2, 0]] }}\n  \
             cloths[0].grid.pose.xyz: {{ jitter: 0.02 }}\n"
        ),
    );
    let start = Instant::now();
    let o = drape()
        .args(["sweep", "run", "--local", "-j", "2", "--quiet"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    eprintln!("200 jobs in {:.1} s", start.elapsed().as_secs_f64());
    let out = dir.path().join("out");
    let m = collect(&out).unwrap();
    assert_eq!(m.entries.len(), 200);
    assert_eq!(m.count(Status::Ok), 200);
    let c = check_sweep(&out);
    assert_eq!(c["bags"], 200, "{c}");
    assert_eq!(c["errors"], serde_json::json!([]), "{c}");

    // Lose job 17 (bag and record) and leave a stale partial bag for job 42.
    let bag17 = out.join("jobs/000017.mcap");
    let bytes17 = std::fs::read(&bag17).unwrap();
    std::fs::remove_file(&bag17).unwrap();
    std::fs::remove_file(out.join("jobs/000042.json")).unwrap();
    std::fs::write(out.join("jobs/000042.mcap.part"), b"junk").unwrap();
    let kept = std::fs::metadata(out.join("jobs/000100.mcap"))
        .unwrap()
        .modified()
        .unwrap();
    let m = collect(&out).unwrap();
    assert_eq!(m.entries[17].status, Status::Failed, "{:?}", m.entries[17]);
    assert_eq!(m.entries[42].status, Status::Failed, "{:?}", m.entries[42]);
    let o = drape()
        .args(["sweep", "run", "--local", "-j", "2", "--quiet"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("2 ran, 198 already done"), "{text}");
    assert_eq!(
        std::fs::read(&bag17).unwrap(),
        bytes17,
        "a rerun gives the same bytes"
    );
    assert!(!out.join("jobs/000042.mcap.part").exists());
    assert_eq!(
        std::fs::metadata(out.join("jobs/000100.mcap"))
            .unwrap()
            .modified()
            .unwrap(),
        kept,
        "a done job was redone"
    );
    assert_eq!(collect(&out).unwrap().count(Status::Ok), 200);
}

/// A job stopped by SIGTERM removes its partial bag and records `failed`; one killed by SIGKILL
/// leaves only a `.part` (never a bag under its final name), which collect reports as failed;
/// a rerun finishes both.
#[cfg(unix)]
#[test]
fn killed_jobs_lose_only_themselves() {
    let dir = tempfile::tempdir().unwrap();
    let f = sweep_file(
        dir.path(),
        "three_corner_normal.yaml",
        "set:\n  cloths[0].grid.resolution: [6, 6]\ngrid:\n  duration: [0.1, 600.0, 600.0]\n",
    );
    let out = dir.path().join("out");
    let run = |i: usize| {
        drape()
            .args(["sweep", "run", "--quiet", "--index", &i.to_string()])
            .arg(&f)
            .spawn()
            .unwrap()
    };
    assert!(run(0).wait().unwrap().success());
    for (i, signal) in [(1, "-TERM"), (2, "-KILL")] {
        let mut child = run(i);
        let part = out.join(format!("jobs/{i:06}.mcap.part"));
        let t0 = Instant::now();
        while !part.exists() && t0.elapsed() < Duration::from_secs(30) {
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(Duration::from_millis(300));
        assert!(Command::new("kill")
            .arg(signal)
            .arg(child.id().to_string())
            .status()
            .unwrap()
            .success());
        let status = child.wait().unwrap();
        assert!(!status.success(), "{signal}: a stopped job must not exit 0");
        assert!(!out.join(format!("jobs/{i:06}.mcap")).exists());
    }
    assert!(
        !out.join("jobs/000001.mcap.part").exists(),
        "SIGTERM removes the partial bag"
    );
    assert!(out.join("jobs/000002.mcap.part").exists());
    let m = collect(&out).unwrap();
    let statuses: Vec<Status> = m.entries.iter().map(|e| e.status).collect();
    assert_eq!(statuses, [Status::Ok, Status::Failed, Status::Failed]);
    assert!(m.entries[1]
        .error
        .as_deref()
        .unwrap()
        .contains("interrupted"));
    assert!(m.entries[2]
        .error
        .as_deref()
        .unwrap()
        .contains("partial bag"));
    let csv = std::fs::read_to_string(&m.csv).unwrap();
    assert!(
        csv.starts_with("index,status,bag,size,sha256,error,param.duration,"),
        "{csv}"
    );

    // The rerun, with the long jobs made short, finishes the sweep and keeps job 0.
    let text = std::fs::read_to_string(&f).unwrap().replace("600.0", "0.1");
    std::fs::write(&f, text).unwrap();
    let kept = std::fs::metadata(out.join("jobs/000000.mcap"))
        .unwrap()
        .modified()
        .unwrap();
    let o = drape()
        .args(["sweep", "run", "--local", "-j", "2", "--quiet"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("2 ran, 1 already done"));
    assert_eq!(
        std::fs::metadata(out.join("jobs/000000.mcap"))
            .unwrap()
            .modified()
            .unwrap(),
        kept
    );
    assert_eq!(collect(&out).unwrap().count(Status::Ok), 3);
}

/// The same job index gives the same bag bytes on one and two threads, for an implicit cloth
/// large enough for the parallel solver paths and for a robot scene.
#[test]
fn same_bag_bytes_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    for (scene, body) in [
        (
            "three_corner_soft_warp.yaml",
            "set:\n  duration: 0.25\n  cloths[0].grid.resolution: [48, 48]\n",
        ),
        (
            "robot_towel.yaml",
            "set:\n  duration: 0.2\nrandom:\n  job.time_scale: { uniform: [0.8, 1.2] }\n",
        ),
    ] {
        let f = sweep_file(dir.path(), scene, body);
        let mut bags = Vec::new();
        for threads in ["1", "2"] {
            let out = dir.path().join(format!("t{threads}"));
            let o = drape()
                .args(["sweep", "run", "--quiet", "--index", "0", "--out"])
                .arg(&out)
                .arg(&f)
                .env("RAYON_NUM_THREADS", threads)
                .output()
                .unwrap();
            assert!(o.status.success(), "{scene}: {}", stderr(&o));
            bags.push(std::fs::read(out.join("jobs/000000.mcap")).unwrap());
            std::fs::remove_dir_all(&out).unwrap();
        }
        assert!(bags[0].len() > 1000);
        assert!(
            bags[0] == bags[1],
            "{scene}: bags differ between 1 and 2 threads"
        );
    }
}
