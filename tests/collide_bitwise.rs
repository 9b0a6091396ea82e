//! The collision stage and its coupling to the solver, bit for bit: scenes through the stage's
//! paths (self-collision with impact zones, box edges and wedges under the implicit solver with
//! its held-contact feedback, a robot that grasps and releases, projection response with an
//! explicit integrator) hash to the recorded values, which a reorganisation of the stage or of
//! its coupling to the solver must reproduce. `tests/step_bitwise.rs` and
//! `tests/implicit_bitwise.rs` cover the integrators.
//!
//! A mismatch means an operation moved to another order somewhere in the collision stage or
//! in the feedback between solver and stage. To re-record after a deliberate physics change,
//! run with `--nocapture` and copy the printed table.

#[path = "common/bitwise.rs"]
mod bitwise;

use bitwise::{assert_recorded, bundled_scene, fnv, fnv_state, FNV_OFFSET};
use drape::collide::{DetectionMode, ResponseMode};
use drape::integrate::IntegratorKind;

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
    // The same at a spacing near its contact distance: pairs near in the rest shape (the sheet
    // squeezed in its own plane) answer too.
    Case {
        name: "crumple64_near",
        file: "crumple.yaml",
        res: 64,
        kind: None,
        mode: None,
        response: None,
        steps: 80,
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
    // The current physics' hashes, in `CASES` order. The contact cases are chaotic: a changed
    // rounding anywhere in the stage, its feedback to the solver or the solver's preconditioner
    // moves them all.
    ("crumple16_self", 0x3b9eb235b0738e05),
    ("crumple64_near", 0xe69a1c6c2501f5d4),
    ("chair16_edges", 0x7cf5eb2e53680cd1),
    ("pick12_robot", 0x91502f3bee59ea5e),
    ("sphere16_projection", 0x1fe679b46677527e),
];

/// Runs a case; returns the hash of the per-step metrics and the final state, and the total
/// contact count seen.
fn run(c: &Case) -> (u64, usize) {
    let mut s = bundled_scene(c.file, c.res);
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
    let mut h = FNV_OFFSET;
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
    fnv_state(&mut h, &sim.cloth);
    (h, contacts)
}

#[test]
fn collision_trajectories_are_bitwise_those_before_the_reorganisation() {
    let mut found = Vec::new();
    for c in CASES {
        let (h, contacts) = run(c);
        assert!(contacts > 0, "{}: the case made no contact", c.name);
        found.push((c.name, h));
    }
    assert_recorded(&found, EXPECTED);
}
