//! `drape record config/shirt.yaml`: the bag carries the welded shirt from the first frame
//! on (dressing happens while the scene is built), with a constant vertex count equal to the
//! welded garment's, whose connectivity `garment_shirt` checks (one manifold component).
#![cfg(feature = "ros")]

use drape::ros::msg::PointCloud2;
use drape::ros::read_topic;
use drape::scene::Scene;
use std::path::Path;
use std::process::Command;

#[test]
fn recorded_shirt_is_the_welded_garment_in_every_frame() {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/shirt.yaml");
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("shirt.mcap");
    let status = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["record", "--quiet", "--duration", "0.2", "--scene"])
        .arg(&scene_path)
        .arg("--out")
        .arg(&bag)
        .status()
        .unwrap();
    assert!(status.success());

    let scene = Scene::load(&scene_path).unwrap();
    let sim = scene.build().unwrap();
    let welded = sim.cloth.len();
    let panels: usize = drape::garment::mesh_garment(&scene.garments[0])
        .unwrap()
        .panels
        .iter()
        .map(|p| p.points.len())
        .sum();
    assert!(welded < panels);

    let read = read_topic::<PointCloud2>(&bag, "/drape/points").unwrap();
    assert!(read.messages.len() >= 6, "{} frames", read.messages.len());
    for (t, m) in &read.messages {
        assert_eq!(m.width as usize, welded, "frame at {t} ns");
    }
    // The first frame is the dressed shirt at t = 0, as built in-process (f32 rounding apart).
    let first = &read.messages[0].1;
    let step = first.point_step as usize;
    for (i, x) in sim.cloth.x.iter().enumerate() {
        let f = |k: usize| {
            let o = i * step + 4 * k;
            f32::from_le_bytes([
                first.data[o],
                first.data[o + 1],
                first.data[o + 2],
                first.data[o + 3],
            ]) as f64
        };
        let err = (f(0) - x.x)
            .abs()
            .max((f(1) - x.y).abs())
            .max((f(2) - x.z).abs());
        assert!(err < 1e-6, "vertex {i}: error {err}");
    }
}
