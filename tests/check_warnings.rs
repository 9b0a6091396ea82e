//! `drape check`'s warnings (`src/scene/lint.rs`) through the built binary: degrees written
//! where radians belong and a towel attached two metres from its link (and so far from every
//! link) are named by key, the
//! check still succeeds, `--links` prints the poses the library computes, and every bundled
//! scene checks without a warning.

use drape::scene::{lint, Scene};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn drape(args: &[&str], scene: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .arg(scene)
        .env("RUST_LOG", "error")
        .output()
        .unwrap()
}

/// `config/robot_towel.yaml` with its URDF named absolutely, so it can live in a temp folder,
/// and `edit` applied to its text.
fn towel_scene(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(root().join("config/robot_towel.yaml")).unwrap();
    let urdf = root().join("urdf/drape_bot.urdf");
    let text = text.replace("../urdf/drape_bot.urdf", &urdf.display().to_string());
    let path = dir.join("towel.yaml");
    std::fs::write(&path, edit(text)).unwrap();
    path
}

/// The number that follows `prefix` in a warning line (up to the next space).
fn number_after(line: &str, prefix: &str) -> f64 {
    line.split(prefix)
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no number after {prefix:?} in {line}"))
}

const POSE: &str = "pose: { xyz: [0.879, -0.255, 0.392], rpy: [1.5707963267948966, 0.0, 0.0] }";
const ATTACH: &str = "near: { point: [0.0, 0.0, -0.13], radius: 0.03 }";

#[test]
fn degrees_and_a_towel_two_metres_from_its_link_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    // The towel two metres along y from where the gripper holds it, attached by its corner,
    // its orientation written in degrees.
    let scene = towel_scene(dir.path(), |t| {
        t.replace(
            POSE,
            "pose: { xyz: [0.879, 1.745, 0.392], rpy: [90, 0, 90] }",
        )
        .replace(ATTACH, "region: top_left")
    });
    let o = drape(&["check"], &scene);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "warnings are not errors\n{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let warnings: Vec<&str> = out.lines().filter(|l| l.starts_with("warning:")).collect();
    let file = scene.display().to_string();
    for key in [
        "cloths[0].grid.pose.rpy[0]: 90 rad",
        "cloths[0].grid.pose.rpy[2]: 90 rad",
    ] {
        assert!(
            warnings
                .iter()
                .any(|w| w.starts_with(&format!("warning: {file}: {key}"))),
            "no {key}\n{out}"
        );
    }
    let attach: Vec<&&str> = warnings
        .iter()
        .filter(|w| w.contains("robot.attach[0]: the attached vertices are"))
        .collect();
    assert_eq!(attach.len(), 1, "{out}");
    assert!(attach[0].contains("from link `right_palm`"), "{out}");
    // The distance printed is the corner's, about two metres (the towel moved 2 m).
    let metres = number_after(attach[0], "are ");
    assert!((1.8..2.2).contains(&metres), "{metres}\n{out}");
    // Two metres off, the towel is also more than a metre from every link: true, and said.
    assert!(
        warnings
            .iter()
            .any(|w| w
                .contains("cloths[0].grid.pose: no obstacle or robot link within 1.00 m at t = 0")),
        "{out}"
    );
    assert_eq!(warnings.len(), 4, "{out}");

    // The same scene as `--scene`: the same report.
    let flag = drape(&["check", "--scene"], &scene);
    assert_eq!(String::from_utf8_lossy(&flag.stdout), out);
}

#[test]
fn a_correct_scene_has_no_warning_and_links_prints_the_poses() {
    let dir = tempfile::tempdir().unwrap();
    let scene = towel_scene(dir.path(), |t| t);
    let o = drape(&["check", "--links"], &scene);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}");
    assert!(!out.contains("warning:"), "{out}");
    assert!(out.contains("no warnings"), "{out}");
    // Every link's line against the library's forward kinematics at t = 0.
    let s = Scene::load(&scene).unwrap();
    let (_, driver) = s.build_with_robot().unwrap();
    let d = driver.unwrap();
    assert!(
        out.contains("link poses at t = 0 (world frame: the root link `base_link`):"),
        "{out}"
    );
    for (name, pose) in d.robot().link_names().iter().zip(d.link_poses()) {
        let line = out
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name}: ")))
            .unwrap_or_else(|| panic!("no line for {name}\n{out}"));
        let numbers: Vec<f64> = line
            .split(['[', ']', ','])
            .filter_map(|x| x.trim().parse().ok())
            .collect();
        assert_eq!(numbers.len(), 6, "{line}");
        let (xyz, rpy) = numbers.split_at(3);
        let back = drape::Pose::from_xyz_rpy([xyz[0], xyz[1], xyz[2]], [rpy[0], rpy[1], rpy[2]]);
        assert!(
            (back.translation - pose.translation).length() < 1e-3,
            "{line}"
        );
        assert!(back.rotation.angle_between(pose.rotation) < 1e-3, "{line}");
    }
}

