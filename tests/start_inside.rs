//! Cloth that starts inside an obstacle, in full simulations: reported when the
//! scene is built, then led out consistently (each connected patch the way it came in, or across
//! the cloth when it came in from several sides) and without tearing, judged at every frame end:
//!
//! - every vertex is out of every solid within a few frames, and the step metrics say how many
//!   are still on their way out until then;
//! - no mesh edge passes through an obstacle deeper than the cloth's thickness (a patch split
//!   across the obstacle keeps it between two rows for good, its edges stretched over it);
//! - the largest edge stays within `1 + 2 EXIT_STEP` of rest: the lead-out's own step, and one
//!   more the solve has not relaxed yet (it follows each pass within a substep or two);
//! - the guard does not cascade (fewer subdivisions than frames; a cloth kept astride an
//!   obstacle subdivides nearly every step).

use drape::scene::Scene;
use drape::sim::Simulation;
use parry3d::math::Pose as PPose;
use parry3d::shape::Segment;
use std::path::Path;

/// What a run did to the cloth that started inside.
#[derive(Debug, Default)]
struct Judged {
    /// Vertices inside an obstacle when built.
    inside_at_build: usize,
    /// The last frame that ended with a vertex inside an obstacle, or with the stage still
    /// leading one out.
    last_inside_frame: Option<usize>,
    last_exiting_frame: Option<usize>,
    /// Largest edge length over rest length of the judged edges, and when.
    max_stretch: f64,
    max_stretch_at: f64,
    /// Deepest any mesh edge passes into an obstacle at a frame end after the lead-out (m), and
    /// the cloth's thickness.
    deepest_edge: f64,
    thickness: f64,
    subdivisions: u32,
    frames: usize,
    diverged: Option<String>,
    wall_s: f64,
}

fn inside(sim: &Simulation) -> usize {
    sim.collision().map_or(0, |s| {
        s.overlaps(&sim.cloth.x).iter().map(|o| o.vertices).sum()
    })
}

/// Deepest a mesh edge of the cloth passes into an obstacle (m; 0 when none touches).
fn deepest_edge(sim: &Simulation, edges: &[(usize, usize, f64)]) -> f64 {
    let Some(stage) = sim.collision() else {
        return 0.0;
    };
    let mut deepest: f64 = 0.0;
    for o in stage.obstacles() {
        let local = |i: usize| o.pose.inverse_transform_point(sim.cloth.x[i]).as_vec3();
        for &(a, b, _) in edges {
            let seg = Segment::new(local(a), local(b));
            let c = parry3d::query::contact(
                &PPose::IDENTITY,
                &seg,
                &PPose::IDENTITY,
                o.shape.as_ref(),
                0.0,
            );
            if let Ok(Some(c)) = c {
                deepest = deepest.max(-f64::from(c.dist));
            }
        }
    }
    deepest
}

