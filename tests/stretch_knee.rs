//! Stretch that stiffens inside the implicit solve (`material.stretch_knee`, see
//! `effects/springs.rs`), run as a user would: scene files through `Simulation`, judged on the
//! state every frame step ends in by the largest mesh edge length over its rest length.
//!
//! - the peers' drape on a sphere (benchmark scene S1) with a knee at 3 %;
//! - a stiff tarp (stretch 1e5 N/m) falling onto a box turning at 1.5 rad/s, implicit at 1/30 s;
//! - the bundled cloth dropped on a ball with self-collision on, folding onto itself;
//! - every bundled scene with self-collision on and a knee at 3 % on every material;
//! - the scene keys checked with the file and key named.
//!
//! The sheet pinned at its corners and hit by rods is in `tests/fast_links.rs`.

#[path = "common/self_check.rs"]
mod self_check;

use drape::scene::Scene;
use drape::sim::Simulation;
use std::path::{Path, PathBuf};

/// Largest mesh edge length over rest length (rest: the grid's `(u, v)`).
fn worst_edge(sim: &Simulation) -> f64 {
    1.0 + sim.cloth.max_edge_stretch()
}

/// The worst edge over `frames` frame ends, and the frame it was at.
fn worst_over(sim: &mut Simulation, frames: usize) -> (f64, usize) {
    let mut w = (0.0, 0);
    for f in 0..frames {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
        let r = worst_edge(sim);
        if r > w.0 {
            w = (r, f + 1);
        }
    }
    w
}

fn bench_scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("benches/scenes")
        .join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// S1 (a 1 m cloth dropped onto a sphere, `benches/scenes/bench_s1.yaml`) at `res` vertices a
/// side with the knee `knee`, over its whole run: the worst frame's edge.
fn sphere_drape(res: usize, knee: Option<f64>) -> (f64, usize) {
    let mut scene = bench_scene("bench_s1.yaml");
    scene.cloths[0].grid.resolution = [res, res];
    scene.cloths[0].material.stretch_knee = knee;
    let frames = (scene.duration / scene.solver.dt).round() as usize;
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    worst_over(&mut sim, frames)
}

/// The bundled cloth dropped on a ball (`config/sphere_drape.yaml`, 1.2 m, 32x32) with
/// self-collision on and a knee at 3 %: its free edges fold over as it lands, and cloth-cloth
/// repulsion pushes them apart; held to the knee like the obstacles' answers, every frame end
/// stays within 1.05 of rest (unheld, one repulsion took a rim edge to 1.14) and no triangle
/// pair intersects.
#[test]
fn a_cloth_folding_onto_itself_on_a_ball_stays_near_its_knee() {
    let mut scene = self_check::bundled("sphere_drape.yaml", 1);
    scene.cloths[0].material.stretch_knee = Some(0.03);
    scene.collision.count_self_intersections = true;
    let frames = (scene.duration / scene.solver.dt).round() as usize;
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    let (mut worst, mut at) = (0.0, 0);
    for f in 0..frames {
        let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.self_intersections, Some(0), "frame {}", f + 1);
        let r = worst_edge(&sim);
        if r > worst {
            (worst, at) = (r, f + 1);
        }
    }
    eprintln!("sphere_drape, self-collision, knee 3 %: worst edge {worst:.4} at frame {at}");
    assert!(worst <= 1.05, "worst edge {worst:.4} at frame {at}");
}

/// The peers' drape on a sphere at 32x32 with a knee at 3 %: every frame end within 1.05.
#[test]
fn a_sheet_dropped_on_a_sphere_stays_near_its_knee() {
    let (knee, at) = sphere_drape(32, Some(0.03));
    eprintln!("S1 32x32, knee 3 %: worst edge {knee:.4} at frame {at}");
    assert!(knee <= 1.05, "worst edge {knee:.4} at frame {at}");
}

/// The same at the benchmark's 64x64, with the linear material's figure beside it.
#[test]
#[ignore = "64x64 over 2 s: a minute in debug"]
fn a_sheet_dropped_on_a_sphere_stays_near_its_knee_at_64() {
    let (linear, lat) = sphere_drape(64, None);
    let (knee, at) = sphere_drape(64, Some(0.03));
    eprintln!("S1 64x64: linear {linear:.4} (frame {lat}), knee 3 % {knee:.4} (frame {at})");
    assert!(knee <= 1.05, "worst edge {knee:.4} at frame {at}");
}

/// A stiff tarp (1.2 m, 40x40, stretch 1e5 N/m) dropped onto a 0.6 m box turning about the
/// vertical at 1.5 rad/s, implicit at dt 1/30 s, for 2 s.
fn tarp(knee: Option<f64>) -> String {
    let knee = knee.map_or(String::new(), |k| format!("      stretch_knee: {k}\n"));
    format!(
        r#"
name: tarp
duration: 2.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.03333333333333333, substeps: 1 }}
cloths:
  - name: tarp
    grid: {{ size: [1.2, 1.2], resolution: [40, 40], pose: {{ xyz: [0.0, 0.0, 0.7] }} }}
    material:
      density: 0.3
      stretch: 1.0e5
      shear: 1.0e4
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      thickness: 0.005
      friction: 0.4
{knee}obstacles:
  - name: box
    shape: {{ type: box, half_extents: [0.3, 0.3, 0.2] }}
    pose: {{ xyz: [0.0, 0.0, 0.2] }}
    motion: {{ type: velocity, linear: [0.0, 0.0, 0.0], angular: [0.0, 0.0, 1.5] }}
  - {{ name: floor, shape: {{ type: plane, normal: [0.0, 0.0, 1.0] }} }}
