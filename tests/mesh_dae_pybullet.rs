//! Real Collada files from `pybullet_data` (racecar meshes). Triangle counts were cross-checked
//! against trimesh 5.2 / pycollada; unlike trimesh we honour `<unit>` and `<up_axis>`, so the
//! bounds below are derived from trimesh's raw bounds by those conversions.

use drape::mesh::load_mesh;
use drape::Vec3;
use std::path::PathBuf;

fn racecar_meshes() -> PathBuf {
    let out = std::process::Command::new("python3")
        .args([
            "-c",
            "import pybullet_data; print(pybullet_data.getDataPath())",
        ])
        .output()
        .unwrap_or_else(|e| panic!("cannot run python3 ({e}); pip install pybullet yourdfpy"));
    assert!(
        out.status.success(),
        "pybullet_data missing: pip install pybullet yourdfpy\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()).join("racecar/meshes")
}

#[test]
fn racecar_collada_meshes_match_reference() {
    let dir = racecar_meshes();
    let counts = [
        ("chassis.dae", 324),
        ("cone.dae", 38),
        ("hokuyo.dae", 1250),
        ("left_front_wheel.dae", 1632),
        ("left_steering_hinge.dae", 2352),
        ("walker_racecourse.dae", 3382),
    ];
    for (name, tris) in counts {
        let m = load_mesh(&dir.join(name), Vec3::ONE).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.indices.len(), tris, "{name}");
    }
    // cone.dae: <unit meter="0.0254"> (inches), Z_UP; trimesh's raw half-width is 2.9528 in.
    let (lo, hi) = load_mesh(&dir.join("cone.dae"), Vec3::ONE)
        .unwrap()
        .aabb()
        .unwrap();
    assert!((hi.x - 2.9528 * 0.0254).abs() < 1e-4 && (lo.x + 2.9528 * 0.0254).abs() < 1e-4);
    assert!((hi.z - 6.6929 * 0.0254).abs() < 1e-4, "{hi}");
    // chassis.dae: Y_UP; raw y in [-0.1, 0.1], z in [-0.03, 0.03] becomes z and -y.
    let (lo, hi) = load_mesh(&dir.join("chassis.dae"), Vec3::ONE)
        .unwrap()
        .aabb()
        .unwrap();
    assert!((lo - Vec3::new(-0.04, -0.03, -0.1)).length() < 1e-4, "{lo}");
    assert!((hi - Vec3::new(0.365, 0.03, 0.1)).length() < 1e-4, "{hi}");
}
