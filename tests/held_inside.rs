//! Held cloth driven into a solid is reported, not silent: kinematic vertices (pinned,
//! attached, grasped) inside an obstacle at a step's end are counted in `StepMetrics` with
//! their depth (no response can move them), and the frame's `/diagnostics` status warns.

#[path = "common/finger_rule.rs"]
mod finger_rule;

use drape::scene::Scene;
use std::path::Path;

/// A 0.2 m sheet hanging from its two top corners, with a 0.1 m box whose top face is at
/// `box_top` (m) around the top-left corner, which sits at z = 1.
fn pinned_sheet(box_top: f64) -> Scene {
    let yaml = format!(
        r#"
name: pinned_in_a_box
duration: 0.1
effects: [gravity, stretch, shear, bending]
solver: {{ integrator: implicit, dt: 0.01, substeps: 1 }}
cloths:
  - name: sheet
    grid: {{ size: [0.2, 0.2], resolution: [9, 9], pose: {{ xyz: [0.1, 0, 0.9], rpy: [1.5707963267948966, 0, 0] }} }}
    material: {{ thickness: 0.002 }}
    pins: [ {{ region: top_left }}, {{ region: top_right }} ]
obstacles:
  - {{ name: block, shape: {{ type: box, half_extents: [0.05, 0.05, 0.05] }}, pose: {{ xyz: [0, 0, {z}] }} }}
collision: {{ mode: continuous }}
"#,
        z = box_top - 0.05
    );
    Scene::from_yaml(&yaml, "pinned_in_a_box").unwrap_or_else(|e| panic!("{e}"))
}

/// A corner pinned 1 cm below a box's top face is one held vertex 1 cm inside it; pinned 1 cm
/// above, none is.
#[test]
fn a_corner_pinned_inside_a_box_is_counted_with_its_depth() {
    for (box_top, count, depth) in [(1.01, 1, 0.01), (0.99, 0, 0.0)] {
        let mut sim = pinned_sheet(box_top)
            .build()
            .unwrap_or_else(|e| panic!("{e}"));
        let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.held_inside, count, "box top at {box_top}");
        assert!(
            (m.held_inside_depth - depth).abs() < 1e-9,
            "box top at {box_top}: depth {}",
            m.held_inside_depth
        );
    }
}

/// A grasp rule whose fingers keep closing past the cloth they hold (drape_bot's pick by
/// contact with a rule added, the fingers closed onto the overhang): the held strip lies
/// tilted across the pads and the closing fingers reach its vertices, which the metric reports
/// from the first frames after the grasp.
#[test]
fn fingers_closing_past_the_cloth_a_rule_holds_are_reported() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/robot_pinch_towel.yaml");
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let robot = scene.robot.as_mut().expect("a robot");
    robot.grasps.push(finger_rule::between_the_fingers());
    let (mut sim, driver) = scene.build_with_robot().unwrap_or_else(|e| panic!("{e}"));
    let mut driver = driver.expect("a robot");
    let dt = sim.settings.dt;
    let mut first_reported = None;
    while sim.time() < 1.45 && first_reported.is_none() {
        let t = sim.time() + dt;
        driver.advance(&mut sim, t);
        let m = sim.step().unwrap_or_else(|e| panic!("t = {t:.3}: {e}"));
        if m.held_inside > 0 {
            assert!(m.held_inside_depth > 0.0);
            first_reported = Some(t);
        }
    }
    assert!(
        first_reported.is_some(),
        "no held vertex reported inside a finger by t = 1.45 s"
    );
}
