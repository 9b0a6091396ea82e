//! `drape sweep emit k8s`: the Indexed Job manifest validates against the Kubernetes Job schema
//! (`kubernetes-validate --strict`, from tests/py/requirements.txt; no cluster needed) and runs
//! one completion per job with the index the Job controller gives each pod.
#![cfg(feature = "ros")]

use std::path::Path;
use std::process::Command;

#[test]
fn indexed_job_manifest_validates_against_the_job_schema() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/three_corner_soft_warp.yaml");
    let sweep = dir.path().join("materials.yaml");
    std::fs::write(
        &sweep,
        format!(
            "name: Three corner materials\nscene: {}\nsamples: 4\n\
             grid:\n  cloths[0].material.bend_warp: [1.0e-4, 1.0e-3, 2.0e-3]\n",
            scene.display()
        ),
    )
    .unwrap();
    let manifest = dir.path().join("job.yaml");
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["sweep", "emit", "k8s"])
        .arg(&sweep)
        .arg("--manifest")
        .arg(&manifest)
        .args(["--image", "ghcr.io/example/drape:0.1", "--parallelism", "4"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&manifest).unwrap();
    let v: serde_yaml_ng::Value = serde_yaml_ng::from_str(&text).unwrap();
    assert_eq!(v["kind"].as_str(), Some("Job"));
    assert_eq!(
        v["metadata"]["name"].as_str(),
        Some("drape-three-corner-materials")
    );
    let spec = &v["spec"];
    assert_eq!(spec["completionMode"].as_str(), Some("Indexed"));
    assert_eq!(spec["completions"].as_u64(), Some(12));
    assert_eq!(spec["parallelism"].as_u64(), Some(4));
    let args: Vec<&str> = spec["template"]["spec"]["containers"][0]["args"]
        .as_sequence()
        .unwrap()
        .iter()
        .filter_map(|a| a.as_str())
        .collect();
    assert!(args.contains(&"$(JOB_COMPLETION_INDEX)"), "{args:?}");
    assert!(args.contains(&"/data/materials.yaml"), "{args:?}");

    let check = Command::new("kubernetes-validate")
        .args(["--strict", "--quiet"])
        .arg(&manifest)
        .output();
    let check = match check {
        Ok(c) => c,
        Err(e) => {
            panic!("kubernetes-validate is missing ({e}): pip install -r tests/py/requirements.txt")
        }
    };
    assert!(
        check.status.success(),
        "the manifest does not validate:\n{}{}\n{text}",
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&check.stderr)
    );

    // A broken manifest does not validate (the check is real).
    let bad = dir.path().join("bad.yaml");
    std::fs::write(&bad, text.replace("completionMode", "completionModes")).unwrap();
    let o = Command::new("kubernetes-validate")
        .args(["--strict", "--quiet"])
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!o.status.success());
}
