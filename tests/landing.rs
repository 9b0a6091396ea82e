//! Cloth driven into a still obstacle, judged on the state every frame ends in: the collision
//! pass answers a vertex that reached the obstacle by position, and when that jump is a good
//! part of the spacing its edges stretch by it while its neighbours stay. `sim/fast.rs`
//! (`jumped`) rolls such a substep back and splits it.

use drape::scene::Scene;
use std::path::Path;

/// The contact bench's S1 (`benches/scenes/bench_s1.yaml`) at `res` x `res`, and the impact
/// stretch bound plus 10 % for its landing, `1.1 (1 + 2 v / c + M g / k)`.
fn s1(res: usize) -> (drape::sim::Simulation, f64) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/scenes/bench_s1.yaml");
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.cloths[0].grid.resolution = [res, res];
    let (k, rho, g, fall) = (1000.0f64, 0.2f64, 9.81f64, 0.2f64);
    let v = (2.0 * g * fall).sqrt();
    // The cloth is 1 m square: its mass is `rho` times 1 m^2.
    let bound = 1.1 * (1.0 + 2.0 * v / (k / rho).sqrt() + rho * g / k);
    (scene.build().unwrap_or_else(|e| panic!("{e}")), bound)
}

/// The contact bench's S1 at 32 x 32 (`benches/scenes/bench_s1.yaml`: a 1 m cloth dropped flat
/// from 1.0 m onto a still sphere of radius 0.3 m at 0.5 m, implicit at 60 Hz, one substep a
/// frame): over its first second (landing at `v = sqrt(2 g 0.2 m)` = 1.98 m/s, then sliding on
/// the ball and flapping), no mesh edge exceeds the impact stretch bound plus 10 %,
/// `1.1 (1 + 2 v / c + M g / k)` = 1.164 (`c = sqrt(k / rho)` = 70.7 m/s, `M` = 0.2 kg). A pass
/// free to jump a vertex by any fraction of its spacing would break it.
#[test]
fn a_cloth_dropped_on_a_sphere_lands_within_the_impact_bound() {
    let (mut sim, bound) = s1(32);
    let mut worst = (0.0f64, 0.0f64);
    let mut touched = false;
    for _ in 0..60 {
        let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
        touched |= m.contacts > 0;
        assert!(sim.cloth.x.iter().all(|p| p.is_finite()));
        let s = 1.0 + sim.cloth.max_edge_stretch();
        if s > worst.0 {
            worst = (s, sim.time());
        }
    }
    assert!(touched, "the cloth never reached the sphere");
    eprintln!(
        "largest stretch {:.3} at t = {:.3} s, bound {bound:.3}",
        worst.0, worst.1
    );
    assert!(
        worst.0 <= bound,
        "an edge stretched {:.3} times its rest length at t = {:.3} s, bound {bound:.3}",
        worst.0,
        worst.1
    );
}

/// The same drop at 48 x 48 (2.1 cm spacing): vertices of the flapping border reach the ball
/// at up to several m/s, each within one substep. The solve stops them on the contact layer
/// (an arrival spring on the layer's tangent plane, anchored where the path hit it when
/// friction holds it there: `collide/arrival.rs`, `sim/coupling/arrival.rs`), so the collision pass
/// after it has nothing to push back by more than a third of the spacing and no substep of the
/// landing is rolled back and split (`sim/fast.rs`, `jumped`); before, 9 were, 4 at 32 x 32
/// and 12 at 64 x 64. No vertex ends a frame inside the ball, and every edge stays within the
/// impact bound of the test above.
#[test]
fn a_cloth_landing_on_a_sphere_is_stopped_in_the_solve_not_split() {
    let (mut sim, bound) = s1(48);
    let (centre, radius) = (drape::Vec3::new(0.0, 0.0, 0.5), 0.3);
    let (mut splits, mut touched, mut worst, mut deepest) = (0, false, 0.0f64, 0.0f64);
    for _ in 0..60 {
        let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
        splits += m.contact_splits;
        touched |= m.contacts > 0;
        worst = worst.max(1.0 + sim.cloth.max_edge_stretch());
        for p in &sim.cloth.x {
            deepest = deepest.max(radius - p.distance(centre));
        }
    }
    assert!(touched, "the cloth never reached the sphere");
    eprintln!("split substeps {splits}, largest stretch {worst:.3}, deepest {deepest:.2e} m");
    assert_eq!(splits, 0, "the landing split {splits} substeps");
    assert!(deepest <= 0.0, "a vertex ended {deepest} m inside the ball");
    assert!(
        worst <= bound,
        "an edge stretched {worst:.3}x, bound {bound:.3}"
    );
}

