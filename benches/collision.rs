//! Collision stage time per step, per detection mode, on a 64x64-vertex sheet draped over a
//! sphere (positions set analytically on the sphere cap at the thickness, plus one step of
//! gravity as the candidate motion), with cloth-cloth collision off and on.

use criterion::{criterion_group, criterion_main, Criterion};
use drape::collide::SolverFeedback;
use drape::collide::{CollisionSettings, CollisionStage, DetectionMode, Obstacle};
use drape::{Pose, Vec3};

const N: usize = 64;
const R: f64 = 0.5;
const TH: f64 = 0.003;
const H: f64 = 1.0 / 60.0;

struct Drape {
    x0: Vec<Vec3>,
    x1: Vec<Vec3>,
    v1: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
}

fn drape() -> Drape {
    let spacing = 0.015;
    let half = (N - 1) as f64 * spacing / 2.0;
    let mut x0 = Vec::with_capacity(N * N);
    for i in 0..N {
        for j in 0..N {
            // Map the flat grid onto the cap by arc length from the top.
            let (u, v) = (i as f64 * spacing - half, j as f64 * spacing - half);
            let arc = (u * u + v * v).sqrt();
            let theta = arc / R;
            let phi = v.atan2(u);
            let dir = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            x0.push(dir * (R + TH));
        }
    }
    let g = Vec3::new(0.0, 0.0, -9.81);
    let v1: Vec<Vec3> = x0.iter().map(|_| g * H).collect();
    let x1 = x0.iter().zip(&v1).map(|(x, v)| *x + *v * H).collect();
    let mut tris = Vec::new();
    let id = |i: usize, j: usize| (i * N + j) as u32;
    for i in 0..N - 1 {
        for j in 0..N - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Drape { x0, x1, v1, tris }
}

fn bench(c: &mut Criterion) {
    let d = drape();
    let n = d.x0.len();
    let w = vec![1.0; n];
    let mut group = c.benchmark_group("collision_step_64x64_sphere");
    for mode in [
        DetectionMode::Spheres,
        DetectionMode::Proximity,
        DetectionMode::Continuous,
    ] {
        for self_collision in [false, true] {
            let settings = CollisionSettings {
                mode,
                self_collision,
                ..CollisionSettings::default()
            };
            let ball = Obstacle::sphere("ball", R, Pose::IDENTITY).expect("valid sphere");
            let mut stage = CollisionStage::new(
                settings,
                vec![ball],
                d.tris.clone(),
                n,
                vec![TH; n],
                vec![0.5; n],
            )
            .expect("valid stage");
            let (mut x1, mut v1) = (d.x1.clone(), d.v1.clone());
            let name = format!(
                "{mode:?}/self_{}",
                if self_collision { "on" } else { "off" }
            );
            group.bench_function(name, |b| {
                b.iter(|| {
                    x1.copy_from_slice(&d.x1);
                    v1.copy_from_slice(&d.v1);
                    stage.resolve(&d.x0, &mut x1, &mut v1, &w, H, &SolverFeedback::default())
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
