//! Garments sewn and welded with self-collision on: the seam neighbourhoods are exempt from
//! self-contact while sewing, so every seam closes below its tolerance as without
//! self-collision, the welded garment starts free of self-intersections and stays so while the
//! robot moves. Without the exemption, self-contact holds the seam's two edges apart and the
//! build fails with a seam still open.

#[path = "common/self_check.rs"]
mod self_check;

use drape::garment::dress;
use drape::garment::sew::SewReport;
use drape::scene::Scene;
use drape::sim::Simulation;
use self_check::{bundled, intersecting_pairs};

/// The scene built bare, then dressed, with the sewing reports.
fn dressed(scene: &Scene) -> (Simulation, Vec<SewReport>) {
    let mut bare = scene.clone();
    bare.garments.clear();
    let (mut sim, mut driver) = bare.build_with_robot().unwrap();
    let reports = dress(
        &mut sim,
        &scene.garments,
        &scene.effect_plan(),
        driver.as_mut(),
    )
    .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
    (sim, reports)
}

/// Sews `file` with and without self-collision: same tolerance met, the same welded vertex
/// count, a sewing time within 10% (the exemption makes sewing the same problem), and no
/// self-intersection when welded.
fn sews_with_self_collision(file: &str, welded: Option<usize>) {
    let on = bundled(file, 1);
    let mut off = on.clone();
    off.collision.self_collision = false;
    let (sim, r_on) = dressed(&on);
    let (_, r_off) = dressed(&off);
    for (a, b) in r_on.iter().zip(&r_off) {
        eprintln!(
            "{file} {}: self on: {:.3} s, gap {:.4} mm, {} vertices; off: {:.3} s, gap {:.4} mm",
            a.garment,
            a.time,
            a.max_gap * 1e3,
            a.welded_vertices,
            b.time,
            b.max_gap * 1e3
        );
        let tol = on.garments[0].sewing.tolerance;
        assert!(a.max_gap < tol, "{}: gap {} m", a.garment, a.max_gap);
        if let Some(w) = welded {
            assert_eq!(a.welded_vertices, w);
        }
        assert_eq!(a.welded_vertices, b.welded_vertices);
        assert!(
            (a.time - b.time).abs() <= 0.1 * b.time,
            "sewing took {} s with self-collision, {} s without",
            a.time,
            b.time
        );
    }
    assert_eq!(intersecting_pairs(&sim.cloth.x, &sim.cloth.triangles), 0);
}

#[test]
fn shirt_sews_and_welds_with_self_collision() {
    sews_with_self_collision("shirt.yaml", Some(976));
}

#[test]
fn sleeve_sews_and_welds_with_self_collision() {
    sews_with_self_collision("sleeve.yaml", None);
}
