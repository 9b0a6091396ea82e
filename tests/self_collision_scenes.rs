//! Every bundled scene with `self_collision: true` added, run as a user would (scene file through
//! `Simulation`, robot driven), judged at every frame end on the state the step ends in: no
//! divergence, zero intersecting non-adjacent triangle pairs (counted by `common/self_check.rs`,
//! not by drape's metric), no edge beyond 1.5x rest unless the scene's forces explain it, and
//! pinned or attached vertices on target.

#[path = "common/self_check.rs"]
mod self_check;

use self_check::{bundled, run, Judged, SCENES};

/// Edge stretch allowed without a reason in the scene.
const STRETCH: f64 = 1.5;

/// Runs `name` with self-collision on for its full duration at `scale` x its resolution and
/// judges it. `stretch` is the bound on the largest edge over rest: 1.5, or where the scene's own
/// forces stretch it further (measured with self-collision off, same resolution), that value
/// plus 20% (the self-contact's share may not exceed a fifth of the scene's own). At twice the
/// resolution the scene's own stretch is measured in the test (`check_against_off`).
fn check(name: &str, scale: usize, stretch: f64) {
    let j = report(name, scale, None);
    assert!(j.diverged.is_none(), "{name}: {:?}", j.diverged);
    assert_eq!(
        j.max_intersections, 0,
        "{name}: intersecting triangle pairs from frame {:?}",
        j.first_intersecting_frame
    );
    assert!(
        j.max_stretch <= stretch,
        "{name}: an edge at {:.3}x rest (t = {:.3} s) > {stretch}",
        j.max_stretch,
        j.max_stretch_at
    );
    // Kinematic vertices are put on their targets every substep: round-off only.
    assert!(
        j.max_drift < 1e-9,
        "{name}: attached drift {:.2e} m",
        j.max_drift
    );
}

/// As [`check`], with the bound taken from the same scene and resolution run with self-collision
/// off: 1.5, or 1.2x what the scene itself stretches an edge to where that is more.
fn check_against_off(name: &str, scale: usize) {
    let mut off = bundled(name, scale);
    off.collision.self_collision = false;
    let base = run(&off, off.duration).max_stretch;
    eprintln!("{name} x{scale}: {base:.3}x rest with self-collision off");
    check(name, scale, STRETCH.max(1.2 * base));
}

macro_rules! scenes {
    ($($test:ident: $file:literal, $stretch:expr;)*) => {
        mod own_resolution {
            $( #[test] fn $test() { super::check($file, 1, $stretch); } )*
        }
        mod twice_the_resolution {
            $( #[test] #[ignore = "2x resolution: minutes"] fn $test() {
                super::check_against_off($file, 2);
            } )*
        }
        const TESTED: &[&str] = &[$($file),*];
    };
}

scenes! {
    // The cloth lands on the chair's back edge at 4 m/s: 1.83x with self-collision off.
    chair: "chair.yaml", 1.2 * 1.83;
    crumple: "crumple.yaml", super::STRETCH;
    flag: "flag.yaml", super::STRETCH;
    hanging: "hanging.yaml", super::STRETCH;
    robot_cape: "robot_cape.yaml", super::STRETCH;
    // 1.70x at t = 1.40 s with self-collision off, made by the arm's moving-feature springs in
    // the solve: the stretch is the arm's, not self-contact's.
    robot_drape_arm: "robot_drape_arm.yaml", 1.2 * 1.70;
    robot_pick_towel: "robot_pick_towel.yaml", super::STRETCH;
    robot_pinch_towel: "robot_pinch_towel.yaml", super::STRETCH;
    robot_towel: "robot_towel.yaml", super::STRETCH;
    shirt: "shirt.yaml", super::STRETCH;
    sleeve: "sleeve.yaml", super::STRETCH;
    sphere_drape: "sphere_drape.yaml", super::STRETCH;
    table: "table.yaml", super::STRETCH;
    three_corner_normal: "three_corner_normal.yaml", super::STRETCH;
    three_corner_soft_bending: "three_corner_soft_bending.yaml", super::STRETCH;
    // 100 N/m springs under gravity: 1.71x with self-collision off.
    three_corner_soft_stretch: "three_corner_soft_stretch.yaml", 1.2 * 1.71;
    three_corner_soft_warp: "three_corner_soft_warp.yaml", super::STRETCH;
}

/// The two scenes whose layers fold onto each other hardest, at twice their resolution in the
/// suite: the repulsion once pushed the two ends of an edge apart about a crease of the other
/// layer (flag 1.74x, crumple 1.81x; now 1.34 and 1.36). Their own stretch with self-collision
/// off is under 1.3 (flag 1.149, crumple 1.272), so the bound is 1.5.
#[test]
fn folded_layers_hold_the_stretch_bound_at_twice_the_resolution() {
    check("flag.yaml", 2, STRETCH);
    check("crumple.yaml", 2, STRETCH);
}

/// Every scene file in config/ (but the node's parameters) has a test above.
#[test]
fn every_bundled_scene_is_tested() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|f| f.ends_with(".yaml") && f != "node.yaml")
        .collect();
    files.sort();
    assert_eq!(files, TESTED);
    assert_eq!(SCENES, TESTED);
}

