//! Tests for the divergence error of `src/sim/error.rs` and `src/sim/guard/`: the message says
//! what the guard measured, and blames an effect (with advice on the step) only where the
//! integrator's stability bound `h omega <= limit` is exceeded.

use drape::integrate::IntegratorKind;
use drape::scene::Scene;
use drape::sim::{Cause, DivergenceError, DivergencePolicy, Symptom};

/// A 12x12 hanging sheet with `kind`, step `dt`, stretch stiffness `stretch`, a guard that
/// stops at `max_speed`; steps until it fails.
fn diverge(kind: IntegratorKind, dt: f64, stretch: f64, max_speed: f64) -> Box<DivergenceError> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/hanging.yaml");
    let mut scene = Scene::load(path.as_ref()).expect("hanging scene");
    let c = &mut scene.cloths[0];
    c.grid.resolution = [12, 12];
    c.material.stretch = stretch;
    scene.solver.integrator = kind;
    scene.solver.dt = dt;
    scene.solver.guard.policy = DivergencePolicy::Stop;
    scene.solver.guard.max_speed = max_speed;
    let mut sim = scene.build().expect("scene builds");
    (0..200)
        .find_map(|_| sim.step().err())
        .expect("the guard must stop the run")
}

#[test]
fn an_implicit_run_reports_the_symptom_and_suggests_no_step() {
    // Falling faster than 1 mm/s trips the speed bound within a few steps: no instability.
    let e = diverge(IntegratorKind::Implicit, 1.0 / 60.0, 1e3, 1e-3);
    let msg = e.to_string();
    assert!(matches!(e.symptom, Symptom::Speed(_)), "{msg}");
    assert_eq!(e.cause, Cause::Unknown, "{msg}");
    assert!(
        msg.contains("cloth 'sheet'") && msg.contains("moves at"),
        "{msg}"
    );
    for advice in ["lower dt", "substeps", "soften", "cause"] {
        assert!(!msg.contains(advice), "no guessed cause or advice: {msg}");
    }
}

#[test]
fn an_explicit_run_within_its_stability_limit_blames_no_effect() {
    let e = diverge(IntegratorKind::SymplecticEuler, 1e-4, 1e3, 1e-3);
    let msg = e.to_string();
    assert!(matches!(e.symptom, Symptom::Speed(_)), "{msg}");
    assert_eq!(e.cause, Cause::Unknown, "{msg}");
    assert!(
        !msg.contains("lower dt") && !msg.contains("stretch"),
        "{msg}"
    );
}

#[test]
fn an_explicit_run_over_its_stability_limit_names_the_stiffest_effect() {
    let e = diverge(IntegratorKind::SymplecticEuler, 1.0 / 60.0, 1e5, 500.0);
    let msg = e.to_string();
    match &e.cause {
        Cause::Unstable {
            parameter,
            h_omega,
            limit,
        } => {
            assert!(parameter.contains("stretch"), "{msg}");
            assert!(h_omega > limit, "{msg}");
        }
        other => panic!("expected the stability bound's verdict, got {other:?}: {msg}"),
    }
    assert!(
        msg.contains("cloths[0].material.stretch") && msg.contains("lower dt"),
        "{msg}"
    );
}
