//! A strip lying on a table with part of it hanging over the table's (sharp, box) edge: the
//! hanging weight pulls the rest over the edge against Coulomb friction. With `l` of length `L`
//! hanging, per unit width and weight, the pull at the edge is `l`, reduced by the capstan
//! effect of the 90-degree wrap to `l exp(-mu pi / 2)`, against `mu (L - l)` on the table top:
//!
//! - it stays for any edge friction when `l <= mu (L - l)`;
//! - it slides off when `l exp(-mu pi / 2) > mu (L - l)`.

use drape::scene::Scene;

const L: f64 = 1.0;
const MU: f64 = 0.2;

/// How far the strip's far end (on the table) moved towards the edge after `seconds` (m), and the
/// farthest it got on the way (m): once the far end passes the edge the strip has left the table
/// (it then falls and swings back under the edge).
fn strip(hanging: f64, mu: f64, seconds: f64) -> (f64, f64) {
    let th = 0.004;
    let yaml = format!(
        r#"
name: strip
duration: {seconds}
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 2 }}
cloths:
  - name: strip
    grid: {{ size: [{L}, 0.1], resolution: [40, 5], pose: {{ xyz: [{cx}, 0.0, {th}] }} }}
    material:
      density: 0.2
      stretch: 2000.0
      shear: 200.0
      bend_warp: 1.0e-6
      bend_weft: 1.0e-6
      damping: {{ spring: 0.05, air: 0.5 }}
      thickness: {th}
      friction: {mu}
obstacles:
  - {{ name: table, shape: {{ type: box, half_extents: [1.0, 0.5, 0.5] }}, pose: {{ xyz: [-1.0, 0.0, -0.5] }} }}
collision: {{ mode: continuous }}
"#,
        // The hanging part starts level with the table top beyond the edge (x > 0) and falls.
        cx = hanging - L / 2.0,
    );
    let scene = Scene::from_yaml(&yaml, "table_edge").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    let far_end = |sim: &drape::sim::Simulation| {
        sim.cloth
            .x
            .iter()
            .map(|p| p.x)
            .fold(f64::INFINITY, f64::min)
    };
    let start = far_end(&sim);
    let mut farthest: f64 = 0.0;
    for _ in 0..(seconds / sim.settings.dt).round() as usize {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
        farthest = farthest.max(far_end(&sim) - start);
    }
    (far_end(&sim) - start, farthest)
}

/// The far end's start distance from the edge (m) for `hanging` of the strip over it.
fn on_table(hanging: f64) -> f64 {
    L - hanging
}

/// 12 % hanging: `0.12 < mu (L - l) = 0.176`, so even a frictionless edge holds it. It may
/// shift while the hanging part falls and swings (a few mm), never slide.
#[test]
fn a_strip_with_little_hanging_stays_on_the_table() {
    let (moved, _) = strip(0.12, MU, 2.0);
    assert!(moved.abs() < 0.01, "moved {moved:.4} m");
}

/// Without friction anything hanging pulls the strip off: the sharp edge's geometric response
/// alone must not hold it. This checks the verdict (the far end passes the edge: the strip left
/// the table), not the speed: an ideal string hanging 30 % would be off in 0.6 s
/// (`l = 0.3 cosh(sqrt(g / L) t)`), ~1 s with the fall of the part that starts level with the
/// table; measured 1.4 s.
#[test]
fn a_frictionless_strip_slides_off_the_table() {
    let (_, farthest) = strip(0.3, 0.0, 3.0);
    assert!(
        farthest > on_table(0.3),
        "far end got {farthest:.4} m of {:.2} m",
        on_table(0.3)
    );
}

/// 45 % hanging at mu 0.2: pull `0.45 exp(-0.1 pi) = 0.33` against `mu (L - l) = 0.11`, so the
/// strip slides off: an ideal string would accelerate at about `g (0.33 - 0.11) / L = 2 m/s^2`
/// and be off in ~1 s after the hanging part's fall. Measured 2.3 s: the strip slides at a near
/// steady 0.3 m/s, the coarse strip (2.5 cm segments) flapping on the table next to the edge,
/// where its landings take about half the work gravity does (docs/guide/collision.md, known
/// limits). A push by position at the edge would stretch the strip over it (several newtons of
/// tension against 0.09 N of hanging weight) and glue it to the table; the edge's contact is
/// solved with the tension instead. The verdict is what this checks, with 3 s to reach it.
#[test]
fn a_strip_with_a_heavy_hanging_part_slides_off_the_table() {
    let (_, farthest) = strip(0.45, MU, 3.0);
    assert!(
        farthest > on_table(0.45),
        "far end got {farthest:.4} m of {:.2} m",
        on_table(0.45)
    );
}
