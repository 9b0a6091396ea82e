//! Picking by contact alone: the bundled `robot_pinch_towel.yaml` (no `grasps:` rule, no
//! attachment) run as a user would, with self-collision off and on, and judged at every frame
//! end on the state the step ends in: the fingers close on the towel's overhang, lift it at
//! least 20 cm, carry it back over the counter and let go when they open (the towel stays as
//! the gripper draws back); no vertex ever ends inside a finger,
//! no step fails, and with self-collision on no two triangles intersect.

#[path = "common/self_check.rs"]
mod self_check;

use drape::robot::{Geometry, Robot};
use drape::scene::Scene;
use drape::{Pose, Vec3};
use std::path::Path;

/// Depth (m) inside a finger that is round-off: a few ulps of a coordinate near 1 m.
const ROUND_OFF: f64 = 1e-12;

/// The trajectory's phases (s): the fingers are closed from `CLOSED`, the lift ends at
/// `LIFTED`, the carry at `CARRIED`; they are open again from `OPEN`, when the gripper draws
/// back.
const CLOSED: f64 = 1.4;
const LIFTED: f64 = 2.4;
const CARRIED: f64 = 3.2;
const OPEN: f64 = 3.5;

/// Signed distance from `p` to the box `[-half, half]` in `pose`'s frame (negative inside).
fn box_distance(pose: &Pose, half: Vec3, p: Vec3) -> f64 {
    let d = pose.inverse_transform_point(p).abs() - half;
    d.max(Vec3::ZERO).length() + d.max_element().min(0.0)
}

/// The fingers' collision boxes: (link index, box pose in the link frame, half extents).
fn finger_boxes(robot: &Robot) -> Vec<(usize, Pose, Vec3)> {
    let mut out = Vec::new();
    for name in ["right_finger_a", "right_finger_b"] {
        let link = robot.link_index(name).expect("a finger link");
        for (pose, g) in &robot.collision_shapes()[link] {
            if let Geometry::Box { half_extents } = g {
                out.push((link, *pose, *half_extents));
            }
        }
    }
    assert_eq!(out.len(), 2, "drape_bot's fingers are two boxes");
    out
}

/// What one run measured.
#[derive(Debug, Default)]
struct Pick {
    /// The towel's highest point at the start and at the end of the lift (m).
    start_top: f64,
    lifted_top: f64,
    /// The fewest pinched vertices over the frames from the lift's end to the carry's end.
    least_pinched_carrying: usize,
    /// How far the vertex nearest the closed fingers' mid-point when they have closed moves
    /// in the fingers' frame over the lift and carry (m): the grip's slip.
    slip_in_fingers: f64,
    /// Pinched vertices at the end of the run; how far the towel's centroid moved from the
    /// opening to the end, while the gripper drew back, and how far its nearest vertex is from
    /// the fingers' mid-point then (m).
    pinched_at_end: usize,
    moved_after_open: f64,
    gone_from_fingers: f64,
    /// Deepest a vertex ended a frame inside a finger (m; 0: none).
    deepest_in_finger: f64,
    /// Largest intersecting triangle pairs at a frame end (counted independently).
    max_intersections: usize,
    max_stretch: f64,
}