fn report(name: &str, scale: usize, seconds: Option<f64>) -> Judged {
    let mut scene = bundled(name, scale);
    if std::env::var("SELFCOL_OFF").is_ok() {
        scene.collision.self_collision = false;
    }
    if let Some(r) = std::env::var("SELFCOL_RES")
        .ok()
        .and_then(|r| r.parse().ok())
    {
        scene
            .cloths
            .iter_mut()
            .for_each(|c| c.grid.resolution = [r, r]);
    }
    let secs = seconds.unwrap_or(scene.duration);
    let j = run(&scene, secs);
    eprintln!(
        "{name} x{scale} {secs}s: frames {} t {:.3} diverged {:?} max_pairs {} first {:?} \
         stretch {:.3} at {:.3} (free ends {:.3}) drift {:.2e} speed {:.2} unresolved {} collide {:.2} s wall {:.2} s\n  {:?}",
        j.frames,
        j.simulated_s,
        j.diverged,
        j.max_intersections,
        j.first_intersecting_frame,
        j.max_stretch,
        j.max_stretch_at,
        j.max_free_stretch,
        j.max_drift,
        j.max_speed,
        j.unresolved,
        j.collision_s,
        j.wall_s,
        j.counts
    );
    j
}

/// Measurement table: `SELFCOL_SCENES=a.yaml,b.yaml SELFCOL_SCALE=2 SELFCOL_SECONDS=1
/// [SELFCOL_RES=48 (grid cloths' vertices per side)] [SELFCOL_OFF=1] [SELFCOL_TRACE=1] cargo test --test self_collision_scenes print_scenes -- --ignored --nocapture`.
#[test]
#[ignore = "measurement: prints the table"]
fn print_scenes() {
    let list = std::env::var("SELFCOL_SCENES").unwrap_or_default();
    let scale = std::env::var("SELFCOL_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let secs = std::env::var("SELFCOL_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok());
    let names: Vec<&str> = if list.is_empty() {
        SCENES.to_vec()
    } else {
        list.split(',').collect()
    };
    for n in names {
        report(n, scale, secs);
    }
}

/// The cape at twice its resolution (47x47) through its first swing: a CCD correction of a
/// vertex-triangle pair whose weight sat almost all on attached vertices threw the one free
/// vertex (0.4 % of the triangle) 3 m at 481 m/s at t = 1.70 s, and an edge to 248x rest, with
/// no divergence reported. Judged: the hard case's speed bound (`src/hard/self_contact.rs`: three
/// times the arms' 1.2 m/s plus a 0.6 m fall, 7.0 m/s), zero intersecting pairs, and edges with
/// a free end stretched at most 1.2x what the scene does with self-collision off.
#[test]
fn cape_at_twice_the_resolution_throws_no_vertex() {
    let on = bundled("robot_cape.yaml", 2);
    let mut off = on.clone();
    off.collision.self_collision = false;
    let base = run(&off, 1.8).max_free_stretch;
    let j = run(&on, 1.8);
    assert!(j.diverged.is_none(), "{:?}", j.diverged);
    assert_eq!(
        j.max_intersections, 0,
        "from frame {:?}",
        j.first_intersecting_frame
    );
    assert!(j.max_speed <= 7.0, "a vertex at {:.2} m/s", j.max_speed);
    assert!(
        j.max_free_stretch <= 1.2 * base,
        "an edge with a free end at {:.3}x rest, {base:.3}x with self-collision off",
        j.max_free_stretch
    );
}

/// A heap on the ground (crumple.yaml, at the hard cases' 14x14, its own 24x24 and 32x32): no
/// vertex behind the ground at any frame end, and the penetration drape reports at least what
/// the frame end shows. The repulsion of a layer landing on the one on the ground pushed a
/// vertex of it 2.7 mm below the ground (14x14) while the metric, measured on the vertex pass's
/// contacts only, said 0; the stage now tests the vertices self-contact moved against the
/// obstacles again and measures them. At 30x30 a vertex held on the ground, pushed by the layer
/// above, ended a frame 0.08 mm below it: those are tested again too.
#[test]
fn a_heap_stays_above_the_ground_and_its_penetration_is_reported() {
    for res in [14, 24, 30, 32] {
        let mut scene = bundled("crumple.yaml", 1);
        scene.cloths[0].grid.resolution = [res, res];
        let th = scene.cloths[0].material.thickness;
        let mut sim = scene.build().expect("crumple builds");
        let frames = (scene.duration / sim.settings.dt).round() as usize;
        for f in 0..frames {
            let m = sim.step().expect("no divergence");
            let (i, z) = sim
                .cloth
                .x
                .iter()
                .enumerate()
                .map(|(i, p)| (i, p.z))
                .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
            assert!(
                z >= 0.0,
                "{res}x{res}, frame {f}: vertex {i} {:.2} mm below the ground",
                -z * 1e3
            );
            assert!(
                m.deepest_penetration >= th - z - 1e-12,
                "{res}x{res}, frame {f}: vertex {i} {:.2} mm into the {:.0} mm layer, reported {:.2} mm",
                (th - z) * 1e3,
                th * 1e3,
                m.deepest_penetration * 1e3
            );
        }
    }
}
