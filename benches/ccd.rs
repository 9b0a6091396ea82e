//! ns per continuous test: vertex-triangle and edge-edge, hit and miss, cubic and thick.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use drape::collide::narrow::{
    edge_edge_ccd, edge_edge_ccd_thick, triangles_intersect, vertex_triangle_ccd,
    vertex_triangle_ccd_thick,
};
use drape::Vec3;

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

fn bench(c: &mut Criterion) {
    let t0 = [v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)];
    let t1 = [v(0.05, 0., 0.02), v(1.05, 0., 0.), v(0., 1.02, -0.01)];
    let eta = 1e-3;
    // (name, p0, p1): a hit, a miss the swept boxes reject, and a miss that crosses the plane
    // beside the triangle (full cubic solve + inside tests).
    let vt_cases = [
        ("hit", v(0.2, 0.2, 0.5), v(0.25, 0.2, -0.5)),
        ("miss_box", v(3., 3., 0.5), v(3., 3., -0.5)),
        ("miss_plane", v(0.7, 0.7, 0.5), v(0.7, 0.7, -0.5)),
    ];
    let mut g = c.benchmark_group("vertex_triangle");
    for (name, p0, p1) in vt_cases {
        g.bench_function(format!("cubic_{name}"), |b| {
            b.iter(|| {
                vertex_triangle_ccd(
                    black_box(p0),
                    black_box(p1),
                    black_box(t0),
                    black_box(t1),
                    eta,
                )
            })
        });
        g.bench_function(format!("thick_{name}"), |b| {
            b.iter(|| {
                vertex_triangle_ccd_thick(
                    black_box(p0),
                    black_box(p1),
                    black_box(t0),
                    black_box(t1),
                    eta,
                )
            })
        });
    }
    g.finish();

    let q0 = [v(0., -1., 0.), v(0., 1., 0.)];
    let q1 = [v(0.05, -1., 0.), v(0., 1., 0.02)];
    let ee_cases = [
        (
            "hit",
            [v(-1., 0., 0.5), v(1., 0., 0.5)],
            [v(-1., 0.1, -0.5), v(1., 0., -0.5)],
        ),
        (
            "miss_box",
            [v(-1., 5., 0.5), v(1., 5., 0.5)],
            [v(-1., 5., -0.5), v(1., 5., -0.5)],
        ),
        (
            "miss_plane",
            [v(0.5, 0., 0.5), v(2., 0., 0.5)],
            [v(0.5, 0.1, -0.5), v(2., 0., -0.5)],
        ),
    ];
    let mut g = c.benchmark_group("edge_edge");
    for (name, p0, p1) in ee_cases {
        g.bench_function(format!("cubic_{name}"), |b| {
            b.iter(|| {
                edge_edge_ccd(
                    black_box(p0),
                    black_box(p1),
                    black_box(q0),
                    black_box(q1),
                    eta,
                )
            })
        });
        g.bench_function(format!("thick_{name}"), |b| {
            b.iter(|| {
                edge_edge_ccd_thick(
                    black_box(p0),
                    black_box(p1),
                    black_box(q0),
                    black_box(q1),
                    eta,
                )
            })
        });
    }
    g.finish();

    let crossing = [v(0.2, 0.2, -1.), v(0.2, 0.2, 1.), v(0.3, 0.25, 1.)];
    let apart = [v(0.2, 0.2, 0.1), v(0.2, 0.2, 1.), v(0.3, 0.25, 1.)];
    let mut g = c.benchmark_group("triangles_intersect");
    g.bench_function("hit", |b| {
        b.iter(|| triangles_intersect(black_box(t0), black_box(crossing)))
    });
    g.bench_function("miss", |b| {
        b.iter(|| triangles_intersect(black_box(t0), black_box(apart)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