/// Runs `scene` for `seconds`, judging the edges `judged` selects (by their two vertices) for
/// stretch and every edge for passing through an obstacle once the lead-out is over.
fn run(scene: &Scene, seconds: f64, judged: impl Fn(usize, usize) -> bool) -> Judged {
    let t0 = std::time::Instant::now();
    let (mut sim, mut driver) = scene
        .build_with_robot()
        .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
    let mut edges = Vec::new();
    for t in &sim.cloth.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if a < b {
                edges.push((a, b, (sim.cloth.x[a] - sim.cloth.x[b]).length()));
            }
        }
    }
    let mut j = Judged {
        inside_at_build: inside(&sim),
        thickness: sim.cloth.thickness.iter().copied().fold(0.0, f64::max),
        ..Judged::default()
    };
    let frames = (seconds / sim.settings.dt).round() as usize;
    let trace = std::env::var_os("START_INSIDE_TRACE").is_some();
    for f in 0..frames {
        if let Some(d) = driver.as_mut() {
            let t = sim.time() + sim.settings.dt;
            d.advance(&mut sim, t);
        }
        let exiting = match sim.step() {
            Ok(m) => {
                j.subdivisions += m.subdivisions;
                m.exiting_vertices
            }
            Err(e) => {
                j.diverged = Some(e.to_string());
                break;
            }
        };
        assert!(sim.cloth.x.iter().all(|p| p.is_finite()));
        j.frames = f + 1;
        let n = inside(&sim);
        if n > 0 {
            j.last_inside_frame = Some(f);
        }
        if exiting > 0 {
            j.last_exiting_frame = Some(f);
        }
        let s = (edges.iter())
            .filter(|&&(a, b, _)| judged(a, b))
            .map(|&(a, b, r)| (sim.cloth.x[a] - sim.cloth.x[b]).length() / r)
            .fold(0.0, f64::max);
        let through = if exiting == 0 {
            deepest_edge(&sim, &edges)
        } else {
            0.0
        };
        if trace {
            let worst = (edges.iter())
                .map(|&(a, b, r)| ((sim.cloth.x[a] - sim.cloth.x[b]).length() / r, a, b))
                .fold((0.0, 0, 0), |w, e| if e.0 > w.0 { e } else { w });
            eprintln!(
                "  worst edge {worst:?} x {:?} {:?}",
                sim.cloth.x[worst.1], sim.cloth.x[worst.2]
            );
            eprintln!(
                "t {:.3} inside {n} exiting {exiting} stretch {s:.3} edge depth {:.1} mm subdiv {}",
                sim.time(),
                through * 1e3,
                sim.last_metrics().subdivisions
            );
        }
        j.deepest_edge = j.deepest_edge.max(through);
        if s > j.max_stretch {
            (j.max_stretch, j.max_stretch_at) = (s, sim.time());
        }
    }
    j.wall_s = t0.elapsed().as_secs_f64();
    j
}

/// The acceptance above: out by frame `out_by`, stretch within `stretch`.
fn accept(name: &str, j: &Judged, out_by: usize, stretch: f64) {
    let frames = j.frames;
    eprintln!("{name}: {j:?}");
    assert!(j.inside_at_build > 0, "{name}: the case starts clear");
    assert_eq!(j.diverged, None, "{name}");
    assert!(
        j.last_inside_frame.is_none_or(|f| f < out_by)
            && j.last_exiting_frame.is_none_or(|f| f < out_by),
        "{name}: still inside at frame {:?} (exiting reported until {:?}), bound {out_by}",
        j.last_inside_frame,
        j.last_exiting_frame
    );
    assert!(
        j.deepest_edge <= j.thickness,
        "{name}: an edge passes {:.1} mm into an obstacle (thickness {:.1} mm)",
        j.deepest_edge * 1e3,
        j.thickness * 1e3
    );
    assert!(
        j.max_stretch <= stretch,
        "{name}: stretch {:.3} at t = {:.3} s (bound {stretch})",
        j.max_stretch,
        j.max_stretch_at
    );
    assert!(
        (j.subdivisions as usize) < frames,
        "{name}: the guard subdivided {} times in {frames} frames",
        j.subdivisions
    );
}

fn config(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A scene of one grid cloth of the usual test material (200 g/m^2, stretch 1000 N/m) at 60 Hz with
/// two substeps, `cloth` its grid (and pins) lines, `obstacle` its one obstacle.
fn scene(name: &str, cloth: &str, obstacle: &str) -> Scene {
    let yaml = format!(
        r#"
name: {name}
duration: 1.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 2 }}
cloths:
  - name: sheet
{cloth}
    material: {{ density: 0.2, stretch: 1000.0, shear: 100.0, bend_warp: 1.0e-5, bend_weft: 1.0e-5, damping: {{ spring: 0.05, air: 0.1 }}, thickness: 0.005, friction: 0.3 }}
obstacles:
  - {obstacle}
collision: {{ mode: continuous }}
"#
    );
    Scene::from_yaml(&yaml, name).unwrap_or_else(|e| panic!("{e}"))
}

/// The lead-out moves a vertex at most a sixth of its shortest edge per pass (`overlap.rs`).
const EXIT_STEP: f64 = 1.0 / 6.0;
const STRETCH: f64 = 1.0 + 2.0 * EXIT_STEP;

