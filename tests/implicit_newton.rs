//! A very stiff cloth (stretch 1e6 N/m) stepped implicitly at 1/60 s must not gain energy, so
//! the divergence guard never has to subdivide. Without the Newton iterations of the implicit
//! step, every frame of this case would be subdivided (one linearised solve turns the rotation
//! of stiff springs into stretch energy: see `EnergyCheck` in src/integrate/implicit/newton.rs).

use drape::hard::{catalogue, Resolution};

#[test]
fn stiff_implicit_cloth_steps_without_subdivisions_or_energy_gain() {
    let (_, build) = catalogue()
        .into_iter()
        .find(|(n, _)| *n == "stiff_implicit")
        .expect("stiff_implicit is catalogued");
    let mut case = build(Resolution::Ci).expect("builds");
    let sim = &mut case.sim;
    let energy = |m: &drape::sim::StepMetrics| m.kinetic_energy + m.potential_energy;
    let (ke0, pe0) = sim.energy();
    let e0 = ke0 + pe0;
    let (mut prev, mut subdivisions, mut newton_frames) = (e0, 0, 0);
    let mut cg = 0;
    for frame in 0..60 {
        let m = sim.step().expect("stable");
        subdivisions += m.subdivisions;
        cg += m.cg_iterations;
        // One force evaluation for Baraff-Witkin's solve, one for the energy check.
        newton_frames += u32::from(m.force_evaluations > 2 * m.substeps);
        let e = energy(&m);
        // Pinned corners, no wind: nothing does work on the cloth and damping only dissipates,
        // so the total energy never rises (beyond the energy sums' round-off).
        assert!(
            e <= prev + 1e-12 * e0.abs(),
            "frame {frame}: {prev} J -> {e} J"
        );
        prev = e;
    }
    assert_eq!(subdivisions, 0, "the guard had to subdivide");
    assert!(newton_frames > 0, "this case needs Newton iterations");
    // Newton's corrections are solved on the matrix at the iterate, whose stiff springs have
    // turned: with coarse levels rebuilt for it (`SolveKind::Newton`) the 60 frames (63 Newton
    // iterations) take 7552 CG iterations; on the step's own levels, built at its start state,
    // they took 13590.
    assert!(
        cg < 10_000,
        "{cg} CG iterations over 60 frames: Newton's corrections preconditioned on stale levels?"
    );
    assert!(
        prev < e0,
        "the falling cloth converts and dissipates energy"
    );
}
