//! Collision stage time for one step of a 5 mm rod (capsule) sweeping at 20 m/s through a
//! 64x64-vertex sheet (1.5 cm spacing), continuous mode, cloth-cloth off: the cost of the
//! obstacle-feature vs cloth-face tests on top of the vertex tests.

use criterion::{criterion_group, criterion_main, Criterion};
use drape::collide::SolverFeedback;
use drape::collide::{CollisionSettings, CollisionStage, DetectionMode, Motion, Obstacle};
use drape::{Pose, Vec3};

const N: usize = 64;
const H: f64 = 1.0 / 60.0;

fn bench(c: &mut Criterion) {
    let spacing = 0.015;
    let half = (N - 1) as f64 * spacing / 2.0;
    let mut x0 = Vec::with_capacity(N * N);
    for i in 0..N {
        for j in 0..N {
            x0.push(Vec3::new(
                j as f64 * spacing - half,
                0.0,
                i as f64 * spacing - half,
            ));
        }
    }
    let id = |i: usize, j: usize| (i * N + j) as u32;
    let mut tris = Vec::new();
    for i in 0..N - 1 {
        for j in 0..N - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let n = x0.len();
    let pose = Pose::from_xyz_rpy([0.0, -0.1, 0.004], [0.0, 0.0, std::f64::consts::FRAC_PI_2]);
    let rod = Obstacle::capsule("rod", 0.005, 0.3, pose)
        .expect("valid rod")
        .with_motion(Motion::Velocity {
            linear: Vec3::new(0.0, 20.0, 0.0),
            angular: Vec3::ZERO,
        });
    let settings = CollisionSettings {
        mode: DetectionMode::Continuous,
        ..CollisionSettings::default()
    };
    let mut stage = CollisionStage::new(settings, vec![rod], tris, n, vec![0.003; n], vec![0.3; n])
        .expect("valid stage");
    stage.advance_obstacles(0.0, H);
    let w = vec![1.0; n];
    let (mut x1, mut v1) = (x0.clone(), vec![Vec3::ZERO; n]);
    c.bench_function("rod_through_64x64_sheet/continuous", |b| {
        b.iter(|| {
            x1.copy_from_slice(&x0);
            v1.fill(Vec3::ZERO);
            stage.resolve(&x0, &mut x1, &mut v1, &w, H, &SolverFeedback::default())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
