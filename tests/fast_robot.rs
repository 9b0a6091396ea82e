//! Fast robot links through cloth in full simulations (the robot variants of fast thin links):
//! drape_bot's right arm swung at its joint-velocity limits (shoulder pitch 2.0 rad/s, wrist
//! 3.0 rad/s) up through a towel hanging from a rail in front of it, so that the forearm, the
//! palm and both fingers (15 mm boxes, a 20 mm cloth spacing) pass where the towel hangs.
//!
//! Judged exactly, between every two frame ends: no cloth edge crosses a link's core segment
//! (its axis, or a box's medial segment along its longest side, at least half the link's
//! smallest width inside it). Both move linearly over the frame here (60 Hz; the arm turns
//! 0.033 rad a frame); a crossing is a root of the edge and segment's coplanarity cubic, found by
//! sign changes over 64 samples and bisection, at which the two segments meet. The check is
//! written apart from the collision stage's CCD.

use drape::scene::Scene;
use drape::sim::Simulation;
use drape::Vec3;
use std::path::PathBuf;

/// (shoulder speed rad/s, wrist speed rad/s, thickness m, friction).
fn scene(shoulder: f64, wrist: f64, thickness: f64, friction: f64) -> Scene {
    let t_end = 2.0 / shoulder;
    let yaml = format!(
        r#"
name: fast_robot
duration: 1.2
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 2 }}
cloths:
  - name: towel
    grid: {{ size: [0.5, 0.7], resolution: [26, 36], pose: {{ xyz: [0.40, -0.25, 0.75], rpy: [1.5707963267948966, 0.0, 1.5707963267948966] }} }}
    material: {{ density: 0.2, stretch: 1000.0, shear: 100.0, bend_warp: 1.0e-5, bend_weft: 1.0e-5, damping: {{ spring: 0.05, air: 0.1 }}, thickness: {thickness}, friction: {friction} }}
    pins: [ {{ region: top_edge }} ]
robot:
  urdf: {urdf}
  trajectory:
    names: [right_shoulder_pitch, right_wrist]
    points:
      - {{ t: 0.0, positions: [0.0, 0.0] }}
      - {{ t: {t_end}, positions: [-2.0, {wrist_end}] }}
collision: {{ mode: continuous }}
"#,
        urdf = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("urdf/drape_bot.urdf")
            .display(),
        wrist_end = (wrist * t_end).min(2.9),
    );
    Scene::from_yaml(&yaml, "fast_robot").unwrap_or_else(|e| panic!("{e}"))
}

/// A link's core segment in its own frame: along the longest side of its local bounding box,
/// shortened at each end by the smallest half-width (so a crossing is inside the solid).
fn core(o: &drape::collide::Obstacle) -> (Vec3, Vec3) {
    let b = o.shape.compute_local_aabb();
    let (lo, hi) = (b.mins.as_dvec3(), b.maxs.as_dvec3());
    let (c, e) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
    let k = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let min = e.min_element();
    let mut d = Vec3::ZERO;
    d[k] = (e[k] - min).max(0.5 * e[k]);
    (c - d, c + d)
}

fn lerp(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    a + (b - a) * t
}

/// Whether segments `p` and `q` meet (closest distance within `tol`, interior to both).
fn meet(p: (Vec3, Vec3), q: (Vec3, Vec3), tol: f64) -> bool {
    let (d1, d2, r) = (p.1 - p.0, q.1 - q.0, p.0 - q.0);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let (b, c) = (d1.dot(d2), d1.dot(r));
    let den = a * e - b * b;
    if den <= 1e-18 * a * e {
        return false;
    }
    let s = ((b * f - c * e) / den).clamp(0.0, 1.0);
    let t = ((b * s + f) / e).clamp(0.0, 1.0);
    let s = ((b * t - c) / a).clamp(0.0, 1.0);
    (p.0 + d1 * s - (q.0 + d2 * t)).length() <= tol
}

