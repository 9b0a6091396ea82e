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
    // Re-recorded when the self-contact broad phase became a BVH with normal cones, and again
    // when the repulsion and CCD passes became Jacobi (weighted mean per vertex, independent of
    // the pair order). crumple64_near recorded on main at 44f4f5a, before the near pairs got
    // their own list and test. pick12_robot re-recorded when a held link's interpolated pose
    // stopped drifting by round-off (`Pose::lerp` ends exactly on its poses): the still robot
    // is a still obstacle again. crumple64_near and chair16_edges re-recorded when a collision
    // pass that moved a vertex more than a third of its spacing came to split the substep
    // (`sim/fast.rs`, `jumped`): both land on an obstacle. crumple16_self, crumple64_near,
    // chair16_edges and pick12_robot re-recorded when the multigrid's iteration counts came to
    // be read from a step's first solve only (`integrate/implicit/hierarchy.rs`): a step with
    // refits builds its hierarchy at other solves. crumple64_near and chair16_edges re-recorded
    // when split substeps came to keep the last full substep's aggregates
    // (`integrate/implicit/solve.rs`): both split while they land. All four re-recorded when
    // rows without a strong connection (pinned, or held by a sticking drag) left the
    // multigrid's aggregates (`integrate/precond/aggregate.rs`). crumple16_self and
    // crumple64_near re-recorded when proximity stopped answering a vertex within the
    // contact distance of a triangle's plane but not of the triangle (`proximity.rs`).
    // chair16_edges re-recorded when an obstacle edge's contact closest at its end (a box
    // corner) took the separation as its normal, not the two edges' plane normal (`ccd.rs`).
    // All four re-recorded when a step's active-set rounds came to be solved to 1e-2 first,
    // then polished to the scene's tolerance (`integrate/implicit/step.rs`). crumple64_near
    // re-recorded when levels from 512 rows on came to be smoothed in two halves and CG's
    // vector passes to be summed in two (`integrate/precond/smooth.rs`, `integrate/cg.rs`).
    // All four re-recorded when a solve whose start meets its tolerance came to leave the
    // multigrid alone (`integrate/implicit/solve.rs`): its rebuild schedule counts other solves.
    // All five re-recorded when the obstacle response's friction came to move a vertex that
    // arrived during the step by its velocity change over the part of the step in contact only
    // (`collide/respond.rs`, `contact_share`): each lands on an obstacle. The two crumples
    // again when the vertices self-contact moved came to be tested against the obstacles
    // again whether or not the vertex pass held them already (`collide/resolve.rs`). All four
    // implicit cases again when Newton's corrections came to be preconditioned by coarse levels
    // rebuilt for the iterate's matrix (`integrate/implicit/solve.rs`, `SolveKind::Newton`).
    // The two crumples again when layers resting on each other came to be held apart by pair
    // springs inside the implicit solve (`sim/coupling.rs`, `layer_springs`). Those two and the
    // chair again when a spring stretched beyond what its solve's linearisation predicts came to
    // send the step to Newton (`integrate/implicit/newton.rs`, `unseen_stretch`). All four
    // implicit cases again when free vertices heading into a still solid (the ground, the
    // chair, the table) came to be stopped on its contact layer inside the solve
    // (`collide/arrival.rs`, `Coupling::arrival_springs`).
    ("crumple16_self", 0x8adab6bcd159ea8e),
    ("crumple64_near", 0x75fc9d7c8fcd2d50),
    ("chair16_edges", 0x348c37ed77b581f2),
    ("pick12_robot", 0xa0058cbeae2e58c2),
    ("sphere16_projection", 0xcf4c4e2b2272c4c0),
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
