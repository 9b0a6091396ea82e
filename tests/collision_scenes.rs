//! Collision acceptance at scene level: the bundled scenes through the whole step
//! (effects, implicit integrator, guard, collision stage).

use drape::collide::DetectionMode;
use drape::scene::Scene;
use drape::sim::Simulation;
use drape::Vec3;
use std::path::Path;

fn load(name: &str) -> Scene {
    Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config")
            .join(name),
    )
    .unwrap()
}

/// The highest and the lowest cloth vertex (z, m).
fn highest(sim: &Simulation) -> f64 {
    sim.cloth
        .x
        .iter()
        .map(|x| x.z)
        .fold(f64::NEG_INFINITY, f64::max)
}

fn lowest(sim: &Simulation) -> f64 {
    sim.cloth
        .x
        .iter()
        .map(|x| x.z)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn drape_on_sphere_never_penetrates_beyond_a_tenth_of_thickness() {
    for mode in [DetectionMode::Continuous, DetectionMode::Proximity] {
        let mut scene = load("sphere_drape.yaml");
        scene.collision.mode = mode;
        scene.cloths[0].grid.resolution = [24, 24];
        let th = scene.cloths[0].material.thickness;
        let (c, r) = (Vec3::new(0.0, 0.0, 0.2), 0.4);
        let mut sim = scene.build().unwrap();
        let mut touching = 0;
        for _ in 0..120 {
            let m = sim.step().unwrap();
            assert!(
                m.deepest_penetration < 0.1 * th,
                "{mode:?}: stage reports {}",
                m.deepest_penetration
            );
            // Independent check: every vertex stays at least 0.9 thickness from the sphere.
            let worst = sim
                .cloth
                .x
                .iter()
                .map(|x| (*x - c).length() - r)
                .fold(f64::INFINITY, f64::min);
            assert!(
                worst > 0.9 * th,
                "{mode:?}: vertex {:.2e} m from the sphere (thickness {th})",
                worst
            );
            touching = m.contacts;
        }
        assert!(
            touching > 20,
            "{mode:?}: the cloth should rest on the sphere ({touching} contacts)"
        );
    }
}

#[test]
fn tablecloth_rests_on_the_round_table() {
    for mode in [DetectionMode::Continuous, DetectionMode::Proximity] {
        let mut scene = load("table.yaml");
        scene.collision.mode = mode;
        scene.cloths[0].grid.resolution = [28, 28];
        let th = scene.cloths[0].material.thickness;
        let mut sim = scene.build().unwrap();
        for _ in 0..120 {
            let m = sim.step().unwrap();
            assert!(
                m.deepest_penetration < 0.1 * th,
                "{mode:?}: {}",
                m.deepest_penetration
            );
        }
        // The middle of the cloth lies on the top (z = 0.76 + thickness), the rim hangs below it.
        let mid = sim.cloth.x[14 * 28 + 14];
        assert!(
            (mid.z - (0.76 + th)).abs() < 0.1 * th + 2e-3,
            "{mode:?}: middle at z = {}",
            mid.z
        );
        let lowest = lowest(&sim);
        assert!(
            lowest < 0.6,
            "{mode:?}: the rim should drape down (lowest z {lowest})"
        );
    }
}

#[test]
fn crumpling_cloth_never_ends_a_step_self_intersecting() {
    let mut sim = load("crumple.yaml").build().unwrap();
    let steps = (2.0 / sim.settings.dt) as usize;
    for k in 0..steps {
        let m = sim.step().unwrap();
        assert_eq!(m.self_intersections, Some(0), "step {k}");
    }
    // It did crumple: the cloth lies low, in a heap smaller than its flat size.
    let zmax = highest(&sim);
    assert!(zmax < 0.3, "heap top at {zmax}");
}

/// The chair's back (`config/chair.yaml`): its front face is 70 degrees steep, facing
/// `(cos 20, 0, sin 20)`.
const BACK: &str = "{ name: back, shape: { type: box, half_extents: [0.03, 0.25, 0.3] }, pose: { xyz: [-0.28, 0.0, 0.8], rpy: [0.0, -0.35, 0.0] } }";

/// A 0.2 m patch laid on the chair's back alone (nothing under it but the ground, 0.5 m below the
/// back's lower edge): `tan 70 = 2.7 > mu = 0.2`, so friction cannot hold it. It slides at
/// Coulomb's `g (sin 70 - mu cos 70)` = 8.55 m/s^2 (backward Euler's velocity is exact under a
/// constant force, and the drag slides from the first substep: measured 1.2814 m/s at 0.15 s
/// against 1.2814; 1 % allows the solve's tolerance), off the back's lower edge, and ends on the
/// ground with nothing on the back.
#[test]
fn a_patch_on_the_chair_back_alone_slides_down_it_at_coulomb_acceleration_and_off_it() {
    let (th, mu, g) = (0.008, 0.2, 9.81);
    let tilt = 0.35_f64;
    let n = Vec3::new(tilt.cos(), 0.0, tilt.sin());
    let down = Vec3::new(tilt.sin(), 0.0, -tilt.cos());
    // Centred 0.1 m up the face from its middle, one thickness (plus 0.1 mm) off it.
    let c = Vec3::new(-0.28, 0.0, 0.8) + n * (0.03 + th + 1e-4) - down * 0.1;
    let yaml = format!(
        "name: patch_on_back
duration: 3.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666 }}
cloths:
  - name: patch
    grid: {{ size: [0.2, 0.2], resolution: [9, 9], pose: {{ xyz: [{}, {}, {}], rpy: [0.0, {}, 0.0] }} }}
    material:
      density: 0.2
      stretch: 1500.0
      shear: 150.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: {{ spring: 0.05, air: 0.0 }}
      thickness: {th}
      friction: {mu}
obstacles:
  - {BACK}
  - {{ name: ground, shape: {{ type: plane, normal: [0.0, 0.0, 1.0] }} }}
collision: {{ mode: continuous }}
",
        c.x,
        c.y,
        c.z,
        std::f64::consts::FRAC_PI_2 - tilt
    );
    let mut sim = Scene::from_yaml(&yaml, "patch_on_back")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    let a = g
        * ((std::f64::consts::FRAC_PI_2 - tilt).sin()
            - mu * (std::f64::consts::FRAC_PI_2 - tilt).cos());
    // 0.15 s in it has slid 0.5 a t^2 = 9.6 cm of the 20 cm to the edge.
    for _ in 0..9 {
        sim.step().unwrap();
    }
    let t = sim.time();
    let v = sim.cloth.v.iter().map(|v| v.dot(down)).sum::<f64>() / sim.cloth.len() as f64;
    assert!(
        (v - a * t).abs() <= 0.01 * a * t,
        "at {t:.3} s the patch slides at {v:.3} m/s, Coulomb {:.3}",
        a * t
    );
    for _ in 9..180 {
        sim.step().unwrap();
    }
    let on_back = sim
        .collision()
        .expect("it collides")
        .contacts()
        .iter()
        .filter(|c| c.obstacle == 0)
        .count();
    assert_eq!(on_back, 0, "{on_back} vertices still on the back");
    let zmax = highest(&sim);
    assert!(
        zmax < 0.1,
        "the patch's highest vertex is at {zmax} m, not on the ground"
    );
}