/// Whether the edge moving linearly from `e0` to `e1` crosses the segment moving from `s0` to
/// `s1` within the frame.
fn crosses(e0: (Vec3, Vec3), e1: (Vec3, Vec3), s0: (Vec3, Vec3), s1: (Vec3, Vec3)) -> bool {
    let at = |t: f64| {
        (
            (lerp(e0.0, e1.0, t), lerp(e0.1, e1.1, t)),
            (lerp(s0.0, s1.0, t), lerp(s0.1, s1.1, t)),
        )
    };
    let vol = |t: f64| {
        let (e, s) = at(t);
        (e.1 - e.0).cross(s.0 - e.0).dot(s.1 - e.0)
    };
    const N: usize = 64;
    let mut prev = vol(0.0);
    for k in 1..=N {
        let t1 = k as f64 / N as f64;
        let cur = vol(t1);
        if prev == 0.0 || prev.signum() != cur.signum() {
            let (mut lo, mut hi) = ((k - 1) as f64 / N as f64, t1);
            for _ in 0..50 {
                let mid = 0.5 * (lo + hi);
                if vol(mid).signum() == vol(lo).signum() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let (e, s) = at(0.5 * (lo + hi));
            let scale = (e.1 - e.0).length().max((s.1 - s.0).length());
            if meet(e, s, 1e-9 * scale) {
                return true;
            }
        }
        prev = cur;
    }
    false
}

/// The right arm's links the towel meets.
const LINKS: [&str; 4] = [
    "right_forearm/0",
    "right_palm/0",
    "right_finger_a/0",
    "right_finger_b/0",
];

fn cores(sim: &Simulation) -> Vec<(Vec3, Vec3)> {
    let stage = sim.collision().expect("a robot scene collides");
    LINKS
        .iter()
        .map(|name| {
            let o = (stage.obstacles().iter())
                .find(|o| o.name == *name)
                .unwrap_or_else(|| panic!("no obstacle {name}"));
            let (a, b) = core(o);
            (o.pose.transform_point(a), o.pose.transform_point(b))
        })
        .collect()
}

#[derive(Debug, Default)]
struct Outcome {
    /// Frames in which a cloth edge crossed a link's core, and the first as words.
    crossed_frames: usize,
    first: Option<String>,
    max_stretch: f64,
    max_stretch_at: f64,
    contacts: usize,
    splits: u32,
    subdivisions: u32,
}

fn run(scene: &Scene) -> Outcome {
    let (mut sim, driver) = scene.build_with_robot().unwrap_or_else(|e| panic!("{e}"));
    let mut driver = driver.expect("a robot scene");
    let mut edges = Vec::new();
    for t in &sim.cloth.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if a < b {
                edges.push((a, b));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let mut out = Outcome::default();
    let frames = (scene.duration / sim.settings.dt).round() as usize;
    for f in 0..frames {
        let (x0, c0) = (sim.cloth.x.clone(), cores(&sim));
        let t = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, t);
        let m = sim
            .step()
            .unwrap_or_else(|e| panic!("frame {f}: {e}"))
            .clone();
        (out.contacts, out.splits, out.subdivisions) = (
            out.contacts.max(m.contacts),
            out.splits + m.contact_splits,
            out.subdivisions + m.subdivisions,
        );
        let x1 = &sim.cloth.x;
        assert!(x1.iter().all(|p| p.is_finite()), "frame {f}: not finite");
        let c1 = cores(&sim);
        let mut crossed = None;
        'links: for (k, (s0, s1)) in c0.iter().zip(&c1).enumerate() {
            let (lo, hi) = (
                s0.0.min(s0.1).min(s1.0).min(s1.1),
                s0.0.max(s0.1).max(s1.0).max(s1.1),
            );
            for &(a, b) in &edges {
                let (elo, ehi) = (
                    x0[a].min(x0[b]).min(x1[a]).min(x1[b]),
                    x0[a].max(x0[b]).max(x1[a]).max(x1[b]),
                );
                if elo.cmpgt(hi).any() || ehi.cmplt(lo).any() {
                    continue;
                }
                if crosses((x0[a], x0[b]), (x1[a], x1[b]), *s0, *s1) {
                    crossed = Some(format!("frame {f}: edge ({a}, {b}) crossed {}", LINKS[k]));
                    break 'links;
                }
            }
        }
        if let Some(what) = crossed {
            out.crossed_frames += 1;
            out.first.get_or_insert(what);
        }
        let s = 1.0 + sim.cloth.max_edge_stretch();
        if std::env::var_os("FAST_ROBOT_TRACE").is_some() {
            eprintln!(
                "t {:.3} stretch {s:.3} speed {:.2} contacts {} features {} splits {} refused {} subdiv {} pen {:.1} mm",
                sim.time(),
                m.max_speed,
                m.contacts,
                sim.collision().map_or(0, |c| c.feature_contacts().len()),
                m.contact_splits,
                m.contact_splits_refused,
                m.subdivisions,
                m.deepest_penetration * 1e3
            );
        }
        if s > out.max_stretch {
            (out.max_stretch, out.max_stretch_at) = (s, sim.time());
        }
    }
    out
}

