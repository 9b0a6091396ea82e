//! Cross-checks our forward kinematics against an independent URDF implementation (yourdfpy,
//! driven by tests/py/fk_reference.py) on real robots from `pybullet_data` and the bundled
//! drape_bot, at 20 random in-limit configurations each. Agreement: 1e-6 m and 1e-6 rad
//! (both sides are f64; the observed gap is ~1e-15 m and ~1e-15 rad).

use drape::robot::{JointKind, JointPositions, Robot, UrdfOptions};
use drape::Pose;
use glam::{DMat3, DQuat, DVec3};
use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

const TOL_M: f64 = 1e-6;
const TOL_RAD: f64 = 1e-6;
const CONFIGS: usize = 20;
const PIP_HINT: &str = "pip install pybullet yourdfpy";

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/fk_reference.py")
}

/// Runs the reference script; any failure to run it fails the test with the pip hint.
fn run_python(args: &[&str]) -> String {
    let out = Command::new("python3")
        .arg(script())
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run python3 ({e}); install Python 3 and `{PIP_HINT}`"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "FK reference failed ({}). If a module is missing: `{PIP_HINT}`.\n{stderr}",
        out.status
    );
    String::from_utf8(out.stdout).expect("reference output is UTF-8")
}

fn pybullet_data() -> PathBuf {
    PathBuf::from(run_python(&["--data-path"]).trim())
}

/// Deterministic xorshift so the configurations are reproducible without a rand dependency.
struct Rng(u64);
impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

fn random_configs(robot: &Robot, seed: u64) -> Vec<(String, JointPositions)> {
    let kin = robot.kinematics();
    let mut rng = Rng(seed);
    (0..CONFIGS)
        .map(|_| {
            let mut q = kin.zero_positions();
            let mut line = String::new();
            for (ji, j) in kin.actuated_joints() {
                let (lo, hi) = match (j.limits, j.kind) {
                    (Some(l), _) => l,
                    (None, JointKind::Prismatic) => (-0.5, 0.5),
                    (None, _) => (-std::f64::consts::PI, std::f64::consts::PI),
                };
                let v = rng.uniform(lo, hi);
                q.positions[ji] = v;
                line.push_str(&format!("{}={:e} ", j.name, v));
            }
            (line, q)
        })
        .collect()
}

fn parse_reference(text: &str) -> Vec<HashMap<String, Pose>> {
    let mut out: Vec<HashMap<String, Pose>> = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let mut it = line.split_whitespace();
        let idx: usize = it
            .next()
            .and_then(|s| s.parse().ok())
            .expect("config index");
        let link = it.next().expect("link name").to_string();
        let m: Vec<f64> = it.map(|s| s.parse().expect("number")).collect();
        assert_eq!(m.len(), 12, "bad reference line: {line}");
        let rot = DMat3::from_cols(
            DVec3::new(m[0], m[4], m[8]),
            DVec3::new(m[1], m[5], m[9]),
            DVec3::new(m[2], m[6], m[10]),
        );
        let pose = Pose::new(
            DVec3::new(m[3], m[7], m[11]),
            DQuat::from_mat3(&rot).normalize(),
        );
        if out.len() <= idx {
            out.resize(idx + 1, HashMap::new());
        }
        out[idx].insert(link, pose);
    }
    out
}

fn check_robot(urdf: &Path, seed: u64) {
    let options = UrdfOptions {
        use_ros_env: false,
        ..Default::default()
    };
    let robot = Robot::from_urdf_file(urdf, &options)
        .unwrap_or_else(|e| panic!("loading {}: {e}", urdf.display()));
    let configs = random_configs(&robot, seed);
    let mut file = tempfile::NamedTempFile::new().expect("temp file");
    for (line, _) in &configs {
        writeln!(file, "{line}").expect("write configs");
    }
    let cfg_path = file.path().to_str().expect("utf-8 temp path").to_string();
    let urdf_str = urdf.to_str().expect("utf-8 urdf path");
    let reference = parse_reference(&run_python(&[urdf_str, &cfg_path]));
    assert_eq!(reference.len(), CONFIGS, "{}", urdf.display());

    let mut poses = Vec::new();
    let (mut worst_m, mut worst_rad) = (0.0f64, 0.0f64);
    for (k, (_, q)) in configs.iter().enumerate() {
        let report = robot.link_poses_into(q, &mut poses);
        assert!(
            report.is_clean(),
            "in-limit configuration reported {report:?}"
        );
        assert_eq!(
            reference[k].len(),
            robot.link_names().len(),
            "link sets differ"
        );
        for (li, name) in robot.link_names().iter().enumerate() {
            let want = reference[k]
                .get(name)
                .unwrap_or_else(|| panic!("reference lacks link {name}"));
            let got = poses[li];
            let dm = (got.translation - want.translation).length();
            // 2 asin |vec(q1^-1 q2)| keeps full precision near zero (acos of the dot does not).
            let drad = 2.0
                * (got.rotation.inverse() * want.rotation)
                    .xyz()
                    .length()
                    .min(1.0)
                    .asin();
            worst_m = worst_m.max(dm);
            worst_rad = worst_rad.max(drad);
            assert!(
                dm < TOL_M && drad < TOL_RAD,
                "{} config {k} link {name}: position off by {dm:e} m, rotation by {drad:e} rad",
                urdf.display()
            );
        }
    }
    eprintln!(
        "{}: {} links x {CONFIGS} configs, worst {worst_m:e} m / {worst_rad:e} rad",
        urdf.display(),
        robot.link_names().len()
    );
}

#[test]
fn fk_matches_reference_panda() {
    check_robot(
        &pybullet_data().join("franka_panda/panda.urdf"),
        0x5eed_0001,
    );
}

#[test]
fn fk_matches_reference_kuka_iiwa() {
    check_robot(&pybullet_data().join("kuka_iiwa/model.urdf"), 0x5eed_0002);
}

#[test]
fn fk_matches_reference_xarm6() {
    check_robot(&pybullet_data().join("xarm/xarm6_robot.urdf"), 0x5eed_0003);
}

#[test]
fn fk_matches_reference_drape_bot() {
    check_robot(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/drape_bot.urdf"),
        0x5eed_0004,
    );
}

/// pybullet's humanoid ends in a NUL byte and uses non-standard `spherical` joints (loaded as
/// free joints that default to identity and are reported).
#[test]
fn humanoid_with_trailing_nul_and_spherical_joints_loads() {
    let path = pybullet_data().join("humanoid/humanoid.urdf");
    let options = UrdfOptions {
        use_ros_env: false,
        ..Default::default()
    };
    let robot = Robot::from_urdf_file(&path, &options).unwrap_or_else(|e| panic!("{e}"));
    let mut out = Vec::new();
    let report = robot.link_poses_into(&robot.zero_positions(), &mut out);
    assert_eq!(report.free_defaulted.len(), 8, "{report:?}");
    assert!(out.iter().all(|p| p.is_finite()));
}
