//! Speed-ups of the explicit step must not change a single bit of the physics: trajectories of a
//! few hundred explicit steps (sequential and two-thread sizes, every explicit integrator, the
//! velocity-dependent and energy-injecting effects, the guard's subdivision and a contact scene)
//! hash to the recorded values: those of the plain, unoptimised step, which every speed-up of
//! the explicit path must reproduce (the contact case with the current obstacle response).
//!
//! A mismatch means rounding changed somewhere in the force, update or guard path; since contact
//! scenes are chaotic, that would flip unrelated round-off-sensitive tests. To re-record after a
//! deliberate physics change, run with `--nocapture` and copy the printed table.

#[path = "common/bitwise.rs"]
mod bitwise;

use bitwise::{assert_recorded, bundled_scene, fnv, fnv_state, FNV_OFFSET};
use drape::integrate::IntegratorKind;
use drape::scene::EffectKind;

const BASE: &[EffectKind] = &[
    EffectKind::Gravity,
    EffectKind::Stretch,
    EffectKind::Shear,
    EffectKind::Bending,
];

const ALL: &[EffectKind] = &EffectKind::ALL;

struct Case {
    name: &'static str,
    file: &'static str,
    res: usize,
    kind: IntegratorKind,
    effects: &'static [EffectKind],
    dt: f64,
    substeps: u32,
    steps: usize,
}

const CASES: &[Case] = &[
    // The benchmark's configuration, on two threads (4096 vertices) and on one (1024).
    Case {
        name: "hanging64_symplectic_base",
        file: "hanging.yaml",
        res: 64,
        kind: IntegratorKind::SymplecticEuler,
        effects: BASE,
        dt: 1e-5,
        substeps: 1,
        steps: 300,
    },
    Case {
        name: "hanging32_symplectic_base",
        file: "hanging.yaml",
        res: 32,
        kind: IntegratorKind::SymplecticEuler,
        effects: BASE,
        dt: 1e-5,
        substeps: 1,
        steps: 300,
    },
    // Every effect, wind's external work in the guard, two substeps per frame.
    Case {
        name: "hanging64_symplectic_all",
        file: "hanging.yaml",
        res: 64,
        kind: IntegratorKind::SymplecticEuler,
        effects: ALL,
        dt: 2e-5,
        substeps: 2,
        steps: 150,
    },
    Case {
        name: "hanging64_explicit_all",
        file: "hanging.yaml",
        res: 64,
        kind: IntegratorKind::ExplicitEuler,
        effects: ALL,
        dt: 1e-5,
        substeps: 1,
        steps: 200,
    },
    Case {
        name: "hanging48_rk4_all",
        file: "hanging.yaml",
        res: 48,
        kind: IntegratorKind::Rk4,
        effects: ALL,
        dt: 2e-5,
        substeps: 1,
        steps: 100,
    },
    // A step over the stability limit: the guard halves it (subdivision path).
    Case {
        name: "hanging32_symplectic_subdivided",
        file: "hanging.yaml",
        res: 32,
        kind: IntegratorKind::SymplecticEuler,
        effects: BASE,
        dt: 1e-3,
        substeps: 1,
        steps: 20,
    },
    // Contacts with a sphere (continuous collision) from the first steps on.
    Case {
        name: "sphere32_symplectic_contact",
        file: "sphere_drape.yaml",
        res: 32,
        kind: IntegratorKind::SymplecticEuler,
        effects: &[
            EffectKind::Gravity,
            EffectKind::Stretch,
            EffectKind::Shear,
            EffectKind::Bending,
            EffectKind::Damping,
        ],
        dt: 2e-4,
        substeps: 1,
        steps: 300,
    },
];

/// The recorded hashes, in `CASES` order.
const EXPECTED: &[(&str, u64)] = &[
    ("hanging64_symplectic_base", 0x398e73586f61f87e),
    ("hanging32_symplectic_base", 0x9c31fa248d82ad4f),
    ("hanging64_symplectic_all", 0x3e0f4690ba24650a),
    ("hanging64_explicit_all", 0xc9e58ff88b87098c),
    ("hanging48_rk4_all", 0x3e074aa518bb0f27),
    ("hanging32_symplectic_subdivided", 0xb7a995fa51f78019),
    ("sphere32_symplectic_contact", 0x0f62f2549bdf0fe3),
];

/// Runs a case; returns the hash of the final positions and velocities, the per-step kinetic
/// energies and subdivision counts, and the total contact count seen.
fn run(c: &Case) -> (u64, usize, u32) {
    let mut s = bundled_scene(c.file, c.res);
    if c.file == "sphere_drape.yaml" {
        // Start resting on the ball's thickness layer, so contacts begin at once.
        s.cloths[0].grid.pose.xyz[2] = 0.605;
    }
    s.effects = c.effects.to_vec();
    s.solver.integrator = c.kind;
    s.solver.dt = c.dt;
    s.solver.substeps = c.substeps;
    s.cloths[0].material.skip_one = 500.0;
    if c.effects.contains(&EffectKind::Wind) {
        s.wind = Some(serde_yaml_ng::from_str("velocity: [3.0, 1.0, 0.5]").expect("wind"));
    }
    let mut sim = s.build().expect("valid scene");
    let mut h = FNV_OFFSET;
    let (mut contacts, mut subdivisions) = (0, 0);
    for _ in 0..c.steps {
        let m = sim.step().expect("stable");
        contacts += m.contacts;
        subdivisions += m.subdivisions;
        fnv(&mut h, [m.kinetic_energy, m.potential_energy, m.max_speed]);
    }
    fnv_state(&mut h, &sim.cloth);
    (h, contacts, subdivisions)
}

#[test]
fn explicit_trajectories_are_bitwise_those_before_the_speed_work() {
    let mut found = Vec::new();
    for c in CASES {
        let (h, contacts, subdivisions) = run(c);
        if c.name.starts_with("sphere") {
            assert!(contacts > 0, "{}: the contact case made no contact", c.name);
        }
        if c.name.ends_with("subdivided") {
            assert!(subdivisions > 0, "{}: the guard never subdivided", c.name);
        }
        found.push((c.name, h));
    }
    assert_recorded(&found, EXPECTED);
}
