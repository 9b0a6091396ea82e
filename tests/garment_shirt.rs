//! The garment pipeline on config/shirt.yaml: sewing closes every seam, the weld gives one
//! manifold garment with the expected vertex count, no self-intersection or body penetration,
//! and the shirt then hangs on the torso and follows it when the robot moves.

use drape::garment::mesh::min_angle_deg;
use drape::garment::sew::{assemble, body_penetration, self_intersections, SewReport};
use drape::garment::{dress, mesh_garment, MIN_ANGLE_DEG};
use drape::robot::RobotDriver;
use drape::scene::Scene;
use drape::sim::Simulation;
use drape::{Pose, Vec3};
use std::collections::HashMap;
use std::path::Path;

fn shirt() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/shirt.yaml");
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The shirt scene's simulation with the robot, dressed, and the sewing report.
fn dressed(scene: &Scene) -> (Simulation, RobotDriver, SewReport) {
    let mut bare = scene.clone();
    bare.garments.clear();
    let (mut sim, mut driver) = bare.build_with_robot().unwrap();
    let mut reports = dress(
        &mut sim,
        &scene.garments,
        &scene.effect_plan(),
        driver.as_mut(),
    )
    .unwrap();
    (sim, driver.unwrap(), reports.remove(0))
}

fn edge_counts(triangles: &[[u32; 3]]) -> HashMap<(u32, u32), usize> {
    let mut m = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *m.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    m
}

fn components(n: usize, triangles: &[[u32; 3]]) -> usize {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for t in triangles {
        for k in 1..3 {
            let (a, b) = (
                find(&mut parent, t[0] as usize),
                find(&mut parent, t[k] as usize),
            );
            parent[a] = b;
        }
    }
    (0..n).filter(|&i| find(&mut parent, i) == i).count()
}

fn centroid(x: &[Vec3]) -> Vec3 {
    x.iter().copied().sum::<Vec3>() / x.len() as f64
}

#[test]
fn shirt_panels_mesh_above_twenty_degrees_along_the_grain() {
    let scene = shirt();
    let g = &scene.garments[0];
    let mesh = mesh_garment(g).unwrap();
    for p in &mesh.panels {
        let worst = p
            .triangles
            .iter()
            .map(|t| min_angle_deg(t.map(|i| p.points[i as usize])))
            .fold(180.0, f64::min);
        assert!(worst > MIN_ANGLE_DEG, "panel {}: {worst} deg", p.name);
        // Mean edge length near the target (refinement halves areas above the bound).
        let edges = edge_counts(&p.triangles);
        let mean = edges
            .keys()
            .map(|&(a, b)| (p.points[a as usize] - p.points[b as usize]).length())
            .sum::<f64>()
            / edges.len() as f64;
        assert!(
            mean > 0.5 * g.edge_length && mean < 1.1 * g.edge_length,
            "panel {}: mean edge {mean}",
            p.name
        );
        // Grain 90 deg: the warp (u) runs along pattern y, the weft (v) along -x.
        for (q, uv) in p.points.iter().zip(&p.uv) {
            assert!((uv.x - q.y).abs() < 1e-12 && (uv.y + q.x).abs() < 1e-12);
        }
    }
}

#[test]
fn shirt_sewing_closes_seams_into_one_manifold_garment() {
    let scene = shirt();
    let g = &scene.garments[0];
    let (panels, seams) = assemble(g).unwrap();
    let pairs: usize = seams.iter().map(|s| s.pairs.len()).sum();
    let (sim, _, report) = dressed(&scene);
    let c = &sim.cloth;
    // Every seam gap below 1 mm when welded.
    assert_eq!(report.seam_gaps.len(), 4);
    for (name, gap) in &report.seam_gaps {
        assert!(*gap < 1e-3, "seam {name}: gap {gap}");
    }
    // One vertex less per seam pair (no seam vertex is shared by two seams in this pattern).
    assert_eq!(report.panel_vertices, panels.len());
    assert_eq!(c.len(), panels.len() - pairs);
    assert_eq!(report.welded_vertices, c.len());
    // Manifold: seam edges shared by exactly two triangles, no edge by more; one component.
    let edges = edge_counts(&c.triangles);
    assert_eq!(report.seam_edges.len(), pairs - seams.len());
    for &(a, b) in &report.seam_edges {
        assert_eq!(
            edges.get(&(a.min(b), a.max(b))),
            Some(&2),
            "seam edge {a}-{b}"
        );
    }
    assert!(edges.values().all(|&n| n <= 2));
    assert_eq!(components(c.len(), &c.triangles), 1);
    // Consistent orientation across seams: each shared edge is walked both ways.
    let mut directed = std::collections::HashSet::new();
    for t in &c.triangles {
        for k in 0..3 {
            assert!(
                directed.insert((t[k], t[(k + 1) % 3])),
                "edge walked twice the same way"
            );
        }
    }
    assert_eq!(self_intersections(&c.x, &c.triangles), 0);
    let thickness = g.material.thickness;
    let pen = body_penetration(&sim);
    assert!(pen <= 0.1 * thickness, "penetration {pen} m");
}

#[test]
fn shirt_hangs_five_seconds_then_follows_the_robot() {
    let scene = shirt();
    let thickness = scene.garments[0].material.thickness;
    let (mut sim, mut driver, _) = dressed(&scene);
    let c0 = centroid(&sim.cloth.x);
    let steps = (5.0 / sim.settings.dt).round() as usize;
    for _ in 0..steps {
        let next = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, next);
        let m = sim.step().unwrap();
        assert!(m.max_speed < 3.0, "t {}: speed {}", m.time, m.max_speed);
    }
    let c1 = centroid(&sim.cloth.x);
    let top = sim.cloth.x.iter().map(|p| p.z).fold(f64::MIN, f64::max);
    // Still on the shoulders: the straps rest on the torso top (z = 0.7), the shirt sank only
    // by the slack of the straps' tent above it.
    assert!(top > 0.7 && top < 0.8, "top {top}");
    assert!((c1 - c0).length() < 0.1, "centroid moved {:?}", c1 - c0);
    assert!(body_penetration(&sim) <= 0.1 * thickness);

    // The whole robot (every link obstacle) moves 10 cm forward and 5 cm up over 1 s, then holds.
    let start: Vec<Pose> = sim
        .collision()
        .unwrap()
        .obstacles()
        .iter()
        .map(|o| o.pose)
        .collect();
    let shift = Vec3::new(0.1, 0.0, 0.05);
    let n = (1.5 / sim.settings.dt).round() as usize;
    for k in 1..=n {
        let s = (k as f64 * sim.settings.dt).min(1.0);
        for (i, p) in start.iter().enumerate() {
            let mut q = *p;
            q.translation += shift * s;
            assert!(sim.set_obstacle_target(i, q));
        }
        sim.step().unwrap();
    }
    let c2 = centroid(&sim.cloth.x);
    let moved = c2 - c1;
    assert!(
        (moved - shift).length() < 0.03,
        "shirt moved {moved:?}, robot {shift:?}"
    );
    assert!(body_penetration(&sim) <= 0.1 * thickness);
}
