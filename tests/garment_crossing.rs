//! A garment sewn through itself is refused when it is built, naming the seam: a pillowcase of
//! two square panels, one above the other, sewn along two opposite edges. Sewn edge to facing
//! edge it is a tube, with no triangle crossing another; with one panel's sides swapped (each
//! edge sewn to the edge diagonally across), the seams pull the panels through each other.

#[path = "common/self_check.rs"]
mod self_check;

use drape::scene::{Scene, SceneError};

/// The pillowcase with its seams' `b` sides and orientation as given.
fn pillowcase(left_b: &str, right_b: &str, reversed: bool, self_collision: bool) -> String {
    format!(
        r#"
name: pillowcase
duration: 0.2
effects: [gravity, stretch, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 2 }}
garments:
  - name: case
    edge_length: 0.03
    material: {{ density: 0.2, stretch: 1000.0, bend_warp: 1.0e-4, bend_weft: 1.0e-4, damping: {{ spring: 0.05, air: 0.5 }}, thickness: 0.005 }}
    panels:
      - {{ name: top, outline: [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]], placement: {{ pose: {{ xyz: [0.0, 0.0, 0.03] }} }} }}
      - {{ name: bottom, outline: [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]], placement: {{ pose: {{ xyz: [0.0, 0.0, -0.03] }} }} }}
    seams:
      - {{ name: left, a: {{ panel: top, from: 3, to: 0 }}, b: {{ panel: bottom, {left_b} }}, reversed: {reversed} }}
      - {{ name: right, a: {{ panel: top, from: 1, to: 2 }}, b: {{ panel: bottom, {right_b} }}, reversed: {reversed} }}
    sewing: {{ stiffness: 2000.0, close_time: 0.5, tolerance: 0.001, max_time: 2.0 }}
collision: {{ mode: continuous, self_collision: {self_collision} }}
"#
    )
}

fn build(text: &str) -> Result<drape::sim::Simulation, SceneError> {
    Scene::from_yaml(text, "pillowcase.yaml")?.build()
}

/// The build's error with its causes, as `drape` prints them.
fn refused(text: &str, why: &str) -> String {
    match build(text) {
        Ok(_) => panic!("{why}"),
        Err(e) => {
            let mut msg = e.to_string();
            let mut source = std::error::Error::source(&e);
            while let Some(s) = source {
                msg += &format!(": {s}");
                source = s.source();
            }
            msg
        }
    }
}

#[test]
fn a_pillowcase_sewn_edge_to_facing_edge_welds_without_a_crossing() {
    for self_collision in [false, true] {
        let text = pillowcase("from: 3, to: 0", "from: 1, to: 2", false, self_collision);
        let sim = build(&text).unwrap_or_else(|e| panic!("{e:#}"));
        let n = self_check::intersecting_pairs(&sim.cloth.x, &sim.cloth.triangles);
        assert_eq!(n, 0, "self-collision {self_collision}");
    }
}

#[test]
fn a_pillowcase_sewn_through_itself_is_refused_naming_a_seam() {
    // Each top edge sewn to the bottom edge diagonally across, in the orientation that closes
    // without twisting: the panels pass through each other as the seams close.
    let text = pillowcase("from: 1, to: 2", "from: 3, to: 0", true, false);
    let msg = refused(&text, "a garment crossing itself must not build");
    assert!(
        msg.starts_with("pillowcase.yaml: garments[0].seams["),
        "the error names the file and the seam's key: {msg}"
    );
    assert!(
        msg.contains("sewn through itself") && msg.contains("at seam '"),
        "the error says what is wrong and where: {msg}"
    );
}

#[test]
fn with_self_collision_the_crossing_seams_stay_open_and_are_named() {
    // Self-collision keeps the panels from passing through each other: the seams cannot close.
    let text = pillowcase("from: 1, to: 2", "from: 3, to: 0", true, true);
    let msg = refused(&text, "the seams cannot close");
    assert!(
        msg.starts_with("pillowcase.yaml: garments[0].seams[") && msg.contains("gap"),
        "{msg}"
    );
}