/// A cloth falling straight down onto a slope it lies parallel to, with friction `mu` above the
/// slope's `tan a`, sticks where it hits: each vertex ends on the plane's contact layer straight
/// below where it started, whatever share of the landing substep it fell before touching.
/// Exact up to the in-solve friction's creep, at most its `STICK_SPEED` (1e-4 m/s,
/// `integrate/friction.rs`) over the 1.5 s run: 0.15 mm. The collision pass's Coulomb friction
/// undoes the tangential motion of the substep since the vertex touched only: undoing the whole
/// substep's, the free fall before the hit included, would put the cloth up the slope by
/// `v sin(a) h` times the share fallen (up to 11 mm here; on the contact bench's S1 such jumps
/// at the sphere's rim stretch landing edges).
#[test]
fn a_cloth_landing_on_a_slope_with_friction_sticks_where_it_hits() {
    let (a, mu, th, dt) = (0.35f64, 0.6f64, 0.005f64, 1.0f64 / 60.0);
    assert!(a.tan() < mu);
    let (stick_speed, seconds) = (1e-4, 1.5);
    let creep = stick_speed * seconds;
    // Drops of 2.3, 5.5 and 9.6 substeps' fall: the hit lands at different shares of a substep.
    for drop in [0.03f64, 0.08, 0.15] {
        let yaml = format!(
            r#"
name: slope
duration: {seconds}
effects: [gravity, stretch, shear, bending]
solver: {{ integrator: implicit, dt: {dt} }}
cloths:
  - name: patch
    grid: {{ size: [0.2, 0.2], resolution: [8, 8], pose: {{ xyz: [0.0, 0.0, {z}], rpy: [{a}, 0.0, 0.0] }} }}
    material: {{ density: 0.2, stretch: 1000.0, shear: 100.0, bend_warp: 1.0e-5, bend_weft: 1.0e-5, thickness: {th}, friction: {mu} }}
obstacles:
  - {{ name: slope, shape: {{ type: plane, normal: [0.0, 0.0, 1.0] }}, pose: {{ rpy: [{a}, 0.0, 0.0] }} }}
collision: {{ mode: continuous }}
"#,
            z = (th + drop) / a.cos(),
        );
        let scene = Scene::from_yaml(&yaml, "slope").unwrap_or_else(|e| panic!("{e}"));
        let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
        let start = sim.cloth.x.clone();
        let mut landed = false;
        while sim.time() < seconds - 0.5 * dt {
            let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
            landed |= m.contacts == start.len();
        }
        assert!(landed, "drop {drop}: the patch never lay on the slope");
        let normal = drape::Vec3::new(0.0, -a.sin(), a.cos());
        let (mut shift, mut height) = (0.0f64, 0.0f64);
        for (x, x0) in sim.cloth.x.iter().zip(&start) {
            shift = shift.max((x.x - x0.x).hypot(x.y - x0.y));
            height = height.max((x.dot(normal) - th).abs());
        }
        eprintln!(
            "drop {drop}: largest horizontal shift {shift:.2e} m, off the layer {height:.1e} m"
        );
        assert!(
            height < 1e-4 * th,
            "drop {drop}: {height} m off the contact layer"
        );
        assert!(
            shift <= creep + 1e-9,
            "drop {drop}: a vertex ended {shift} m from straight below its start (creep allows {creep})"
        );
    }
}
