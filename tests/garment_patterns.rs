//! Pattern validation, meshing, placement and welding on small hand-made patterns.

use drape::cloth::topology::Stencil;
use drape::garment::mesh::min_angle_deg;
use drape::garment::pattern::validate;
use drape::garment::placement::place;
use drape::garment::sew::assemble;
use drape::garment::weld::weld;
use drape::garment::{mesh_garment, GarmentError, GarmentSpec, PlacementSpec, WrapSpec};
use drape::scene::{Scene, SceneError};
use drape::Vec3;
use glam::DVec2;

/// Two 0.2 x 0.3 panels side by side in the plane, sewn along their facing edges.
fn two_panels() -> GarmentSpec {
    let yaml = r#"
name: test
edge_length: 0.04
panels:
  - name: left
    outline: [[0, 0], [0.2, 0], [0.2, 0.3], [0, 0.3]]
    grain: 30
    placement: { pose: { xyz: [0, 0, 0] } }
  - name: right
    outline: [[0, 0], [0.2, 0], [0.2, 0.3], [0, 0.3]]
    placement: { pose: { xyz: [0.25, 0, 0] } }
seams:
  - { name: middle, a: { panel: left, from: 1, to: 2 }, b: { panel: right, from: 3, to: 0 }, reversed: true }
"#;
    serde_yaml_ng::from_str(yaml).unwrap()
}

#[test]
fn self_intersecting_outline_is_rejected_naming_the_panel() {
    let mut g = two_panels();
    g.panels[1].outline = vec![[0.0, 0.0], [0.2, 0.3], [0.2, 0.0], [0.0, 0.3]];
    let e = validate(&g).unwrap_err();
    assert!(
        matches!(&e, GarmentError::SelfIntersecting { panel, .. } if panel == "right"),
        "{e}"
    );
    assert!(e.to_string().contains("'right'"));
}

#[test]
fn seam_sides_of_very_different_length_are_rejected_naming_the_seam() {
    let mut g = two_panels();
    g.panels[1].outline = vec![[0.0, 0.0], [0.2, 0.0], [0.2, 0.1], [0.0, 0.1]];
    let e = validate(&g).unwrap_err();
    assert!(
        matches!(&e, GarmentError::SeamLength { seam, .. } if seam == "middle"),
        "{e}"
    );
    // 10% apart is within tolerance.
    g.panels[1].outline = vec![[0.0, 0.0], [0.2, 0.0], [0.2, 0.27], [0.0, 0.27]];
    validate(&g).unwrap();
}

#[test]
fn seam_naming_a_missing_panel_is_rejected() {
    let mut g = two_panels();
    g.seams[0].b.panel = "sleeve".into();
    let e = validate(&g).unwrap_err();
    assert!(
        matches!(&e, GarmentError::MissingPanel { seam, panel } if seam == "middle" && panel == "sleeve"),
        "{e}"
    );
    g.seams[0].b.panel = "right".into();
    g.seams[0].b.to = 7;
    assert!(matches!(
        validate(&g),
        Err(GarmentError::SeamIndex { index: 7, .. })
    ));
}

#[test]
fn scene_file_reports_garment_errors_with_their_key() {
    let text = r#"
effects: [stretch]
garments:
  - name: shirt
    panels:
      - name: front
        outline: [[0, 0], [1, 1], [1, 0], [0, 1]]
"#;
    let e = Scene::from_yaml(text, "bad.yaml").unwrap_err().to_string();
    assert!(
        e.starts_with("bad.yaml: garments[0].panels[0].outline: ") && e.contains("'front'"),
        "{e}"
    );
    // A seam's side is named down to the value at fault.
    let mut g = two_panels();
    g.seams[0].b.to = 7;
    let scene = format!(
        "effects: [stretch]\ngarments:\n{}",
        indent(&serde_yaml_ng::to_string(&vec![g]).unwrap())
    );
    let e = Scene::from_yaml(&scene, "bad.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("bad.yaml: garments[0].seams[0].b.to: "),
        "{e}"
    );
}

