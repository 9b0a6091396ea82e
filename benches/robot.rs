//! FK cost for the bundled robot and the Franka Panda (from pybullet_data, skipped if that
//! Python package is missing) and mesh load times.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use drape::mesh::load_mesh;
use drape::robot::{Robot, UrdfOptions};
use drape::Vec3;
use std::path::{Path, PathBuf};

fn pybullet_data() -> Option<PathBuf> {
    let out = std::process::Command::new("python3")
        .args([
            "-c",
            "import pybullet_data; print(pybullet_data.getDataPath())",
        ])
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()))
}

fn bench_fk(c: &mut Criterion, name: &str, urdf: &Path) {
    let options = UrdfOptions {
        use_ros_env: false,
        ..Default::default()
    };
    let robot = match Robot::from_urdf_file(urdf, &options) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("skipping {name}: {e}");
            return;
        }
    };
    let mut q = robot.zero_positions();
    for (i, p) in q.positions.iter_mut().enumerate() {
        *p = 0.1 * i as f64;
    }
    let mut out = Vec::new();
    c.bench_function(&format!("fk_{name}"), |b| {
        b.iter(|| black_box(robot.link_poses_into(black_box(&q), &mut out)))
    });
    c.bench_function(&format!("load_urdf_{name}"), |b| {
        b.iter(|| black_box(Robot::from_urdf_file(urdf, &options).ok()))
    });
}

fn fk(c: &mut Criterion) {
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/drape_bot.urdf");
    bench_fk(c, "drape_bot", &bundled);
    match pybullet_data() {
        Some(d) => bench_fk(c, "panda", &d.join("franka_panda/panda.urdf")),
        None => eprintln!("skipping panda: pip install pybullet"),
    }
}

fn meshes(c: &mut Criterion) {
    let head = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/meshes/head.stl");
    c.bench_function("load_stl_head_960_tris", |b| {
        b.iter(|| black_box(load_mesh(&head, Vec3::ONE).ok()))
    });
    if let Some(d) = pybullet_data() {
        let obj = d.join("franka_panda/meshes/collision/link0.obj");
        c.bench_function("load_obj_panda_link0", |b| {
            b.iter(|| black_box(load_mesh(&obj, Vec3::ONE).ok()))
        });
    }
}

criterion_group!(benches, fk, meshes);
criterion_main!(benches);
