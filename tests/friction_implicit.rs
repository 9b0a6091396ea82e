//! Coulomb friction inside the implicit solve (held contact vertices): a cloth lying on a plane
//! tilted by `a` must stick iff `tan a <= mu`, and slide with the acceleration
//! `g (sin a - mu cos a)` otherwise, as a rigid block would (a flat cloth under uniform
//! gravity and friction keeps its shape, so every vertex sees the same ratio).

use drape::scene::Scene;

const G: f64 = 9.81;
const MU: f64 = 0.4;

/// A 0.2 m square cloth lying on a plane tilted by `angle` about y (downhill along -x' of the
/// tilted frame), with friction `MU`, started at `v0` (m/s) downhill. Returns the centre-of-mass
/// velocity along the downhill direction after every step up to `t_end`, and the step.
fn run(angle: f64, v0: f64, t_end: f64) -> (Vec<f64>, f64) {
    run_on(angle, v0, 0.0, t_end)
}

/// [`run`] on a plane moving downhill at `belt` (m/s) in its own plane (a conveyor belt).
fn run_on(angle: f64, v0: f64, belt: f64, t_end: f64) -> (Vec<f64>, f64) {
    let (s, c) = angle.sin_cos();
    // The plane's normal (tilted about y), the cloth lying on it `thickness` above.
    let th = 0.004;
    let normal = [s, 0.0, c];
    let motion = if belt == 0.0 {
        String::new()
    } else {
        format!(
            ", motion: {{ type: velocity, linear: [{}, 0.0, {}], angular: [0.0, 0.0, 0.0] }}",
            belt * c,
            -belt * s
        )
    };
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
  - {{ name: slope, shape: {{ type: plane, normal: [{nx}, {ny}, {nz}] }}{motion} }}
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
    for v in sim.cloth.v.iter_mut() {
        *v = downhill * v0;
    }
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
    let dt = sim.settings.dt;
    let steps = (t_end / dt).round() as usize;
    let mut out = Vec::with_capacity(steps);
    for _ in 0..steps {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
        out.push(com_velocity(&sim));
    }
    (out, dt)
}

/// [`run`] from rest: the centre-of-mass velocity at `t1` and `t2`.
fn slide(angle: f64, t1: f64, t2: f64) -> (f64, f64) {
    let (v, dt) = run(angle, 0.0, t2);
    let at = |t: f64| v[(t / dt).round() as usize - 1];
    (at(t1), at(t2))
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

/// Sliding starts when the load exceeds Coulomb's limit, not some substeps later: above the
/// friction angle the centre of mass follows `g (sin a - mu cos a) t` from the first frames on.
/// The normal force is lagged one substep and the sliding decision one more (both are decided
/// on the last substep's forces), so the velocity may trail by at most two substeps of the
/// full tangential acceleration `g sin a` (what the cloth gains while not yet braked by the
/// right force), plus the conjugate gradient's tolerance.
#[test]
fn sliding_starts_at_the_threshold_without_delay() {
    for factor in [1.2, 1.6] {
        let a = factor * MU.atan();
        let (v, dt) = run(a, 0.0, 0.25);
        let h = dt / 2.0;
        let expected_acc = G * (a.sin() - MU * a.cos());
        for (k, vk) in v.iter().enumerate() {
            let t = (k + 1) as f64 * dt;
            let expected = expected_acc * t;
            let slack = 2.0 * h * G * a.sin() + 1e-4 * expected;
            assert!(
                (vk - expected).abs() <= slack,
                "angle {factor} x atan(mu), t {t:.4} s: velocity {vk:.5} m/s, Coulomb {expected:.5} \
                 (bound {slack:.2e})"
            );
        }
    }
}

/// A cloth thrown along a level plane decelerates at `mu g` and stops at `v0 / (mu g)`, and
/// stays stopped: the last step before the stop does not overshoot into a backward slide
/// (friction only removes motion). Before the stop the velocity is exact: Coulomb's force is
/// constant while sliding and the normal force on a level plane is `m g` from the first substep
/// on, so backward Euler's velocity is `v0 - mu g t` to the conjugate gradient's tolerance.
#[test]
fn sliding_decelerates_at_mu_g_and_stops() {
    let v0 = 0.5;
    let (v, dt) = run(0.0, v0, 0.4);
    let h = dt / 2.0;
    let stop = v0 / (MU * G);
    for (k, vk) in v.iter().enumerate() {
        let t = (k + 1) as f64 * dt;
        if t < stop - 2.0 * h {
            let expected = v0 - MU * G * t;
            assert!(
                (vk - expected).abs() <= 1e-4 * v0,
                "t {t:.4} s: velocity {vk:.5} m/s, Coulomb {expected:.5}"
            );
        } else if t > stop + 2.0 * h {
            assert!(
                vk.abs() <= drape::integrate::STICK_SPEED,
                "t {t:.4} s (stop at {stop:.4} s): still moving at {vk:.3e} m/s"
            );
        }
        assert!(
            *vk >= -drape::integrate::STICK_SPEED,
            "t {t:.4} s: friction reversed the cloth ({vk:.3e} m/s)"
        );
    }
}

/// A cloth dropped at rest onto a level belt moving at `V` is dragged by Coulomb friction at
/// `mu g` until it rides along at `V` (at `V / (mu g)`), then rides along and never overtakes
/// it. The moving surface's friction is solved with the cloth (a drag towards the belt's
/// velocity), so the velocity is Coulomb's to the same bounds as on a still plane: up to two
/// substeps' lag at the start (the normal force and the mode are lagged one substep each) and
/// the stick speed once riding. (The collision stage's friction after the solve, which moving
/// surfaces had before, gives the same here: a uniform patch has no neighbour pulling a held
/// vertex off the belt. What it did to such a vertex is `tests/robot_scenes.rs`'s forearm.)
#[test]
fn a_moving_belt_drags_the_cloth_at_mu_g_until_it_rides_along() {
    let belt = 0.3;
    let (v, dt) = run_on(0.0, 0.0, belt, 0.4);
    let h = dt / 2.0;
    let caught = belt / (MU * G);
    let stick = drape::integrate::STICK_SPEED;
    for (k, vk) in v.iter().enumerate() {
        let t = (k + 1) as f64 * dt;
        if t < caught - 2.0 * h {
            let expected = MU * G * t;
            let slack = 2.0 * h * MU * G + 1e-4 * expected;
            assert!(
                (vk - expected).abs() <= slack,
                "t {t:.4} s: velocity {vk:.5} m/s, Coulomb {expected:.5} (bound {slack:.2e})"
            );
        } else if t > caught + 2.0 * h {
            assert!(
                (vk - belt).abs() <= stick,
                "t {t:.4} s (caught up at {caught:.4} s): {vk:.5} m/s against the belt's {belt}"
            );
        }
        assert!(
            *vk <= belt + stick,
            "t {t:.4} s: the cloth overtook the belt ({vk:.5} m/s)"
        );
    }
}
