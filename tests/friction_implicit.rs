//! Coulomb friction inside the implicit solve (held contact vertices): a cloth lying on a plane
//! tilted by `a` must stick iff `tan a <= mu`, and slide with the acceleration
//! `g (sin a - mu cos a)` otherwise, as a rigid block would (a flat cloth under uniform
//! gravity and friction keeps its shape, so every vertex sees the same ratio).

use drape::scene::Scene;

const G: f64 = 9.81;
const MU: f64 = 0.4;

/// A 0.2 m square cloth lying on a plane tilted by `angle` about y (downhill along -x' of the
/// tilted frame), with friction `MU`. Returns the centre-of-mass velocity along the downhill
/// direction at `t1` and `t2`.
fn slide(angle: f64, t1: f64, t2: f64) -> (f64, f64) {
    let (s, c) = angle.sin_cos();
    // The plane's normal (tilted about y), the cloth lying on it `thickness` above.
    let th = 0.004;
    let normal = [s, 0.0, c];
    let yaml = format!(
        r#"
name: slope
duration: 2.0
effects: [gravity, stretch, shear, bending]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 2 }}
cloths:
  - name: patch
    grid: {{ size: [0.2, 0.2], resolution: [8, 8], pose: {{ xyz: [{x}, 0.0, {z}], rpy: [0.0, {angle}, 0.0] }} }}
    material:
      density: 0.2
      stretch: 1000.0
      shear: 100.0
      bend_warp: 1.0e-5
      bend_weft: 1.0e-5
      thickness: {th}
      friction: {MU}
obstacles:
  - {{ name: slope, shape: {{ type: plane, normal: [{nx}, {ny}, {nz}] }} }}
collision: {{ mode: continuous, response: both }}
"#,
        x = normal[0] * th,
        z = normal[2] * th,
        nx = normal[0],
        ny = normal[1],
        nz = normal[2],
    );
    let scene = Scene::from_yaml(&yaml, "friction_implicit").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    // Downhill: the direction of gravity's tangential part.
    let downhill = drape::Vec3::new(c, 0.0, -s);
    let mass: f64 = sim.cloth.mass.iter().sum();
    let com_velocity = |sim: &drape::sim::Simulation| {
        sim.cloth
            .v
            .iter()
            .zip(&sim.cloth.mass)
            .map(|(v, m)| v.dot(downhill) * m)
            .sum::<f64>()
            / mass
    };
    let (mut v1, mut v2) = (f64::NAN, f64::NAN);
    let steps = (t2 / sim.settings.dt).round() as usize;
    let k1 = (t1 / sim.settings.dt).round() as usize;
    for k in 1..=steps {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
        if k == k1 {
            v1 = com_velocity(&sim);
        }
    }
    v2 = v2.max(com_velocity(&sim));
    (v1, v2)
}

/// Below the threshold (a = 0.9 atan mu) the cloth stays put: it creeps at most at the stick
/// speed of the in-solve friction (1e-4 m/s).
#[test]
fn cloth_sticks_below_the_friction_angle() {
    let a = 0.9 * MU.atan();
    let (v1, v2) = slide(a, 0.5, 1.0);
    assert!(
        v1.abs() <= drape::integrate::STICK_SPEED && v2.abs() <= drape::integrate::STICK_SPEED,
        "sliding below the friction angle: {v1:.3e}, {v2:.3e} m/s"
    );
}

/// Above it the centre of mass accelerates at `g (sin a - mu cos a)`, measured between 0.5 s and
/// 1 s. Sliding friction is Coulomb's constant force along the slip and the normal force on a
/// plane is constant, so backward Euler's velocity is exact: the tolerance is the conjugate
/// gradient's (relative residual 1e-5), with a factor 10 for its accumulation over 60 steps.
#[test]
fn cloth_slides_with_coulomb_acceleration_above_it() {
    for factor in [1.2, 1.6] {
        let a = factor * MU.atan();
        let (v1, v2) = slide(a, 0.5, 1.0);
        let measured = (v2 - v1) / 0.5;
        let expected = G * (a.sin() - MU * a.cos());
        assert!(
            (measured - expected).abs() < 1e-4 * expected,
            "angle {factor} x atan(mu): acceleration {measured:.4} m/s^2, Coulomb {expected:.4}"
        );
    }
}
