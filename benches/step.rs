//! Step cost per integrator and resolution, and the cost of effects.
//!
//! `cargo bench --bench step` prints criterion's timings; divide by the vertex count for the
//! per-vertex figure (the bench ids carry the vertex count).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use drape::integrate::IntegratorKind;
use drape::scene::{EffectKind, Scene};
use drape::sim::Simulation;
use std::path::Path;
use std::time::Duration;

fn scene(res: usize, kind: IntegratorKind, effects: &[EffectKind]) -> Simulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml");
    let mut s = Scene::load(&path).expect("bundled scene");
    s.cloths[0].grid.resolution = [res, res];
    s.effects = effects.to_vec();
    s.solver.integrator = kind;
    // Explicit methods are timed at a step they survive; implicit at one step per 60 Hz frame.
    s.solver.dt = if kind == IntegratorKind::Implicit {
        1.0 / 60.0
    } else {
        1e-5
    };
    s.solver.cg_tolerance = 1e-5;
    s.cloths[0].material.skip_one = 500.0;
    if effects.contains(&EffectKind::Wind) {
        s.wind = Some(serde_yaml_ng::from_str("velocity: [3.0, 1.0, 0.0]").expect("wind"));
    }
    let mut sim = s.build().expect("valid scene");
    // Start from a moving, deformed state rather than rest.
    for _ in 0..3 {
        sim.step().expect("stable");
    }
    sim
}

const BASE: &[EffectKind] = &[
    EffectKind::Gravity,
    EffectKind::Stretch,
    EffectKind::Shear,
    EffectKind::Bending,
];

fn integrators(c: &mut Criterion) {
    let mut g = c.benchmark_group("step");
    g.measurement_time(Duration::from_secs(3)).sample_size(20);
    for res in [32usize, 64, 128] {
        for kind in IntegratorKind::ALL {
            if kind == IntegratorKind::Implicit && res == 128 {
                g.sample_size(10);
            }
            let mut sim = scene(res, kind, BASE);
            g.throughput(Throughput::Elements((res * res) as u64));
            g.bench_with_input(BenchmarkId::new(kind.name(), res * res), &res, |b, _| {
                b.iter(|| sim.step().expect("stable").cg_iterations)
            });
        }
    }
    g.finish();
}

fn effects(c: &mut Criterion) {
    let mut g = c.benchmark_group("effects_64x64_symplectic");
    g.measurement_time(Duration::from_secs(3));
    let all = EffectKind::ALL;
    for (name, list) in [
        (
            "gravity+springs",
            &[EffectKind::Gravity, EffectKind::Stretch, EffectKind::Shear][..],
        ),
        ("all_effects", &all[..]),
    ] {
        let mut sim = scene(64, IntegratorKind::SymplecticEuler, list);
        g.bench_function(name, |b| {
            b.iter(|| sim.step().expect("stable").cg_iterations)
        });
    }
    g.finish();
}

criterion_group!(benches, integrators, effects);
criterion_main!(benches);