/// At the joint-velocity limits, with the towel's friction on the arm and without: no link
/// passes through the towel, and without friction no edge exceeds the impact stretch bound plus
/// 10 %, `1 + 2 v / c + M g / k` (the fingertips at `v` = 2.0 rad/s x 0.75 m + 3.0 rad/s x 0.1 m,
/// the factor 2 for the front reflected at the rail). With friction 0.3 the rising arm drags the
/// towel up against its rail (a capstan, not an impact; reported, not judged). Without friction
/// the largest edge comes close to the bound, made by the collision pass; the run is chaotic,
/// and neighbouring runs (shoulder speed, thickness) scatter below it. A pass that jumps a
/// vertex over a third of its spacing splits the substep (`sim/fast.rs`, `jumped`), which keeps
/// such jumps from stretching the towel past the bound.
///
/// Before the edge-edge contact normal of a vertex against a segment was its separation, this
/// diverged at t = 0.59 s: the towel draped over the forearm's axis at one vertex, its two
/// column edges there got opposite plane normals, and the feature passes pushed the vertex
/// 7.6 cm within a substep however short (3.9x rest, then 1060 m/s).
#[test]
fn an_arm_at_its_velocity_limits_lifts_a_hanging_towel_without_passing_through_it() {
    let (c, v) = ((1000.0f64 / 0.2).sqrt(), 2.0 * 0.75 + 3.0 * 0.1);
    let bound = 1.1 * (1.0 + 2.0 * v / c + 0.2 * 0.5 * 0.7 * 9.81 / 1000.0);
    for friction in [0.3, 0.0] {
        let o = run(&scene(2.0, 3.0, 0.004, friction));
        eprintln!("friction {friction}: {o:?}");
        assert!(o.contacts > 0, "the arm never touched the towel");
        assert_eq!(o.crossed_frames, 0, "{:?}", o.first);
        if friction == 0.0 {
            assert!(
                o.max_stretch <= bound,
                "stretch {:.3} at t = {:.3} s, bound {bound:.3}",
                o.max_stretch,
                o.max_stretch_at
            );
        }
    }
}

/// The same with self-collision on (the towel folds over the arm onto itself): no link passes
/// through it either.
#[test]
fn with_self_collision_the_arm_still_does_not_pass_through_the_towel() {
    let mut s = scene(2.0, 3.0, 0.004, 0.3);
    s.collision.self_collision = true;
    let o = run(&s);
    eprintln!("self-collision: {o:?}");
    assert!(o.contacts > 0, "the arm never touched the towel");
    assert_eq!(o.crossed_frames, 0, "{:?}", o.first);
}

/// The check sees a crossing where there is one: a rod sweeping through an edge, and not one
/// sweeping past its end or parallel to it.
#[test]
fn the_crossing_check_sees_a_segment_sweep_through_an_edge() {
    let edge = (Vec3::new(-0.01, 0.0, 0.0), Vec3::new(0.01, 0.0, 0.0));
    let rod = |y: f64, x: f64| (Vec3::new(x, y, -0.1), Vec3::new(x, y, 0.1));
    assert!(crosses(edge, edge, rod(-0.05, 0.0), rod(0.05, 0.0)));
    assert!(crosses(edge, edge, rod(-0.05, 0.009), rod(0.05, 0.009)));
    assert!(!crosses(edge, edge, rod(-0.05, 0.011), rod(0.05, 0.011)));
    assert!(!crosses(edge, edge, rod(-0.05, 0.0), rod(-0.001, 0.0)));
    // The edge moving through a fixed rod is the same crossing.
    let moved = (edge.0 + Vec3::Y * 0.1, edge.1 + Vec3::Y * 0.1);
    assert!(crosses(edge, moved, rod(0.05, 0.0), rod(0.05, 0.0)));
}
