//! Cost of recording one cloth frame: 64x64 vertices to a Marker (TRIANGLE_LIST,
//! 7938 triangles) and a PointCloud2, serialised and written to a zstd MCAP bag.

use criterion::{criterion_group, criterion_main, Criterion};
use drape::ros::msg::{ColorRGBA, Marker, PointCloud2, Time};
use drape::ros::{cdr, mesh_marker, point_cloud, BagWriter, Distro};
use drape::Vec3;
use std::hint::black_box;

const N: usize = 64;

fn grid() -> (Vec<Vec3>, Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::with_capacity(N * N);
    let mut nrm = Vec::with_capacity(N * N);
    for j in 0..N {
        for i in 0..N {
            let (x, y) = (i as f64 * 0.01, j as f64 * 0.01);
            pos.push(Vec3::new(x, y, (x * 9.0).sin() * (y * 7.0).cos() * 0.02));
            nrm.push(Vec3::new(-0.1 * x, 0.05 * y, 1.0).normalize());
        }
    }
    let mut tris = Vec::with_capacity(2 * (N - 1) * (N - 1));
    for j in 0..N - 1 {
        for i in 0..N - 1 {
            let a = (j * N + i) as u32;
            let n = N as u32;
            tris.push([a, a + 1, a + n]);
            tris.push([a + 1, a + n + 1, a + n]);
        }
    }
    (pos, nrm, tris)
}

fn bench_frame(c: &mut Criterion) {
    let (pos, nrm, tris) = grid();
    let color = ColorRGBA::new(0.8, 0.3, 0.2, 1.0);
    let dir = tempfile::tempdir().expect("temp dir");

    c.bench_function("convert_64x64", |b| {
        b.iter(|| {
            let m = mesh_marker(
                Distro::Jazzy,
                Time::default(),
                "world",
                "cloth",
                &pos,
                &tris,
                color,
            );
            let p = point_cloud(Time::default(), "world", &pos, &nrm);
            black_box((m, p))
        })
    });

    let marker = mesh_marker(
        Distro::Jazzy,
        Time::default(),
        "world",
        "cloth",
        &pos,
        &tris,
        color,
    );
    let cloud = point_cloud(Time::default(), "world", &pos, &nrm);
    let mut buf = Vec::new();
    c.bench_function("cdr_encode_64x64", |b| {
        b.iter(|| {
            cdr::encode_into(&marker, &mut buf).expect("encode marker");
            let n = buf.len();
            cdr::encode_into(&cloud, &mut buf).expect("encode cloud");
            black_box(n + buf.len())
        })
    });

    let mut bag = BagWriter::create(dir.path().join("bench.mcap")).expect("bag");
    let marker_t = bag
        .add_topic::<Marker>("/cloth/marker", Distro::Jazzy, None)
        .expect("topic");
    let cloud_t = bag
        .add_topic::<PointCloud2>("/cloth/points", Distro::Jazzy, None)
        .expect("topic");
    let mut t_ns = 0u64;
    c.bench_function("convert_write_64x64", |b| {
        b.iter(|| {
            t_ns += 33_333_333;
            let stamp = Time::from_nanos(t_ns);
            let m = mesh_marker(Distro::Jazzy, stamp, "world", "cloth", &pos, &tris, color);
            let p = point_cloud(stamp, "world", &pos, &nrm);
            bag.write(marker_t, t_ns, &m).expect("write marker");
            bag.write(cloud_t, t_ns, &p).expect("write cloud");
        })
    });
    bag.finish().expect("finish");
    let frames = t_ns / 33_333_333;
    let bytes = std::fs::metadata(dir.path().join("bench.mcap")).map_or(0, |m| m.len());
    eprintln!(
        "bag: {frames} frames, {:.0} kB per frame on disk (uncompressed CDR {} kB)",
        bytes as f64 / frames.max(1) as f64 / 1e3,
        (cdr::encode(&marker).map_or(0, |v| v.len()) + cdr::encode(&cloud).map_or(0, |v| v.len()))
            / 1000
    );
}

criterion_group!(benches, bench_frame);
criterion_main!(benches);