/// robot_cape with the cape 5 cm longer: its hem hangs 5 cm into drape_bot's base box (two rows
/// of vertices, 10 cm box). Each row pushed to its nearest face put the box between them for
/// good: 4.46x rest on the edge between, 7952 guard subdivisions in 2 s, 48 s of wall time.
/// Judged: the lower half, away from the attachments, before the arms swing (t = 0.5 s).
fn cape() -> Scene {
    let mut s = config("robot_cape.yaml");
    let g = &mut s.cloths[0].grid;
    g.size = [0.6, 0.65];
    g.resolution = [24, 26];
    g.pose.xyz[2] = 0.375;
    s
}

fn cape_lower_half(a: usize, b: usize) -> bool {
    a.min(b) / 24 < 13
}

#[test]
fn a_cape_hem_inside_the_base_leaves_it_upwards_without_tearing() {
    let j = run(&cape(), 0.5, cape_lower_half);
    accept("cape", &j, 6, STRETCH);
}

/// A free sheet placed through a sphere (its middle 15 cm deep): the disc inside leaves upwards,
/// the way its edges cross the sphere, then the sheet drapes on it.
fn sphere() -> Scene {
    scene(
        "through_sphere",
        "    grid: { size: [1.0, 1.0], resolution: [25, 25], pose: { xyz: [0.0, 0.0, 0.6] } }",
        "{ name: ball, shape: { type: sphere, radius: 0.3 }, pose: { xyz: [0, 0, 0.45] } }",
    )
}

#[test]
fn a_sheet_through_a_sphere_leaves_it_upwards() {
    let j = run(&sphere(), 1.0, |_, _| true);
    accept("sphere", &j, 15, STRETCH);
}

/// robot_drape_arm with the cloth lowered onto the arm's axis (z = 0.64 m): the outstretched
/// arm lies in the cloth, and the one patch inside the upper arm, forearm, palm and fingers
/// came in from both sides: it leaves across the cloth, to the nearer side, as one. (Each
/// obstacle's patch on its own way split the cloth between the forearm and the palm, an edge
/// 32 mm into the arm; a wedge between the palm and a finger projected a vertex out of the
/// finger's side at once.)
fn arm_in_cloth(friction: Option<f64>, per_side: Option<usize>) -> Judged {
    let mut s = config("robot_drape_arm.yaml");
    s.cloths[0].grid.pose.xyz[2] = 0.64;
    if let Some(r) = per_side {
        s.cloths[0].grid.resolution = [r, r];
    }
    if let Some(mu) = friction {
        s.cloths[0].material.friction = mu;
    }
    run(&s, 1.0, |_, _| true)
}

/// Without friction and with the scene's (0.5), within the lead-out's stretch bound. Before the
/// rim of the patch (vertices outside the arm but inside its contact layer) left with it, the
/// vertex pass pushed those to the palm's and forearm's nearest faces at once, in the cloth's
/// plane: the edges there compressed, the next solve buckled the cloth out of its plane, 1.53x
/// rest without friction and 2.91x with it; then a cloth edge 8 mm above the palm's corner,
/// pushed sideways each substep (`ccd.rs`, `ee_hit`), 1.33x. Earlier: a vertex retired alone while its edge still
/// cut the forearm spiked to 3.49x without friction, and one retired while its neighbour was
/// still inside to 3.46x with it (their edge ended through the axis); both now wait
/// (`retire_exits`).
///
/// Also at 33 x 33, where a column of the cloth lies on the face the closed fingers share:
/// read as in neither finger's layer, it was pushed out of one through the other (8 mm across
/// the cloth in one pass), and the cloth around followed: 1.37x (now 1.24 and 1.14).
#[test]
fn an_arm_lying_in_a_cloth_leaves_it_without_tearing() {
    for per_side in [None, Some(33)] {
        for mu in [Some(0.0), None] {
            let j = arm_in_cloth(mu, per_side);
            let side = per_side.map_or("the scene's".into(), |r| r.to_string());
            let name = format!("arm, {side} vertices a side, friction {mu:?}");
            accept(&name, &j, 15, STRETCH);
        }
    }
}

