//! The implicit step's trajectories, bit for bit: a few scenes through the implicit solver's
//! paths (multigrid with parallel halves, Newton iterations, held contacts with in-solve
//! friction and their constraint impulses, obstacle edges as contact springs) hash to the
//! recorded values, which a reorganisation of the solver's code must reproduce. The explicit
//! paths have their own record in `tests/step_bitwise.rs`.
//!
//! A mismatch means an operation moved to another order somewhere in the solver or its
//! feedback to the collision stage. To re-record after a deliberate physics change, run with
//! `--nocapture` and copy the printed table.

#[path = "common/bitwise.rs"]
mod bitwise;

use bitwise::{assert_recorded, bundled_scene, fnv, fnv_state, FNV_OFFSET};
use drape::integrate::{IntegratorKind, LinearSolver};
use drape::scene::EffectKind;

struct Case {
    name: &'static str,
    file: &'static str,
    res: usize,
    /// The scene's own effects when `None`.
    effects: Option<&'static [EffectKind]>,
    steps: usize,
}

const CASES: &[Case] = &[
    // 4096 vertices: the multigrid smooths parallel halves, the products run on the pool.
    Case {
        name: "hanging64_implicit",
        file: "hanging.yaml",
        res: 64,
        effects: None,
        steps: 30,
    },
    // Every effect, wind included (velocity-dependent and energy-injecting terms).
    Case {
        name: "hanging24_implicit_all",
        file: "hanging.yaml",
        res: 24,
        effects: Some(&EffectKind::ALL),
        steps: 60,
    },
    // Held contacts on a ball: filters, constraint impulses, in-solve friction.
    Case {
        name: "sphere24_implicit_contact",
        file: "sphere_drape.yaml",
        res: 24,
        effects: None,
        steps: 90,
    },
    // A tablecloth over a round table's rim: edge contacts as springs inside the solve.
    Case {
        name: "table24_implicit_edges",
        file: "table.yaml",
        res: 24,
        effects: None,
        steps: 90,
    },
];

const EXPECTED: &[(&str, u64)] = &[
    // The current physics' hashes, in `CASES` order: the preconditioner's structure and every
    // summation order of CG show in all four, the collision stage's response in the contact
    // cases.
    ("hanging64_implicit", 0x8fc88519cc4e52f7),
    ("hanging24_implicit_all", 0x4247c4a169073039),
    ("sphere24_implicit_contact", 0x623f87665e146ff3),
    ("table24_implicit_edges", 0xbae807081c0f31a1),
];

/// Runs a case; returns the hash of the per-step metrics (energies, speed, solver counts) and
/// the final positions and velocities, and the total contact count seen.
fn run(c: &Case) -> (u64, usize) {
    let mut s = bundled_scene(c.file, c.res);
    if let Some(effects) = c.effects {
        s.effects = effects.to_vec();
    }
    if s.effects.contains(&EffectKind::Wind) && s.wind.is_none() {
        s.wind = Some(serde_yaml_ng::from_str("velocity: [3.0, 1.0, 0.5]").expect("wind"));
    }
    s.solver.integrator = IntegratorKind::Implicit;
    // The multigrid-preconditioned path (`auto` may move small cloths in contact to the direct
    // one, whose agreement `tests/implicit_direct.rs` checks).
    s.solver.linear = LinearSolver::Pcg;
    let mut sim = s.build().expect("valid scene");
    let mut h = FNV_OFFSET;
    let mut contacts = 0;
    for _ in 0..c.steps {
        let m = sim.step().expect("stable");
        contacts += m.contacts;
        fnv(
            &mut h,
            [
                m.kinetic_energy,
                m.potential_energy,
                m.max_speed,
                m.cg_residual_max,
                f64::from(m.cg_iterations),
                f64::from(m.force_evaluations),
                m.contacts as f64,
            ],
        );
    }
    fnv_state(&mut h, &sim.cloth);
    (h, contacts)
}

#[test]
fn implicit_trajectories_are_bitwise_those_before_the_split() {
    let mut found = Vec::new();
    for c in CASES {
        let (h, contacts) = run(c);
        if c.name.contains("contact") || c.name.contains("edges") {
            assert!(contacts > 0, "{}: the contact case made no contact", c.name);
        }
        found.push((c.name, h));
    }
    assert_recorded(&found, EXPECTED);
}
