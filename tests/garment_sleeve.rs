//! config/sleeve.yaml: a tube sewn from one panel (a seam joining the panel to itself) around
//! the raised left upper arm, which then moves: the sleeve closes, welds into a tube, its
//! shoulder end follows the arm link and the rest stays around the arm.

use drape::garment::sew::body_penetration;
use drape::garment::{dress, GarmentError};
use drape::scene::{Scene, SceneError};
use drape::Vec3;
use std::path::Path;

#[test]
fn sleeve_sews_into_a_tube_and_stays_on_the_moving_arm() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sleeve.yaml");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut bare = scene.clone();
    bare.garments.clear();
    let (mut sim, driver) = bare.build_with_robot().unwrap();
    let mut driver = driver.unwrap();
    let report = dress(
        &mut sim,
        &scene.garments,
        &scene.effect_plan(),
        Some(&mut driver),
    )
    .unwrap()
    .remove(0);
    assert!(report.max_gap < 1e-3, "gap {}", report.max_gap);
    assert_eq!(
        report.welded_vertices,
        report.panel_vertices - report.seam_pairs
    );
    // A tube: the only open edges are the two end rings.
    let mut edges = std::collections::HashMap::new();
    for t in &sim.cloth.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let open = edges.values().filter(|&&n| n == 1).count();
    let ring = (0.38f64 / 0.03).ceil() as usize;
    assert_eq!(open, 2 * ring, "open edges");
    let thickness = scene.garments[0].material.thickness;
    let arm = driver.robot().link_index("left_upper_arm").unwrap();
    // The shoulder-end ring is attached to the arm and keeps its offset in the arm's frame.
    let held: Vec<(usize, Vec3)> = sim
        .cloth
        .kinematic
        .iter()
        .map(|(i, _)| {
            let i = *i as usize;
            (
                i,
                driver.link_poses()[arm].inverse_transform_point(sim.cloth.x[i]),
            )
        })
        .collect();
    assert!(held.len() >= ring / 2, "{} attached vertices", held.len());
    let steps = (3.5 / sim.settings.dt).round() as usize;
    for _ in 0..steps {
        let next = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, next);
        let m = sim.step().unwrap();
        assert!(m.max_speed < 5.0, "t {}: speed {}", m.time, m.max_speed);
        // Still around the arm: the centroid stays within 10 cm of the arm (upper arm or forearm).
        let pose = driver.link_poses()[arm];
        let c = sim.cloth.x.iter().copied().sum::<Vec3>() / sim.cloth.len() as f64;
        let local = pose.inverse_transform_point(c);
        // The elbow stays straight: upper arm and forearm make one 0.55 m rod along -z.
        let along = local.z.clamp(-0.55, 0.0);
        let off = (local - Vec3::new(0.0, 0.0, along)).length();
        assert!(
            off < 0.1,
            "t {}: sleeve centroid {off} m from the arm",
            m.time
        );
    }
    assert!(body_penetration(&sim) <= 0.1 * thickness);
    let pose = driver.link_poses()[arm];
    for (i, local) in held {
        assert!((pose.inverse_transform_point(sim.cloth.x[i]) - local).length() < 1e-9);
    }
}

#[test]
fn attachment_to_a_missing_link_is_a_clear_error() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sleeve.yaml");
    let mut scene = Scene::load(&path).unwrap();
    scene.garments[0].attach[0].link = "tentacle".into();
    let e = scene.build().err().expect("build fails");
    // The scene error names the key; its source names the garment, the attachment and the link.
    let head = format!("{}: garments[0].attach[0].link", path.display());
    assert!(e.to_string().starts_with(&head), "{e}");
    let SceneError::Garment { source, .. } = &e else {
        panic!("not a garment error: {e}");
    };
    assert!(
        matches!(&**source, GarmentError::AttachLink { garment, index: 0, link }
            if garment == "sleeve" && link == "tentacle"),
        "{source:?}"
    );
    let mut chain = e.to_string();
    let mut cause = std::error::Error::source(&e);
    while let Some(c) = cause {
        chain += &format!(": {c}");
        cause = c.source();
    }
    assert!(
        chain.contains("garments")
            && chain.contains("sleeve")
            && chain.contains("attach[0]")
            && chain.contains("'tentacle'"),
        "{chain}"
    );
}

#[test]
fn shirt_and_sleeve_are_sewn_together_as_two_garments() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let sleeve = Scene::load(&dir.join("sleeve.yaml")).unwrap();
    let mut scene = Scene::load(&dir.join("shirt.yaml")).unwrap();
    scene.garments.push(sleeve.garments[0].clone());
    scene.robot = sleeve.robot.clone();
    let mut bare = scene.clone();
    bare.garments.clear();
    let (mut sim, driver) = bare.build_with_robot().unwrap();
    let mut driver = driver.unwrap();
    let reports = dress(
        &mut sim,
        &scene.garments,
        &scene.effect_plan(),
        Some(&mut driver),
    )
    .unwrap();
    assert_eq!(reports.len(), 2);
    let total: usize = reports.iter().map(|r| r.welded_vertices).sum();
    assert_eq!(sim.cloth.len(), total);
    assert_eq!(sim.cloth.pieces.len(), 2);
    for (r, p) in reports.iter().zip(&sim.cloth.pieces) {
        assert!(r.max_gap < 1e-3, "{}: {}", r.garment, r.max_gap);
        assert_eq!(p.name, r.garment);
        assert_eq!(r.welded_vertices, r.panel_vertices - r.seam_pairs);
    }
    // Only the sleeve's vertices are attached.
    let sleeve_range = sim.cloth.pieces[1].vertices();
    assert!(!sim.cloth.kinematic.is_empty());
    assert!(sim
        .cloth
        .kinematic
        .iter()
        .all(|(i, _)| sleeve_range.contains(&(*i as usize))));
    for _ in 0..30 {
        let next = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, next);
        sim.step().unwrap();
    }
}
