//! Judging a full simulation with self-collision on, independently of drape's own metric: an
//! exact count of intersecting non-adjacent triangle pairs (a uniform grid over triangle boxes,
//! then segment-triangle crossings written here, not drape's tri-tri test), the largest edge
//! stretch against rest, and kinematic vertices on their targets. Shared by
//! `tests/self_collision_scenes.rs` and `benches/self_collision.rs`.

#![allow(dead_code)]

use drape::cloth::Kinematic;
use drape::scene::Scene;
use drape::sim::Simulation;
use drape::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// Every bundled scene file (config/*.yaml except the node's parameters), for the test that runs
/// each with self-collision on and the bench that times each.
pub const SCENES: &[&str] = &[
    "chair.yaml",
    "crumple.yaml",
    "flag.yaml",
    "hanging.yaml",
    "robot_cape.yaml",
    "robot_drape_arm.yaml",
    "robot_pick_towel.yaml",
    "robot_pinch_towel.yaml",
    "robot_towel.yaml",
    "shirt.yaml",
    "sleeve.yaml",
    "sphere_drape.yaml",
    "table.yaml",
    "three_corner_normal.yaml",
    "three_corner_soft_bending.yaml",
    "three_corner_soft_stretch.yaml",
    "three_corner_soft_warp.yaml",
];

/// A bundled scene with `self_collision: true` added, its grid cloths' resolution and its
/// garments' edge length scaled by `scale` (1: its own resolution, 2: twice as fine).
pub fn bundled(name: &str, scale: usize) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(name);
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    scene.collision.self_collision = true;
    for c in &mut scene.cloths {
        c.grid.resolution = c.grid.resolution.map(|r| (r - 1) * scale + 1);
    }
    for g in &mut scene.garments {
        g.edge_length /= scale as f64;
    }
    scene
}

/// `true` when segment `p q` crosses triangle `t` (Moller-Trumbore with the segment parameter
/// in [0, 1]); parallel and coplanar segments do not count (measure zero for cloth in motion).
/// Parallel is relative: a cloth lying flat on a plane has edges parallel to its far triangles to
/// round-off (chair at 2x: determinant 2e-22, 5e-17 of its scale), where the barycentrics are
/// noise and counted two triangles 2 cm apart as crossing.
fn segment_crosses(p: Vec3, q: Vec3, t: [Vec3; 3]) -> bool {
    let d = q - p;
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let h = d.cross(e2);
    let a = e1.dot(h);
    if a.is_nan() || a.abs() <= 1e-12 * d.length() * e1.length() * e2.length() {
        return false;
    }
    let f = 1.0 / a;
    let s = p - t[0];
    let u = f * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(e1);
    let v = f * d.dot(qv);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let w = f * e2.dot(qv);
    (0.0..=1.0).contains(&w)
}

/// Two triangles that share no vertex intersect exactly when an edge of one crosses the other.
fn tri_tri(a: [Vec3; 3], b: [Vec3; 3]) -> bool {
    (0..3).any(|k| segment_crosses(a[k], a[(k + 1) % 3], b))
        || (0..3).any(|k| segment_crosses(b[k], b[(k + 1) % 3], a))
}

/// Exact number of intersecting triangle pairs that share no vertex, at positions `x`.
pub fn intersecting_pairs(x: &[Vec3], tris: &[[u32; 3]]) -> usize {
    intersecting_pair_list(x, tris).len()
}

