//! `Simulation` between steps (`src/sim/simulation.rs`): a cloth replaced mid-run (what sewing
//! does when it welds a garment) is judged by the guard with the new cloth's frequency bound,
//! not the cached bound of the cloth it replaced.

use drape::effects::Lattice;
use drape::integrate::IntegratorKind;
use drape::scene::Scene;
use drape::sim::{Cause, DivergenceError, DivergencePolicy, Simulation};

/// The 12x12 hanging sheet with symplectic Euler at one step per 1/60 s frame.
fn sheet(stretch: f64, policy: DivergencePolicy) -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/hanging.yaml");
    let mut scene = Scene::load(path.as_ref()).expect("hanging scene");
    let c = &mut scene.cloths[0];
    c.grid.resolution = [12, 12];
    c.material.stretch = stretch;
    scene.solver.integrator = IntegratorKind::SymplecticEuler;
    scene.solver.dt = 1.0 / 60.0;
    scene.solver.guard.policy = policy;
    scene.solver.guard.max_speed = 500.0;
    scene
}

fn run_to_failure(sim: &mut Simulation) -> Box<DivergenceError> {
    (0..200)
        .find_map(|_| sim.step().err())
        .expect("the guard must stop the run")
}

#[test]
fn a_replaced_cloth_is_judged_by_its_own_frequency_bound() {
    // The stiff sheet on its own: over the stability bound, the error names stretch.
    let stiff = sheet(1e5, DivergencePolicy::Stop);
    let direct = run_to_failure(&mut stiff.build().expect("stiff sheet builds"));
    let Cause::Unstable {
        parameter, h_omega, ..
    } = &direct.cause
    else {
        panic!("{direct}");
    };
    assert_eq!(parameter, "cloths[0].material.stretch", "{direct}");

    // A soft sheet whose guard computes (and caches) its bound in its first frame, then the
    // stiff sheet's cloth and effects in its place, with the stiff run's guard settings.
    let mut sim = sheet(1.0, DivergencePolicy::Subdivide)
        .build()
        .expect("soft sheet builds");
    sim.step().expect("the soft sheet steps");
    let donor = stiff.build().expect("stiff sheet builds");
    let cloth = donor.cloth.clone();
    let effects = stiff.effect_plan().build(&cloth, &Lattice(&cloth));
    sim.replace_cloth(cloth, effects).expect("same obstacles");
    sim.settings.guard = donor.settings.guard;
    let replaced = run_to_failure(&mut sim);
    // The same failure and the same bound, bit for bit: h omega is the new cloth's (the soft
    // sheet's cached bound, far lower, put h omega under the limit and blamed nothing).
    match &replaced.cause {
        Cause::Unstable {
            parameter: p,
            h_omega: ho,
            ..
        } => {
            assert_eq!(p, parameter, "{replaced}");
            assert_eq!(ho.to_bits(), h_omega.to_bits(), "{replaced} vs {direct}");
        }
        other => panic!("{other:?}: {replaced}"),
    }
}