#[test]
fn meshes_keep_grain_rest_lengths_and_angles() {
    let g = two_panels();
    let mesh = mesh_garment(&g).unwrap();
    let left = &mesh.panels[0];
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    for (p, uv) in left.points.iter().zip(&left.uv) {
        // u is the coordinate along the 30 deg warp, v across it.
        assert!((uv.x - (c * p.x + s * p.y)).abs() < 1e-12);
        assert!((uv.y - (-s * p.x + c * p.y)).abs() < 1e-12);
    }
    // An L-shaped outline (a reflex corner) also meshes above 20 deg.
    let mut l = g.clone();
    l.seams.clear();
    l.panels[0].outline = vec![
        [0.0, 0.0],
        [0.3, 0.0],
        [0.3, 0.1],
        [0.1, 0.1],
        [0.1, 0.3],
        [0.0, 0.3],
    ];
    let m = mesh_garment(&l).unwrap();
    for p in &m.panels {
        for t in &p.triangles {
            assert!(min_angle_deg(t.map(|i| p.points[i as usize])) > 20.0);
        }
        // Every point lies inside the outline's bounding box (nothing outside the cut).
        assert!(p
            .points
            .iter()
            .all(|q| q.x > -1e-12 && q.y > -1e-12 && q.x < 0.3 + 1e-12));
    }
    let area: f64 = m.panels[0]
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.panels[0].points[i as usize]);
            0.5 * (b - a).perp_dot(c - a)
        })
        .sum();
    assert!((area - 0.05).abs() < 1e-12, "area {area}");
}

#[test]
fn seam_sides_are_resampled_to_equal_counts_and_paired_by_orientation() {
    let mut g = two_panels();
    // Right panel 10% shorter: same vertex count on both sides anyway.
    g.panels[1].outline = vec![[0.0, 0.0], [0.2, 0.0], [0.2, 0.27], [0.0, 0.27]];
    let mesh = mesh_garment(&g).unwrap();
    let (a, b) = &mesh.seams[0];
    assert_eq!(a.vertices.len(), b.vertices.len());
    assert_eq!(a.vertices.len(), (0.3f64 / 0.04).ceil() as usize + 1);
    // reversed: a.from (left (0.2, 0)) meets b.to (right (0, 0)); a.to meets b.from.
    let pa = &mesh.panels[0].points;
    let pb = &mesh.panels[1].points;
    assert_eq!(pa[a.vertices[0] as usize], DVec2::new(0.2, 0.0));
    assert_eq!(pb[b.vertices[0] as usize], DVec2::new(0.0, 0.0));
    assert_eq!(
        pb[*b.vertices.last().unwrap() as usize],
        DVec2::new(0.0, 0.27)
    );
}

#[test]
fn wrapping_is_an_isometry_onto_the_cylinder() {
    let r = 0.1;
    let p = PlacementSpec {
        wrap: Some(WrapSpec { radius: r }),
        ..Default::default()
    };
    let axis = Vec3::new(0.0, 0.0, -r);
    let n = 50;
    let mut arc = 0.0;
    let mut prev = place(&p, DVec2::new(0.0, 0.2));
    assert!((prev - Vec3::new(0.0, 0.2, 0.0)).length() < 1e-15);
    for k in 1..=n {
        let x = 0.3 * k as f64 / n as f64;
        let q = place(&p, DVec2::new(x, 0.2));
        let radial = Vec3::new(q.x - axis.x, 0.0, q.z - axis.z).length();
        assert!((radial - r).abs() < 1e-12);
        assert!((q.y - 0.2).abs() < 1e-15);
        arc += (q - prev).length();
        prev = q;
    }
    // Chords of 6 mm on a 10 cm radius: arc - chord sum = L h^2 / (24 r^2) ~ 5e-4 relative.
    assert!((arc - 0.3).abs() < 0.3 * 1e-3, "arc {arc}");
}