/// The intersecting triangle pairs that share no vertex (triangle indices), at positions `x`.
pub fn intersecting_pair_list(x: &[Vec3], tris: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    if tris.is_empty() {
        return out;
    }
    let boxes: Vec<(Vec3, Vec3)> = tris
        .iter()
        .map(|t| {
            let p = t.map(|i| x[i as usize]);
            (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
        })
        .collect();
    // Cell: twice the mean box diagonal, so a triangle spans a few cells.
    let mean = boxes.iter().map(|b| (b.1 - b.0).length()).sum::<f64>() / boxes.len() as f64;
    let cell = (2.0 * mean).max(1e-6);
    let key = |p: Vec3| {
        let c = (p / cell).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    };
    let mut grid: HashMap<(i64, i64, i64), Vec<u32>> = HashMap::new();
    for (k, b) in boxes.iter().enumerate() {
        let (lo, hi) = (key(b.0), key(b.1));
        for i in lo.0..=hi.0 {
            for j in lo.1..=hi.1 {
                for l in lo.2..=hi.2 {
                    grid.entry((i, j, l)).or_default().push(k as u32);
                }
            }
        }
    }
    for (cell_key, members) in &grid {
        for (ai, &a) in members.iter().enumerate() {
            for &b in &members[ai + 1..] {
                let (ba, bb) = (boxes[a as usize], boxes[b as usize]);
                if ba.0.cmpgt(bb.1).any() || bb.0.cmpgt(ba.1).any() {
                    continue;
                }
                // Count a pair once: in the cell holding the low corner of the boxes' overlap.
                if key(ba.0.max(bb.0)) != *cell_key {
                    continue;
                }
                let (ta, tb) = (tris[a as usize], tris[b as usize]);
                if ta.iter().any(|v| tb.contains(v)) {
                    continue;
                }
                if tri_tri(ta.map(|i| x[i as usize]), tb.map(|i| x[i as usize])) {
                    out.push((a, b));
                }
            }
        }
    }
    out
}

/// The cloth's unique edges with their rest lengths: from the rest (u, v) coordinates for grid
/// cloths, from the built state for garments (welded at rest; a seam vertex keeps one panel's
/// (u, v), so (u, v) distances across a seam are not rest lengths).
pub fn rest_edges(sim: &Simulation, garment: bool) -> Vec<(u32, u32, f64)> {
    let c = &sim.cloth;
    let mut e: Vec<(u32, u32)> = c
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.sort_unstable();
    e.dedup();
    e.into_iter()
        .map(|(a, b)| {
            let rest = if garment {
                (c.x[a as usize] - c.x[b as usize]).length()
            } else {
                (c.uv[a as usize] - c.uv[b as usize]).length()
            };
            (a, b, rest)
        })
        .collect()
}

/// Largest edge length over rest, and the edge.
pub fn max_stretch(x: &[Vec3], edges: &[(u32, u32, f64)]) -> (f64, (u32, u32)) {
    edges
        .iter()
        .filter(|e| e.2 > 0.0)
        .map(|&(a, b, r)| ((x[a as usize] - x[b as usize]).length() / r, (a, b)))
        .fold((0.0, (0, 0)), |m, s| if s.0 > m.0 { s } else { m })
}

/// Largest edge length over rest among edges with a free end.
pub fn free_stretch(sim: &Simulation, edges: &[(u32, u32, f64)]) -> f64 {
    let mut kinematic = vec![false; sim.cloth.x.len()];
    for (i, _) in &sim.cloth.kinematic {
        kinematic[*i as usize] = true;
    }
    let free: Vec<_> = edges
        .iter()
        .filter(|e| !(kinematic[e.0 as usize] && kinematic[e.1 as usize]))
        .copied()
        .collect();
    max_stretch(&sim.cloth.x, &free).0
}

/// Largest distance of a pinned or attached vertex from its target (m).
pub fn attached_drift(sim: &Simulation) -> f64 {
    sim.cloth
        .kinematic
        .iter()
        .map(|(i, k)| {
            let target = match *k {
                Kinematic::Pinned(p) => p,
                Kinematic::Attached { frame, local } => {
                    sim.frames.pose(frame).transform_point(local)
                }
            };
            (sim.cloth.x[*i as usize] - target).length()
        })
        .fold(0.0, f64::max)
}

/// What a run measured, worst over its frames.
#[derive(Debug, Clone, Default)]
pub struct Judged {
    pub frames: usize,
    pub simulated_s: f64,
    /// The guard's message when it stopped the run.
    pub diverged: Option<String>,
    /// Largest intersecting-pair count at a frame end, and the first frame with any.
    pub max_intersections: usize,
    pub first_intersecting_frame: Option<usize>,
    pub max_stretch: f64,
    pub max_stretch_at: f64,
    /// As `max_stretch`, over edges with at least one free end: an edge between two attached
    /// vertices is stretched by the robot's motion alone.
    pub max_free_stretch: f64,
    pub max_drift: f64,
    pub max_speed: f64,
    pub unresolved: usize,
    pub collision_s: f64,
    pub wall_s: f64,
    /// Self-contact counts summed over the run (largest zone: the largest seen).
    pub counts: drape::collide::SelfContactReport,
}

/// Runs `scene` for `seconds` (its robot driven), checking every frame end.
pub fn run(scene: &Scene, seconds: f64) -> Judged {
    let t0 = std::time::Instant::now();
    let (mut sim, mut driver) = scene
        .build_with_robot()
        .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
    let edges = rest_edges(&sim, !scene.garments.is_empty());
    let frames = (seconds / sim.settings.dt).round() as usize;
    let mut j = Judged::default();
    let trace = std::env::var("SELFCOL_TRACE").is_ok();
    for f in 0..frames {
        if let Some(d) = driver.as_mut() {
            let t = sim.time() + sim.settings.dt;
            d.advance(&mut sim, t);
        }
        match sim.step() {
            Ok(m) => {
                if trace {
                    let (s, e) = max_stretch(&sim.cloth.x, &edges);
                    eprintln!(
                        "t {:.3} stretch {s:.3} {e:?} speed {:.2} {:?}",
                        m.time, m.max_speed, m.self_contact
                    );
                }
                j.unresolved += m.unresolved_contacts;
                j.collision_s += m.collision_time_s;
                j.max_speed = j.max_speed.max(m.max_speed);
                j.counts.add(&m.self_contact);
            }
            Err(e) => {
                j.diverged = Some(e.to_string());
                break;
            }
        }
        j.frames = f + 1;
        let list = intersecting_pair_list(&sim.cloth.x, &sim.cloth.triangles);
        let n = list.len();
        if trace && n > 0 {
            // Which triangles, with how many kinematic corners each (a pair whose triangles are
            // both driven by the robot is the scene's own motion).
            let k = |t: u32| {
                sim.cloth.triangles[t as usize]
                    .iter()
                    .filter(|&&v| sim.cloth.kinematic_of(v).is_some())
                    .count()
            };
            let shown: Vec<_> = list
                .iter()
                .take(12)
                .map(|&(a, b)| {
                    (
                        sim.cloth.triangles[a as usize],
                        k(a),
                        sim.cloth.triangles[b as usize],
                        k(b),
                    )
                })
                .collect();
            eprintln!("  intersecting: {n} {shown:?}");
        }
        if n > 0 && j.first_intersecting_frame.is_none() {
            j.first_intersecting_frame = Some(f);
        }
        j.max_intersections = j.max_intersections.max(n);
        let (s, _) = max_stretch(&sim.cloth.x, &edges);
        if s > j.max_stretch {
            (j.max_stretch, j.max_stretch_at) = (s, sim.time());
        }
        j.max_free_stretch = j.max_free_stretch.max(free_stretch(&sim, &edges));
        j.max_drift = j.max_drift.max(attached_drift(&sim));
    }
    j.simulated_s = sim.time();
    j.wall_s = t0.elapsed().as_secs_f64();
    j
}
