//! Overhead of the sweep machinery: the same recordings run by `drape sweep run --local -j 1`
//! (plan checks, one process per job, sha256, result records, the manifest) and one by one with
//! `drape record` on the jobs' scenes. Prints both wall times and the overhead in percent
//! (the target is under 2 %). Run on an idle machine: `cargo bench --bench sweep`.
//! `DRAPE_SWEEP_BENCH_JOBS` (default 8) and `DRAPE_SWEEP_BENCH_DURATION` (default 2.0 s of
//! simulated time per job) size it.

use drape::sweep::Sweep;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

fn main() {
    let jobs: usize = std::env::var("DRAPE_SWEEP_BENCH_JOBS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(8);
    let duration: f64 = std::env::var("DRAPE_SWEEP_BENCH_DURATION")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2.0);
    let exe = env!("CARGO_BIN_EXE_drape");
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/three_corner_normal.yaml");
    let sweep_path = dir.path().join("bench.yaml");
    std::fs::write(
        &sweep_path,
        format!(
            "name: bench\nscene: {}\nsamples: {jobs}\nset:\n  duration: {duration}\n  \
             cloths[0].grid.resolution: [24, 24]\nrandom:\n  \
             cloths[0].material.stretch: {{ uniform: [1000, 3000] }}\n",
            scene.display()
        ),
    )
    .expect("sweep file");
    let sweep = Sweep::load(&sweep_path).expect("sweep loads");
    // The jobs' scenes as plain scene files, for `drape record`.
    let mut scenes = Vec::new();
    for i in 0..jobs {
        let spec = sweep
            .job_spec(&sweep.job(i).expect("job"))
            .expect("job scene");
        let p = dir.path().join(format!("job{i}.yaml"));
        std::fs::write(&p, serde_yaml_ng::to_string(&spec.scene).expect("yaml")).expect("write");
        scenes.push(p);
    }
    let mut best_sweep = f64::INFINITY;
    let mut best_record = f64::INFINITY;
    for round in 0..3 {
        let out = dir.path().join(format!("sweep{round}"));
        let t = Instant::now();
        let ok = Command::new(exe)
            .args(["sweep", "run", "--local", "-j", "1", "--quiet", "--out"])
            .arg(&out)
            .arg(&sweep_path)
            .status()
            .expect("sweep runs")
            .success();
        assert!(ok, "the sweep failed");
        best_sweep = best_sweep.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        for (i, s) in scenes.iter().enumerate() {
            let ok = Command::new(exe)
                .args(["record", "--quiet", "--scene"])
                .arg(s)
                .arg("--out")
                .arg(dir.path().join(format!("rec{round}_{i}.mcap")))
                .stdout(std::process::Stdio::null())
                .status()
                .expect("record runs")
                .success();
            assert!(ok, "drape record failed");
        }
        best_record = best_record.min(t.elapsed().as_secs_f64());
    }
    println!(
        "{jobs} jobs of {duration} s: one by one {best_record:.3} s, sweep {best_sweep:.3} s \
         (best of 3): overhead {:+.2} %",
        (best_sweep / best_record - 1.0) * 100.0
    );
}