#[test]
fn weld_merges_pairs_and_bends_across_the_seam() {
    let g = two_panels();
    let (cloth, seams) = assemble(&g).unwrap();
    let pairs = seams[0].pairs.len();
    // Close the 5 cm gap as sewing would: move the right panel onto the left one's edge.
    let mut sewn = cloth.clone();
    let right = sewn.pieces[1].vertices();
    for i in right {
        sewn.x[i].x -= 0.05;
    }
    let w = weld(&sewn, &seams, "test", g.material);
    assert_eq!(w.cloth.len(), cloth.len() - pairs);
    // Rest lengths equal the flat distances (the sheet is flat and unstretched).
    for s in &w.topology.springs {
        let d = (w.cloth.x[s.i as usize] - w.cloth.x[s.j as usize]).length();
        assert!(
            (d - s.rest).abs() < 1e-9,
            "spring {}-{}: {d} vs {}",
            s.i,
            s.j,
            s.rest
        );
    }
    // Cross-seam stencils exist, vanish on the flat sheet and respond to a fold at the seam.
    let seam_vertices: std::collections::HashSet<u32> = w.seams[0].1.iter().copied().collect();
    let cross: Vec<&Stencil<3>> = w
        .topology
        .bending
        .iter()
        .filter(|s| seam_vertices.contains(&s.idx[1]) && !seam_vertices.contains(&s.idx[0]))
        .collect();
    assert!(
        cross.len() >= pairs - 2,
        "{} cross-seam stencils",
        cross.len()
    );
    let eval =
        |x: &[Vec3], s: &Stencil<3>| (0..3).map(|k| x[s.idx[k] as usize] * s.w[k]).sum::<Vec3>();
    // Flat sheet: no out-of-plane component (the stencils' neighbours are within 30 deg of
    // collinear, so like the panels' own free-mesh stencils they leave a small in-plane residue).
    for s in &cross {
        assert!(eval(&w.cloth.x, s).z.abs() < 1e-9);
    }
    let mut folded = w.cloth.x.clone();
    for p in folded.iter_mut() {
        if p.x > 0.2 + 1e-9 {
            p.z += p.x - 0.2;
        }
    }
    assert!(cross.iter().all(|s| eval(&folded, s).z.abs() > 1e-3));
}

#[test]
fn weld_keeps_mass_and_seam_springs_match_finite_differences() {
    use drape::effects::{Effect, State};
    use drape::garment::seam::SeamSprings;
    use drape::linalg::PatternBuilder;
    let g = two_panels();
    let (cloth, seams) = assemble(&g).unwrap();
    let w = weld(&cloth, &seams, "test", g.material);
    let before: f64 = cloth.mass.iter().sum();
    let after: f64 = w.cloth.mass.iter().sum();
    assert!((before - after).abs() < 1e-15 * before.max(1.0));
    // The flat panels' total mass is density x area (2 x 0.2 x 0.3 m^2).
    assert!((before - g.material.density * 0.12).abs() < 1e-12);

    // Seam springs halfway through closing: forces are minus the gradient of the spring energy
    // at frozen rest length, Jacobians match central differences of the forces.
    let pairs = seams[0].pairs.clone();
    let springs = SeamSprings::new(pairs.clone(), &cloth.x, 300.0, 0.0, 1.0);
    let n = cloth.len();
    let mut x = cloth.x.clone();
    for (k, p) in x.iter_mut().enumerate() {
        p.z += 0.01 * ((k as f64) * 0.7).sin();
    }
    let v = vec![Vec3::ZERO; n];
    let t = 0.5;
    let forces = |x: &[Vec3]| {
        let mut f = vec![Vec3::ZERO; n];
        springs.add_forces(&State { t, x, v: &v }, &mut f);
        f
    };
    let mut pb = PatternBuilder::new();
    springs.declare(&mut pb);
    let mut dfdx = pb.build(n);
    let mut dfdv = dfdx.clone();
    dfdx.clear();
    dfdv.clear();
    springs.add_jacobians(&State { t, x: &x, v: &v }, &mut dfdx, &mut dfdv);
    let h = 1e-6;
    for &(a, _) in pairs.iter().take(4) {
        for axis in 0..3 {
            let mut xp = x.clone();
            let mut xm = x.clone();
            xp[a as usize][axis] += h;
            xm[a as usize][axis] -= h;
            let (fp, fm) = (forces(&xp), forces(&xm));
            for j in 0..n {
                let fd = (fp[j] - fm[j]) / (2.0 * h);
                let (cols, blocks) = dfdx.row(j);
                let jac = cols
                    .iter()
                    .position(|&c| c == a)
                    .map(|k| blocks[k].col(axis))
                    .unwrap_or(Vec3::ZERO);
                // Stretched springs (the transverse term is not clamped): exact up to O(h^2).
                assert!(
                    (fd - jac).length() < 1e-4 * 300.0,
                    "row {j} col {a}.{axis}: {fd} vs {jac}"
                );
            }
        }
    }
}

