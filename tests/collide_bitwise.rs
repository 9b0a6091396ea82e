//! The collision stage and its coupling to the solver, bit for bit: scenes through the stage's
//! paths (self-collision with impact zones, box edges and wedges under the implicit solver with
//! its held-contact feedback, a robot that grasps and releases, projection response with an
//! explicit integrator) hash to the values recorded before the coupling between solver and
//! stage was reorganised (issue 15; recorded on simcol at 8f987f2, main's arithmetic with the
//! collision files split). `tests/step_bitwise.rs` and
//! `tests/implicit_bitwise.rs` cover the integrators.
//!
//! A mismatch means an operation moved to another order somewhere in the collision stage or
//! in the feedback between solver and stage. To re-record after a deliberate physics change,
//! run with `--nocapture` and copy the printed table.

use drape::collide::{DetectionMode, ResponseMode};
use drape::integrate::IntegratorKind;
use drape::scene::Scene;
use std::path::Path;

struct Case {
    name: &'static str,
    file: &'static str,
    res: usize,
    /// The scene's own integrator when `None`.
    kind: Option<IntegratorKind>,
    /// Overrides of the scene's collision settings.
    mode: Option<DetectionMode>,
    response: Option<ResponseMode>,
    steps: usize,
}

const CASES: &[Case] = &[
    // Cloth falling onto itself: proximity repulsion, CCD passes, impact zones.
    Case {
        name: "crumple16_self",
        file: "crumple.yaml",
        res: 16,
        kind: None,
        mode: None,
        response: None,
        steps: 60,
    },
    // A cloth over a chair (boxes): vertex contacts, box edges and corners, wedges.
    Case {
        name: "chair16_edges",
        file: "chair.yaml",
        res: 16,
        kind: None,
        mode: None,
        response: None,
        steps: 90,
    },
    // A robot picks a towel off a table and lets go: moving obstacles, grasp and release.
    Case {
        name: "pick12_robot",
        file: "robot_pick_towel.yaml",
        res: 12,
        kind: None,
        mode: None,
        response: None,
        steps: 160,
    },
    // Positions projected with friction, no filter, discrete proximity, symplectic Euler.
    Case {
        name: "sphere16_projection",
        file: "sphere_drape.yaml",
        res: 16,
        kind: Some(IntegratorKind::SymplecticEuler),
        mode: Some(DetectionMode::Proximity),
        response: Some(ResponseMode::Projection),
        steps: 150,
    },
];

const EXPECTED: &[(&str, u64)] = &[
    ("crumple16_self", 0x68213d17a8b829ca),
    ("chair16_edges", 0xa6a0f323a4211f42),
    ("pick12_robot", 0xf82091a005d9fb84),
    ("sphere16_projection", 0xfadc50a365b3a77e),
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

/// Runs a case; returns the hash of the per-step metrics and the final state, and the total
/// contact count seen.
fn run(c: &Case) -> (u64, usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(c.file);
    let mut s = Scene::load(&path).expect("bundled scene");
    s.cloths[0].grid.resolution = [c.res, c.res];
    if c.file == "sphere_drape.yaml" {
        // Start resting on the ball's thickness layer, so contacts begin at once.
        s.cloths[0].grid.pose.xyz[2] = 0.605;
    }
    if let Some(kind) = c.kind {
        s.solver.integrator = kind;
        if kind != IntegratorKind::Implicit {
            s.solver.dt = 2e-4;
            s.solver.substeps = 1;
        }
    }
    if let Some(mode) = c.mode {
        s.collision.mode = mode;
    }
    if let Some(response) = c.response {
        s.collision.response = response;
    }
    let (mut sim, mut driver) = s.build_with_robot().expect("valid scene");
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut contacts = 0;
    for _ in 0..c.steps {
        if let Some(d) = driver.as_mut() {
            let next = sim.time() + sim.settings.dt;
            d.advance(&mut sim, next);
        }
        let m = sim.step().expect("stable");
        contacts += m.contacts;
        fnv(
            &mut h,
            [
                m.kinetic_energy,
                m.potential_energy,
                m.max_speed,
                m.deepest_penetration,
                m.contacts as f64,
                m.unresolved_contacts as f64,
                m.self_intersections.map_or(-1.0, |k| k as f64),
                f64::from(m.subdivisions),
                f64::from(m.cg_iterations),
            ],
        );
    }
    let x = sim.cloth.x.iter().flat_map(|p| p.to_array());
    let v = sim.cloth.v.iter().flat_map(|p| p.to_array());
    fnv(&mut h, x.chain(v));
    (h, contacts)
}

#[test]
fn collision_trajectories_are_bitwise_those_before_the_reorganisation() {
    let mut table = String::new();
    let mut mismatches = Vec::new();
    for c in CASES {
        let (h, contacts) = run(c);
        table += &format!("    (\"{}\", 0x{h:016x}),\n", c.name);
        assert!(contacts > 0, "{}: the case made no contact", c.name);
        match EXPECTED.iter().find(|(name, _)| *name == c.name) {
            Some(&(_, want)) if want == h => {}
            _ => mismatches.push(c.name),
        }
    }
    println!("const EXPECTED: &[(&str, u64)] = &[\n{table}];");
    assert!(mismatches.is_empty(), "changed: {mismatches:?}\n{table}");
}