/// The whole chair scene: the cloth dropped over the chair (from 1.25 m, over the back's top at
/// 1.08 m) comes down off the back; nothing stays where only friction on the 70 degree face
/// could hold it (the patch above shows it cannot).
///
/// Where it then rests is not pinned down by the math, and the test does not pick one outcome:
/// - the heap on the seat can prop cloth up against the lower back: the springs resist
///   compression, so a fold leaning on the back is an equilibrium of this model (measured: ~27
///   vertices up to 0.66 m, with the CG tolerance at 2e-5 instead of the scene's 1e-5, or with
///   split substeps keeping the last full substep's aggregates);
/// - over the seat's front edge the overhang pulls against roughly as much friction on the seat
///   top and the side edges (the 0.2 m it starts with hanging over: 0.31 N, ~0.23 N past the
///   edge's capstan factor `exp(-mu pi / 2)`, against ~0.24 N), so whether it slides on to the
///   ground depends on how it landed (measured both: on the ground at 4.5 s, and resting on the
///   seat with 17 cm hanging over).
///
/// What holds in every outcome: after 8 s nothing rests on the back's upper half (its face spans
/// 0.52-1.08 m), where nothing from the seat props it and only friction could hold it, and
/// nothing of the cloth is that high.
#[test]
fn cloth_dropped_on_the_chair_comes_down_off_its_back() {
    let mut sim = load("chair.yaml").build().unwrap();
    for _ in 0..480 {
        sim.step().unwrap();
    }
    let reach = 0.8;
    let stage = sim.collision().expect("the chair collides");
    let back = stage
        .obstacles()
        .iter()
        .position(|o| o.name == "back")
        .expect("the chair has a back");
    let on_back_high = stage
        .contacts()
        .iter()
        .filter(|c| c.obstacle == back && sim.cloth.x[c.vertex as usize].z > reach)
        .count();
    assert_eq!(
        on_back_high, 0,
        "{on_back_high} vertices rest on the 70 degree back above {reach} m"
    );
    let zmax = highest(&sim);
    assert!(
        zmax < reach,
        "the cloth's highest vertex is still at {zmax} m"
    );
}