#[test]
fn bad_material_and_schedule_values_are_rejected_by_key() {
    let mut g = two_panels();
    g.material.stretch = 0.0;
    let e = validate(&g).unwrap_err().to_string();
    assert!(
        e.contains("'test'") && e.contains("material.stretch"),
        "{e}"
    );
    let mut g = two_panels();
    g.sewing.max_time = g.sewing.close_time;
    assert!(validate(&g)
        .unwrap_err()
        .to_string()
        .contains("sewing.max_time"));
    let mut g = two_panels();
    g.edge_length = 1e-5;
    let e = validate(&g).unwrap_err().to_string();
    assert!(e.contains("'left'") && e.contains("vertices"), "{e}");
}

/// A garment's material is held to the same bounds as a grid cloth's, named by its key; a free
/// mesh has no shear springs, so `shear: 0` is not an error even where the effect is named.
#[test]
fn garment_materials_have_the_bounds_of_cloth_materials() {
    let scene = |edit: &dyn Fn(&mut GarmentSpec)| {
        let mut g = two_panels();
        edit(&mut g);
        format!(
            "effects: [stretch, shear, bending]\ngarments:\n{}",
            indent(&serde_yaml_ng::to_string(&vec![g]).unwrap())
        )
    };
    for (edit, key) in [
        (
            &(|g: &mut GarmentSpec| g.material.stretch = 1e300) as &dyn Fn(&mut GarmentSpec),
            "garments[0].material.stretch",
        ),
        (
            &|g: &mut GarmentSpec| g.material.density = 1e9,
            "garments[0].material.density",
        ),
        (
            &|g: &mut GarmentSpec| g.material.bend_warp = 1e30,
            "garments[0].material.bend_warp",
        ),
        (
            &|g: &mut GarmentSpec| g.material.friction = 1e6,
            "garments[0].material.friction",
        ),
        (
            &|g: &mut GarmentSpec| g.material.thickness = 5.0,
            "garments[0].material.thickness",
        ),
    ] {
        let e = Scene::from_yaml(&scene(edit), "bad.yaml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&format!("bad.yaml: {key}: ")), "{e}");
        assert!(e.contains("at most"), "{e}");
    }
    let shear_free = scene(&|g: &mut GarmentSpec| g.material.shear = 0.0);
    if let Err(e) = Scene::from_yaml(&shear_free, "ok.yaml") {
        assert!(!e.to_string().contains("material.shear"), "{e}");
    }
}

/// The two panels as a scene without a body: sewing in free space.
fn two_panel_scene(sewing: &str) -> String {
    let g = serde_yaml_ng::to_string(&two_panels()).unwrap();
    let g = g.replace("sewing:", "old_sewing:");
    let mut garment: serde_yaml_ng::Value = serde_yaml_ng::from_str(&g).unwrap();
    if let serde_yaml_ng::Value::Mapping(m) = &mut garment {
        m.remove("old_sewing");
        m.insert("sewing".into(), serde_yaml_ng::from_str(sewing).unwrap());
    }
    let garments = serde_yaml_ng::to_string(&vec![garment]).unwrap();
    format!("effects: [gravity, stretch, bending, damping]\nsolver: {{ integrator: implicit, dt: 0.01 }}\ngarments:\n{}", indent(&garments))
}

fn indent(s: &str) -> String {
    s.lines().map(|l| format!("  {l}\n")).collect()
}

#[test]
fn sewing_in_free_space_welds_and_a_weak_seam_fails_naming_it() {
    let ok =
        two_panel_scene("{ stiffness: 2000, close_time: 0.3, tolerance: 0.001, max_time: 2.0 }");
    let scene = Scene::from_yaml(&ok, "two.yaml").unwrap_or_else(|e| panic!("{e}\n{ok}"));
    let sim = scene.build().unwrap();
    let (cloth, seams) = assemble(&scene.garments[0]).unwrap();
    assert_eq!(sim.cloth.len(), cloth.len() - seams[0].pairs.len());
    assert_eq!(sim.time(), 0.0);
    // Gravity is on again after the weld.
    assert!(sim.effects().names().contains(&"gravity"));

    let weak =
        two_panel_scene("{ stiffness: 0.001, close_time: 0.1, tolerance: 0.001, max_time: 0.3 }");
    let scene = Scene::from_yaml(&weak, "weak.yaml").unwrap();
    let e = scene.build().err().expect("sewing fails");
    let SceneError::Garment { source, .. } = &e else {
        panic!("not a garment error: {e:?}");
    };
    let GarmentError::SeamOpen {
        garment,
        seam,
        gap,
        tolerance,
        ..
    } = &**source
    else {
        panic!("not an open seam: {source:?}");
    };
    assert_eq!((garment.as_str(), seam.as_str()), ("test", "middle"));
    assert!(gap > tolerance);
    let mut chain = e.to_string();
    let mut cause = std::error::Error::source(&e);
    while let Some(c) = cause {
        chain += &format!(": {c}");
        cause = c.source();
    }
    assert!(
        chain.contains("garments") && chain.contains("seam 'middle'") && chain.contains("gap"),
        "{chain}"
    );
    // The message starts with the scene's file, then the seam's key.
    assert!(
        chain.starts_with("weak.yaml: garments[0].seams[0]: "),
        "{chain}"
    );
}

#[test]
fn seam_gaps_print_in_a_unit_that_shows_their_digits() {
    let open = |gap: f64, tolerance: f64| {
        GarmentError::SeamOpen {
            garment: "g".into(),
            seam: "s".into(),
            gap,
            time: 4.0,
            tolerance,
        }
        .to_string()
    };
    let e = open(2.5e-6, 1e-6);
    assert!(
        e.contains("2.500 µm gap") && e.contains("tolerance 1.000 µm"),
        "{e}"
    );
    let e = open(3e-9, 1.5e-10);
    assert!(
        e.contains("3.000e-9 m gap") && e.contains("tolerance 1.500e-10 m"),
        "{e}"
    );
    let e = open(0.0123, 0.001);
    assert!(
        e.contains("12.300 mm gap") && e.contains("tolerance 1.000 mm"),
        "{e}"
    );
    let e = GarmentError::SeamLength {
        seam: "s".into(),
        a: 2e-5,
        b: 1e-5,
        max_mismatch: 0.2,
    }
    .to_string();
    assert!(e.contains("20.000 µm and 10.000 µm long"), "{e}");
}
