//! The implicit solver's multigrid-preconditioned CG on the bundled hanging cloth: it converges to
//! the requested tolerance in a number of iterations that does not grow with the resolution.

use drape::integrate::IntegratorKind;
use drape::scene::Scene;
use drape::sim::Simulation;
use std::path::Path;
use std::time::Instant;

/// The bench's scene: hanging cloth at `res x res`, implicit at 60 Hz, CG to 1e-5.
fn hanging(res: usize) -> Simulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml");
    let mut s = Scene::load(&path).expect("bundled scene");
    s.cloths[0].grid.resolution = [res, res];
    s.solver.integrator = IntegratorKind::Implicit;
    s.solver.dt = 1.0 / 60.0;
    s.solver.cg_tolerance = 1e-5;
    s.build().expect("valid scene")
}

/// Iterations of each of `steps` steps, and the mean wall time per step.
fn run(res: usize, steps: usize) -> (Vec<u32>, f64, f64) {
    let mut sim = hanging(res);
    let mut its = Vec::new();
    let mut worst: f64 = 0.0;
    let t0 = Instant::now();
    for _ in 0..steps {
        let m = sim.step().expect("stable");
        its.push(m.cg_iterations);
        worst = worst.max(m.cg_residual_max);
    }
    (its, t0.elapsed().as_secs_f64() * 1e3 / steps as f64, worst)
}

#[test]
#[ignore = "measurement: cargo test --release --test implicit_solver -- --ignored --nocapture"]
fn measure_iterations_and_time() {
    for res in [32, 64, 128] {
        let (its, ms, worst) = run(res, 30);
        println!("{res}x{res}: {ms:.2} ms/step, worst residual {worst:.2e}, iterations {its:?}");
    }
}

/// Level independence on the real scene: the multigrid-preconditioned CG converges to 1e-5 at
/// 32x32 and 64x64 within a bound that does not scale with the resolution (block Jacobi needed
/// more than its 200-iteration cap at 64x64). Measured: at most 20 (32x32) and 32 (64x64) over 10
/// steps, mostly 15-20, including hierarchy reuse between rebuilds.
#[test]
fn hanging_cloth_iterations_are_resolution_independent() {
    for res in [32, 64] {
        let (its, _, worst) = run(res, 10);
        assert!(
            worst <= 1e-5 * (1.0 + 1e-9),
            "{res}x{res}: residual {worst}"
        );
        assert!(
            its.iter().all(|&k| (1..40).contains(&k)),
            "{res}x{res}: {its:?}"
        );
    }
}

/// The `step` bench's implicit scene (gravity, stretch, shear, bending; skip-one springs).
#[test]
#[ignore = "measurement: the bench scene, iterations and time per step"]
fn measure_bench_scene() {
    use drape::scene::EffectKind;
    for res in [32, 64, 128] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml");
        let mut s = Scene::load(&path).expect("bundled scene");
        s.cloths[0].grid.resolution = [res, res];
        s.effects = vec![
            EffectKind::Gravity,
            EffectKind::Stretch,
            EffectKind::Shear,
            EffectKind::Bending,
        ];
        s.solver.integrator = IntegratorKind::Implicit;
        s.solver.dt = 1.0 / 60.0;
        s.solver.cg_tolerance = 1e-5;
        s.cloths[0].material.skip_one = 500.0;
        let mut sim = s.build().expect("valid scene");
        let mut its = Vec::new();
        let t0 = Instant::now();
        for _ in 0..30 {
            its.push(sim.step().expect("stable").cg_iterations);
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3 / 30.0;
        println!("bench scene {res}x{res}: {ms:.2} ms/step, iterations {its:?}");
    }
}