fn pick(self_collision: bool) -> Pick {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/robot_pinch_towel.yaml");
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.collision.self_collision = self_collision;
    let (mut sim, driver) = scene.build_with_robot().unwrap_or_else(|e| panic!("{e}"));
    let mut driver = driver.expect("a robot");
    let robot = driver.robot().clone();
    let fingers = finger_boxes(&robot);
    let dt = sim.settings.dt;
    let frames = (scene.duration / dt).round() as usize;
    let top = |x: &[Vec3]| x.iter().map(|p| p.z).fold(f64::MIN, f64::max);
    let centroid = |x: &[Vec3]| x.iter().copied().sum::<Vec3>() / x.len().max(1) as f64;
    let mut run = Pick {
        start_top: top(&sim.cloth.x),
        least_pinched_carrying: usize::MAX,
        ..Pick::default()
    };
    let mut centroid_at_open = None;
    let mut gripped: Option<(usize, Vec3)> = None;
    for k in 0..frames {
        let t = sim.time() + dt;
        driver.advance(&mut sim, t);
        let m = sim
            .step()
            .unwrap_or_else(|e| panic!("frame {k} (t = {t:.3} s): {e}"));
        let x = &sim.cloth.x;
        assert!(x.iter().all(|p| p.is_finite()), "frame {k}: not finite");
        let poses = driver.link_poses();
        for &(link, local, half) in &fingers {
            let pose = poses[link].mul(&local);
            for p in x {
                run.deepest_in_finger = run.deepest_in_finger.max(-box_distance(&pose, half, *p));
            }
        }
        let mid = 0.5 * poses[fingers[0].0].mul(&fingers[0].1).translation
            + 0.5 * poses[fingers[1].0].mul(&fingers[1].1).translation;
        let nearest = x.iter().map(|p| p.distance(mid)).fold(f64::MAX, f64::min);
        let finger = poses[fingers[0].0];
        if t >= CLOSED + 0.1 && gripped.is_none() {
            let v = (0..x.len())
                .min_by(|a, b| x[*a].distance(mid).total_cmp(&x[*b].distance(mid)))
                .unwrap_or(0);
            gripped = Some((v, finger.inverse_transform_point(x[v])));
        }
        if let Some((v, local)) = gripped.filter(|_| t <= CARRIED) {
            let slip = finger.inverse_transform_point(x[v]).distance(local);
            run.slip_in_fingers = run.slip_in_fingers.max(slip);
        }
        run.gone_from_fingers = nearest;
        if (LIFTED..=CARRIED).contains(&t) {
            run.least_pinched_carrying = run.least_pinched_carrying.min(m.pinched_vertices);
        }
        if (t - LIFTED).abs() < 0.5 * dt {
            run.lifted_top = top(x);
        }
        if t >= OPEN && centroid_at_open.is_none() {
            centroid_at_open = Some(centroid(x));
        }
        run.pinched_at_end = m.pinched_vertices;
        run.max_stretch = run.max_stretch.max(sim.cloth.max_edge_stretch());
        if self_collision {
            let pairs = self_check::intersecting_pairs(x, &sim.cloth.triangles);
            run.max_intersections = run.max_intersections.max(pairs);
        }
    }
    run.moved_after_open =
        (centroid_at_open.unwrap_or(Vec3::NAN) - centroid(&sim.cloth.x)).length();
    run
}

fn judge(self_collision: bool) {
    let r = pick(self_collision);
    eprintln!("self-collision {self_collision}: {r:?}");
    assert!(
        r.lifted_top - r.start_top >= 0.2,
        "lifted only {:.3} m",
        r.lifted_top - r.start_top
    );
    assert!(
        r.least_pinched_carrying > 0,
        "the towel left the fingers during the carry"
    );
    // Held: the gripped cloth slides less than a third of the pads' length (6 cm).
    assert!(
        r.slip_in_fingers < 0.02,
        "the gripped cloth slid {:.3} m in the fingers",
        r.slip_in_fingers
    );
    assert_eq!(
        r.pinched_at_end, 0,
        "still pinched after the fingers opened"
    );
    // Let go: the gripper draws back 20 cm and the towel does not follow it (settling on the
    // counter's edge moves it a few centimetres).
    assert!(
        r.moved_after_open < 0.1 && r.gone_from_fingers > 0.1,
        "after the fingers opened the towel moved {:.3} m and is {:.3} m from them",
        r.moved_after_open,
        r.gone_from_fingers
    );
    assert!(
        r.deepest_in_finger <= ROUND_OFF,
        "a vertex ended {:.3e} m inside a finger",
        r.deepest_in_finger
    );
    assert_eq!(r.max_intersections, 0, "intersecting triangle pairs");
}

#[test]
fn drape_bot_picks_carries_and_drops_a_towel_by_contact_alone() {
    judge(false);
}

#[test]
fn drape_bot_picks_a_towel_by_contact_alone_with_self_collision() {
    judge(true);
}
