//! The implicit step's trajectories, bit for bit: a few scenes through the implicit solver's
//! paths (multigrid with parallel halves, Newton iterations, held contacts with in-solve
//! friction and their constraint impulses, obstacle edges as contact springs) hash to the values
//! recorded on main at 06d618b, before the solver's files were split (issue 15). The explicit
//! paths have their own record in `tests/step_bitwise.rs`.
//!
//! A mismatch means an operation moved to another order somewhere in the solver or its
//! feedback to the collision stage. To re-record after a deliberate physics change, run with
//! `--nocapture` and copy the printed table.

use drape::integrate::IntegratorKind;
use drape::scene::{EffectKind, Scene};
use std::path::Path;

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
    ("hanging64_implicit", 0xaccbdf2aed35b5f3),
    ("hanging24_implicit_all", 0x09b74d283d9895da),
    ("sphere24_implicit_contact", 0xc6d05f7b1d5e319a),
    ("table24_implicit_edges", 0xa544239008951280),
];

/// FNV-1a over the bit patterns of the values.
fn fnv(h: &mut u64, values: impl IntoIterator<Item = f64>) {
    for v in values {
        for b in v.to_bits().to_le_bytes() {
            *h ^= b as u64;
            *h = h.wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// Runs a case; returns the hash of the per-step metrics (energies, speed, solver counts) and
/// the final positions and velocities, and the total contact count seen.
fn run(c: &Case) -> (u64, usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(c.file);
    let mut s = Scene::load(&path).expect("bundled scene");
    s.cloths[0].grid.resolution = [c.res, c.res];
    if let Some(effects) = c.effects {
        s.effects = effects.to_vec();
    }
    if s.effects.contains(&EffectKind::Wind) && s.wind.is_none() {
        s.wind = Some(serde_yaml_ng::from_str("velocity: [3.0, 1.0, 0.5]").expect("wind"));
    }
    s.solver.integrator = IntegratorKind::Implicit;
    let mut sim = s.build().expect("valid scene");
    let mut h = 0xcbf2_9ce4_8422_2325u64;
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
    let x = sim.cloth.x.iter().flat_map(|p| p.to_array());
    let v = sim.cloth.v.iter().flat_map(|p| p.to_array());
    fnv(&mut h, x.chain(v));
    (h, contacts)
}

#[test]
fn implicit_trajectories_are_bitwise_those_before_the_split() {
    let mut table = String::new();
    let mut mismatches = Vec::new();
    for (k, c) in CASES.iter().enumerate() {
        let (h, contacts) = run(c);
        table += &format!("    (\"{}\", 0x{h:016x}),\n", c.name);
        if c.name.contains("contact") || c.name.contains("edges") {
            assert!(contacts > 0, "{}: the contact case made no contact", c.name);
        }
        match EXPECTED.get(k) {
            Some(&(name, want)) if name == c.name && want == h => {}
            _ => mismatches.push(c.name),
        }
    }
    println!("const EXPECTED: &[(&str, u64)] = &[\n{table}];");
    assert!(
        mismatches.is_empty(),
        "trajectories differ from the recorded ones: {mismatches:?}"
    );
}