collision: {{ mode: continuous }}
"#
    )
}

/// The tarp on the turning box, over its whole run: the worst frame's edge.
fn tarp_worst(knee: Option<f64>) -> (f64, usize) {
    let scene = Scene::from_yaml(&tarp(knee), "tarp").unwrap_or_else(|e| panic!("{e}"));
    let frames = (scene.duration / scene.solver.dt).round() as usize;
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    worst_over(&mut sim, frames)
}

/// The tarp on the turning box: with a knee at 3 %, every frame end within 1.05 (the box edge's
/// feature answers spread over the tarp around them, `sim/limit.rs`).
#[test]
fn a_stiff_tarp_on_a_turning_box_stays_near_its_knee() {
    let knee = tarp_worst(Some(0.03));
    eprintln!(
        "tarp, knee 3 %: worst edge {:.4} at frame {}",
        knee.0, knee.1
    );
    assert!(
        knee.0 <= 1.05,
        "worst edge {:.4} at frame {}",
        knee.0,
        knee.1
    );
}

/// The linear tarp's worst edge, for comparison (printed, not judged: the collision pass's
/// answers on a linear material are not held to a bound, see `sim/limit.rs`).
#[test]
#[ignore = "measurement: cargo test --release --test stretch_knee linear_tarp -- --ignored --nocapture"]
fn linear_tarp_on_a_turning_box() {
    let (w, at) = tarp_worst(None);
    eprintln!("tarp, linear: worst edge {w:.4} at frame {at}");
}

/// Every bundled scene with self-collision on and a knee at 3 % on every material: no
/// divergence, no intersecting triangles, every edge within the suite's 1.5 (printed beside the
/// same scene's figure without the knee).
#[test]
#[ignore = "every bundled scene, twice: minutes"]
fn every_bundled_scene_with_a_knee_stays_within_its_bound() {
    let mut failed = Vec::new();
    for name in self_check::SCENES {
        let plain = self_check::bundled(name, 1);
        let mut knee = plain.clone();
        for c in &mut knee.cloths {
            c.material.stretch_knee = Some(0.03);
        }
        for g in &mut knee.garments {
            g.material.stretch_knee = Some(0.03);
        }
        let a = self_check::run(&plain, plain.duration);
        let b = self_check::run(&knee, knee.duration);
        eprintln!(
            "{name}: linear {:.3} ({:.0} s), knee {:.3} ({:.0} s), intersections {}, diverged {:?}",
            a.max_stretch, a.wall_s, b.max_stretch, b.wall_s, b.max_intersections, b.diverged
        );
        if b.diverged.is_some() || b.max_intersections > 0 || b.max_stretch > 1.5 {
            failed.push(*name);
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

/// A scene file of `material` lines on the hanging cloth, in a temporary folder.
struct TempScene(PathBuf);

impl TempScene {
    fn new(tag: &str, material_lines: &str) -> Self {
        let base = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml"),
        )
        .expect("bundled scene");
        let text = base.replacen(
            "stretch: 2000.0",
            &format!("stretch: 2000.0\n{material_lines}"),
            1,
        );
        assert_ne!(text, base, "the hanging scene names its stretch");
        let dir = std::env::temp_dir().join(format!("drape_knee_{}_{tag}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("knee.yaml");
        std::fs::write(&path, text).expect("temp scene");
        Self(path)
    }
}

impl Drop for TempScene {
    fn drop(&mut self) {
        if let Some(dir) = self.0.parent() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// Bad knee keys name the file, the key and the reason; a good one builds.
#[test]
fn knee_keys_are_checked_with_file_and_key() {
    let indent = "      ";
    let cases = [
        (
            "negative",
            "stretch_knee: -0.03",
            "cloths[0].material.stretch_knee: must be > 0",
        ),
        (
            "huge",
            "stretch_knee: 3.0",
            "cloths[0].material.stretch_knee: must be at most",
        ),
        (
            "alone",
            "knee_stiffening: 50.0",
            "cloths[0].material.knee_stiffening: has no effect without stretch_knee",
        ),
        (
            "softening",
            "stretch_knee: 0.03\n      knee_stiffening: 0.5",
            "cloths[0].material.knee_stiffening: must be at least",
        ),
    ];
    for (tag, lines, expected) in cases {
        let f = TempScene::new(tag, &format!("{indent}{lines}"));
        let err = Scene::load(&f.0).expect_err(tag).to_string();
        assert!(err.contains(expected), "{tag}: {err}");
        assert!(err.contains("knee.yaml"), "{tag}: the file is named: {err}");
    }
    let f = TempScene::new(
        "good",
        &format!("{indent}stretch_knee: 0.03\n{indent}knee_stiffening: 50.0"),
    );
    let scene = Scene::load(&f.0).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.cloths[0].material.knee(), Some((0.03, 50.0)));
    scene.build().unwrap_or_else(|e| panic!("{e}"));
}