/// Inside test of a paddle in its own frame (paddle centred on the origin).
type Inside = fn(Vec3) -> bool;

#[test]
fn thin_plate_at_5_and_20_m_per_s_never_passes_through_a_hanging_cloth() {
    let plate: Inside = |p| p.x.abs() < 0.15 && p.y.abs() < 0.001 && p.z.abs() < 0.15;
    let shape = "{ type: box, half_extents: [0.15, 0.001, 0.15] }";
    paddle_through_cloth(&[
        (shape, "[0.0, 0.0, 0.0]", plate, 5.0),
        (shape, "[0.0, 0.0, 0.0]", plate, 20.0),
    ]);
}

#[test]
fn thin_rod_at_5_and_20_m_per_s_never_passes_through_a_hanging_cloth() {
    // parry cylinders run along local y: yaw 90 degrees lays the rod across the cloth (along x).
    let rod: Inside = |p| p.x.abs() < 0.3 && (p.y * p.y + p.z * p.z).sqrt() < 0.005;
    let shape = "{ type: cylinder, radius: 0.005, half_height: 0.3 }";
    let rpy = "[0.0, 0.0, 1.5707963267948966]";
    paddle_through_cloth(&[(shape, rpy, rod, 5.0), (shape, rpy, rod, 20.0)]);
}

/// Sweeps each paddle `(shape, rpy, inside test in the paddle frame, speed)` along +y through the
/// hanging cloth at dt = 1/60: no vertex path may pass through it, and it must push the cloth.
fn paddle_through_cloth(cases: &[(&str, &str, Inside, f64)]) {
    for &(shape, rpy, inside, speed) in cases {
        let base = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml"),
        )
        .unwrap();
        let text = format!(
            "{}\nobstacles:\n  - {{ name: paddle, shape: {shape}, pose: {{ xyz: [0.0, -0.3, 1.2], rpy: {rpy} }}, motion: {{ type: velocity, linear: [0.0, {speed}, 0.0], angular: [0.0, 0.0, 0.0] }} }}\ncollision: {{ mode: continuous }}\n",
            base.replacen("resolution: [32, 32]", "resolution: [24, 24]", 1)
        );
        let scene = Scene::from_yaml(&text, "paddle").unwrap();
        let mut sim = scene.build().unwrap();
        let centre = |sim: &drape::sim::Simulation| {
            Vec3::new(
                0.0,
                sim.collision().unwrap().obstacles()[0].pose.translation.y,
                1.2,
            )
        };
        let mut c0 = centre(&sim);
        let mut through = 0;
        let mut pushed: f64 = 0.0;
        for _ in 0..20 {
            let before = sim.cloth.x.clone();
            let subs = sim.step().unwrap().substeps;
            let c1 = centre(&sim);
            // Each vertex's path relative to the (translating) paddle, finely sampled: a sample
            // inside the paddle means the vertex went through it. 400 samples over at most
            // 0.35 m of relative motion resolve 1 mm, below the 2 mm plate.
            // When the divergence guard split the frame into substeps, the path is piecewise
            // linear and its chord may cut a corner the cloth really wrapped around; then only
            // the end state is checked.
            for (a, b) in before.iter().zip(&sim.cloth.x) {
                let (r0, r1) = (*a - c0, *b - c1);
                let samples = if subs == 1 { 400 } else { 0 };
                if (0..=samples).any(|k| inside(r0.lerp(r1, 1.0 - k as f64 / 400.0))) {
                    through += 1;
                    eprintln!("{subs} substeps: {r0} -> {r1}");
                }
            }
            c0 = c1;
            pushed = sim.cloth.x.iter().map(|x| x.y).fold(pushed, f64::max);
        }
        assert_eq!(
            through, 0,
            "{shape} at {speed} m/s: {through} vertex paths through the paddle"
        );
        assert!(
            pushed > 0.05,
            "{shape} at {speed} m/s pushed the cloth only {pushed} m"
        );
    }
}

#[test]
fn scenes_without_obstacles_build_no_collision_stage() {
    assert!(load("hanging.yaml").build().unwrap().collision().is_none());
    assert!(load("sphere_drape.yaml")
        .build()
        .unwrap()
        .collision()
        .is_some());
}