#[test]
fn bundled_scenes_give_no_warnings() {
    let mut checked = 0;
    let mut entries: Vec<PathBuf> = std::fs::read_dir(root().join("config"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .filter(|p| p.file_name().is_some_and(|n| n != "node.yaml"))
        .collect();
    entries.sort();
    let mut found = Vec::new();
    for path in &entries {
        let s = Scene::load(path).unwrap();
        let (sim, driver) = s.build_with_robot().unwrap();
        for w in lint(&s, &sim, driver.as_ref()) {
            found.push(format!("{}: {w}", path.display()));
        }
        checked += 1;
    }
    assert!(checked >= 15, "{checked} scenes");
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// A sheet laid through a closed mesh (drape_bot's head, an ellipsoid 9 x 8 x 11 cm) is warned
/// about by the mesh's winding number, naming the cloth, the mesh and how many vertices start
/// inside it (the contact stage sees a mesh as a surface and would not lead them out); laid
/// beside it, nothing is.
#[test]
fn a_cloth_laid_through_a_mesh_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    // Meshes are read only from the scene's folder.
    std::fs::copy(
        root().join("urdf/meshes/head.stl"),
        dir.path().join("head.stl"),
    )
    .unwrap();
    for (z, inside) in [(0.0, true), (0.2, false)] {
        let path = dir.path().join("through.yaml");
        std::fs::write(
            &path,
            format!(
                r#"
name: through_a_mesh
duration: 0.1
effects: [gravity, stretch]
solver: {{ integrator: implicit, dt: 0.01 }}
cloths:
  - name: sheet
    grid: {{ size: [0.3, 0.3], resolution: [31, 31], pose: {{ xyz: [0, 0, {z}] }} }}
obstacles:
  - {{ name: head, shape: {{ type: mesh, path: head.stl }}, pose: {{ xyz: [0, 0, 0] }} }}
"#
            ),
        )
        .unwrap();
        let o = drape(&["check"], &path);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{out}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let warned = out.lines().any(|l| {
            l.starts_with("warning:")
                && l.contains("cloths[0]")
                && l.contains("inside the mesh `head`")
        });
        assert_eq!(warned, inside, "sheet at z = {z}:\n{out}");
    }
}

/// A one-joint arm that swings the corner it holds through a post of its own robot (the held
/// point 0.5 m out on the arm, the post 0.5 m along y from the joint): `drape check` names the
/// attachment, the post and when, as a user would be told that their trajectory drags held
/// cloth through the robot; swung only half as far, the held corner stays clear and nothing is
/// said.
#[test]
fn held_cloth_swung_through_another_link_of_the_robot_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("arm.urdf"),
        r#"<robot name="arm">
  <link name="base">
    <collision><origin xyz="0 0.5 0"/><geometry><box size="0.1 0.1 0.4"/></geometry></collision>
  </link>
  <link name="arm">
    <collision><origin xyz="0.2 0 0"/><geometry><box size="0.4 0.02 0.02"/></geometry></collision>
  </link>
  <joint name="swing" type="revolute">
    <parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-3.14" upper="3.14" effort="10" velocity="2.0"/>
  </joint>
</robot>
"#,
    )
    .unwrap();
    for (angle, through) in [
        (std::f64::consts::FRAC_PI_2, true),
        (std::f64::consts::FRAC_PI_4, false),
    ] {
        let path = dir.path().join("swing.yaml");
        std::fs::write(
            &path,
            format!(
                r#"
name: swing
duration: 1.5
effects: [gravity, stretch]
solver: {{ integrator: implicit, dt: 0.01 }}
cloths:
  - name: towel
    grid: {{ size: [0.1, 0.1], resolution: [6, 6], pose: {{ xyz: [0.55, 0.0, -0.05], rpy: [{upright}, 0.0, 0.0] }} }}
robot:
  urdf: arm.urdf
  trajectory:
    names: [swing]
    points:
      - {{ t: 0.0, positions: [0.0] }}
      - {{ t: 1.0, positions: [{angle}] }}
  attach:
    - {{ cloth: towel, link: arm, near: {{ point: [0.5, 0.0, 0.0], radius: 0.015 }} }}
"#,
                upright = std::f64::consts::FRAC_PI_2
            ),
        )
        .unwrap();
        let o = drape(&["check"], &path);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{out}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let held: Vec<&str> = out
            .lines()
            .filter(|l| l.starts_with("warning:") && l.contains("robot.attach[0]"))
            .collect();
        if through {
            assert_eq!(held.len(), 1, "{out}");
            assert!(held[0].contains("inside its link `base`"), "{out}");
            // The held corner enters the 10 cm post where the arm has turned by
            // atan(0.05 / 0.5) short of a quarter turn, and is deepest at the end, 5 cm in.
            let first = number_after(held[0], "from t = ");
            let enters = 1.0 - (0.05f64 / 0.5).atan() / std::f64::consts::FRAC_PI_2;
            assert!((first - enters).abs() < 0.02, "{first} vs {enters}\n{out}");
            assert!(held[0].contains("0.05"), "{out}");
        } else {
            assert!(held.is_empty(), "{out}");
        }
    }
}