/// At 60 x 60 with the scene's friction (0.5): a vertex beside the forearm, pulled into it by
/// its neighbour rising out of it, was pushed back each substep, and its friction (a half of
/// that push) held it while the neighbour rose, like a rope round a capstan: their edge reached
/// 1.42x rest at t = 0.1 s (1.24x without friction; 1.24x now). Cloth beside a lead-out now slides on the
/// solid it leaves without friction (`exit::slip_around`). A finer cloth takes longer to
/// leave: a sixth of its shorter edge a substep at the least (two substeps a frame), along a
/// way out no longer than the largest link radius (the cloth lies through the arm's axis; the
/// upper arm's 5 cm) and the contact layer beyond it (the thickness, 8 mm): within
/// `0.058 / (2 edge / 6)` frames (24 here).
#[test]
fn an_arm_lying_in_a_fine_cloth_with_friction_leaves_it_without_tearing() {
    let j = arm_in_cloth(None, Some(60));
    let edge = 0.44 / 59.0;
    let out_by = ((0.05_f64 + 0.008) / (2.0 * edge / 6.0)).ceil() as usize;
    accept("arm, 60 vertices a side, friction 0.5", &j, out_by, STRETCH);
}

/// A towel hanging from its top corners with its lower rows 4 cm into a table (a box): they
/// leave through the top face, the way the towel enters it.
fn towel() -> Scene {
    scene(
        "towel_in_table",
        "    grid: { size: [0.5, 0.5], resolution: [21, 21], pose: { xyz: [0.0, 0.0, 0.81], rpy: [1.5707963267948966, 0.0, 0.0] } }
    pins: [ { region: top_left }, { region: top_right } ]",
        "{ name: table, shape: { type: box, half_extents: [0.4, 0.4, 0.3] }, pose: { xyz: [0.0, 0.0, 0.3] } }",
    )
}

#[test]
fn a_towel_hanging_into_a_table_leaves_through_its_top() {
    let j = run(&towel(), 1.0, |_, _| true);
    accept("towel", &j, 15, STRETCH);
}

/// A sheet tilted into the ground (its low edge 4 cm below z = 0): the rows under the plane
/// leave along its normal.
fn ground() -> Scene {
    scene(
        "into_ground",
        "    grid: { size: [0.5, 0.5], resolution: [21, 21], pose: { xyz: [0.0, 0.0, 0.045], rpy: [0.35, 0.0, 0.0] } }",
        "{ name: ground, shape: { type: plane, normal: [0.0, 0.0, 1.0] } }",
    )
}

#[test]
fn a_sheet_tilted_into_the_ground_leaves_it_along_its_normal() {
    let j = run(&ground(), 1.0, |_, _| true);
    accept("ground", &j, 15, STRETCH);
}

/// The same scenes with self-collision on hold the same acceptance: the lead-out is the
/// obstacle pass's, and cloth-cloth contact must not undo it (nor the cape's hem fold through
/// itself on the base's top).
#[test]
fn with_self_collision_the_same_scenes_leave_their_obstacles_without_tearing() {
    let on = |mut s: Scene| {
        s.collision.self_collision = true;
        s
    };
    let j = run(&on(cape()), 0.5, cape_lower_half);
    accept("cape, self-collision", &j, 6, STRETCH);
    for (name, s) in [
        ("sphere", sphere()),
        ("towel", towel()),
        ("ground", ground()),
    ] {
        let j = run(&on(s), 1.0, |_, _| true);
        accept(&format!("{name}, self-collision"), &j, 15, STRETCH);
    }
}

/// Cloth laid exactly on a face is on it, not inside: robot_cape's hem rests on drape_bot's base
/// box (z = 0.4 - 0.3 against 0.05 + 0.05, a rounding error either side), and the scene builds
/// with no vertex inside; lowered by 1 mm, the same hem is reported inside, 1 mm deep.
#[test]
fn a_hem_laid_exactly_on_a_face_does_not_start_inside() {
    let overlaps = |s: &Scene| {
        let (sim, _) = s
            .build_with_robot()
            .unwrap_or_else(|e| panic!("{}: {e}", s.name));
        sim.collision()
            .expect("the robot collides")
            .overlaps(&sim.cloth.x)
    };
    let on = overlaps(&config("robot_cape.yaml"));
    assert!(on.is_empty(), "{on:?}");
    let mut lower = config("robot_cape.yaml");
    lower.cloths[0].grid.pose.xyz[2] -= 0.001;
    let inside = overlaps(&lower);
    assert!(
        inside
            .iter()
            .any(|o| o.obstacle.starts_with("base_link") && (o.deepest - 0.001).abs() < 1e-6),
        "{inside:?}"
    );
}
