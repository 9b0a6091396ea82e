//! What a URDF became (`drape check`): links with their shapes and mesh triangle counts, links
//! skipped and why, joints with limits; and the cloth that starts inside an obstacle.

use drape::robot::{Robot, RobotSummary, ShapeSource, UrdfOptions};
use std::path::Path;
use std::process::Command;

const URDF: &str = r#"<robot name="probe">
  <link name="base"><collision><geometry><box size="0.2 0.4 0.6"/></geometry></collision></link>
  <link name="arm">
    <collision><geometry><capsule radius="0.03" length="0.2"/></geometry></collision>
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <link name="shell"><visual><geometry><cylinder radius="0.1" length="0.3"/></geometry></visual></link>
  <link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="2.5"/></joint>
  <joint name="j2" type="fixed"><parent link="arm"/><child link="shell"/></joint>
  <joint name="j3" type="fixed"><parent link="shell"/><child link="tool"/></joint>
</robot>"#;

fn summary(visual_fallback: bool) -> RobotSummary {
    let options = UrdfOptions {
        visual_fallback,
        ..UrdfOptions::default()
    };
    let robot = Robot::from_urdf_str(URDF, None, &options).expect("probe URDF loads");
    RobotSummary::of(&robot)
}

#[test]
fn links_say_where_their_shapes_came_from_or_why_they_have_none() {
    let s = summary(false);
    let sources: Vec<ShapeSource> = s.links.iter().map(|l| l.source).collect();
    assert_eq!(
        sources,
        [
            ShapeSource::Collision,
            ShapeSource::Collision,
            ShapeSource::SkippedVisualOnly,
            ShapeSource::SkippedNoGeometry
        ]
    );
    assert_eq!((s.obstacle_links(), s.shapes()), (2, 3));
    assert_eq!(s.links[1].shapes[0], "capsule r 0.030 length 0.200");
    assert_eq!(s.links[0].shapes[0], "box 0.200 x 0.400 x 0.600");
    let text = s.to_string();
    assert!(
        text.contains("link shell: skipped, no <collision> (it has <visual>"),
        "{text}"
    );
    assert!(text.contains("link tool: skipped, no geometry"), "{text}");
    assert!(
        text.contains(
            "joint j1 (revolute): base -> arm, limits [-1.000, 1.000], velocity limit 2.500"
        ),
        "{text}"
    );

    let with_visual = summary(true);
    assert_eq!(with_visual.links[2].source, ShapeSource::VisualFallback);
    assert_eq!(
        with_visual.links[2].shapes,
        ["cylinder r 0.100 length 0.300"]
    );
    assert_eq!(with_visual.obstacle_links(), 3);
}

fn check(scene: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["check", "--scene"])
        .arg(scene)
        .env("RUST_LOG", "error")
        .output()
        .expect("drape runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 output")
}

#[test]
fn drape_check_shows_the_bundled_robot_and_the_cloth_inside_its_base() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = check(&root.join("config/robot_cape.yaml"));
    // drape_bot: 16 links, two of them frames without geometry; the head is an STL mesh.
    assert!(
        text.contains("robot 'drape_bot': 16 links (14 obstacles, 14 shapes,"),
        "{text}"
    );
    let head = text
        .lines()
        .find(|l| l.starts_with("  link head: mesh "))
        .unwrap_or_else(|| panic!("no head mesh line in\n{text}"));
    let triangles: usize = head["  link head: mesh ".len()..]
        .split(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no triangle count in {head}"));
    assert!(triangles > 0, "{head}");
    assert!(
        text.contains("link right_tool_frame: skipped, no geometry"),
        "{text}"
    );
    assert!(
        text.contains("joint right_finger_b_joint (prismatic)") && text.contains("mimics"),
        "{text}"
    );
    // The bundled cape's hem rests exactly on the base box's top: on it, not inside.
    assert!(text.contains("no cloth vertex starts inside one"), "{text}");
    // Lowered 2 cm, its hem starts inside the base box (the start-inside report).
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = std::fs::read_to_string(root.join("config/robot_cape.yaml"))
        .expect("bundled scene")
        .replace("xyz: [-0.2, 0.0, 0.4]", "xyz: [-0.2, 0.0, 0.38]")
        .replace(
            "../urdf/drape_bot.urdf",
            &root.join("urdf/drape_bot.urdf").display().to_string(),
        );
    let lowered = dir.path().join("cape_lowered.yaml");
    std::fs::write(&lowered, scene).expect("scene written");
    let text = check(&lowered);
    assert!(
        text.contains("cloth vertices start inside obstacle 'base_link/0'"),
        "{text}"
    );

    // A scene without a robot prints no robot section.
    let plain = check(&root.join("config/hanging.yaml"));
    assert!(!plain.contains("robot '"), "{plain}");
}
