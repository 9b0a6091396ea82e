//! Stage-level obstacle tests, driven by a semi-implicit Euler loop inside the test.

use drape::collide::SolverFeedback;
use drape::collide::{
    CollisionReport, CollisionSettings, CollisionStage, DetectionMode, Motion, Obstacle,
    ResponseMode,
};
use drape::{Pose, Vec3};

const G: Vec3 = Vec3::new(0.0, 0.0, -9.81);
const H: f64 = 1.0 / 60.0;

fn settings(mode: DetectionMode) -> CollisionSettings {
    CollisionSettings {
        mode,
        ..CollisionSettings::default()
    }
}

struct Particles {
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    w: Vec<f64>,
}

impl Particles {
    fn new(x: Vec<Vec3>) -> Self {
        let n = x.len();
        Self {
            x,
            v: vec![Vec3::ZERO; n],
            w: vec![1.0; n],
        }
    }

    /// One semi-implicit Euler step then collision resolution over [t, t + H].
    fn step(&mut self, stage: &mut CollisionStage, t: f64, g: Vec3) -> CollisionReport {
        stage.advance_obstacles(t, t + H);
        let x0 = self.x.clone();
        for i in 0..self.x.len() {
            if self.w[i] > 0.0 {
                self.v[i] += g * H;
                self.x[i] += self.v[i] * H;
            }
        }
        stage.resolve(
            &x0,
            &mut self.x,
            &mut self.v,
            &self.w,
            H,
            &SolverFeedback::default(),
        )
    }
}

fn stage(
    mode: DetectionMode,
    obstacles: Vec<Obstacle>,
    n: usize,
    th: f64,
    mu: f64,
) -> CollisionStage {
    CollisionStage::new(
        settings(mode),
        obstacles,
        Vec::new(),
        n,
        vec![th; n],
        vec![mu; n],
    )
    .unwrap()
}

/// Sheet of particles in the world yz-plane at x = 0, spacing `d`, (2k+1)^2 particles.
fn yz_sheet(k: i32, d: f64) -> Vec<Vec3> {
    let mut out = Vec::new();
    for i in -k..=k {
        for j in -k..=k {
            out.push(Vec3::new(0.0, i as f64 * d, j as f64 * d));
        }
    }
    out
}

/// Whether the local-frame path a -> b enters `inside` (dense sampling: spacing well under the
/// thinnest feature tested, 2 mm).
fn path_enters(a: Vec3, b: Vec3, inside: impl Fn(Vec3) -> bool) -> bool {
    let n = 4000;
    (0..=n).any(|k| inside(a.lerp(b, k as f64 / n as f64)))
}

/// Sweeps `obstacle` along +x at `speed` through a particle sheet; returns the number of
/// particles whose path (in the obstacle frame) entered the shape, and of end points inside it.
fn sweep(
    mode: DetectionMode,
    obstacle: Obstacle,
    speed: f64,
    inside: impl Fn(Vec3) -> bool + Copy,
) -> (usize, usize) {
    let th = 0.001;
    let o = obstacle.with_motion(Motion::Velocity {
        linear: Vec3::new(speed, 0.0, 0.0),
        angular: Vec3::ZERO,
    });
    let mut p = Particles::new(yz_sheet(20, 0.0025));
    let mut st = stage(mode, vec![o], p.x.len(), th, 0.3);
    let steps = (0.8 / (speed * H)).ceil() as usize;
    let (mut crossed, mut ended_inside) = (0, 0);
    for s in 0..steps {
        let x0 = p.x.clone();
        p.step(&mut st, s as f64 * H, Vec3::ZERO);
        let o = &st.obstacles()[0];
        for (xa, xb) in x0.iter().zip(&p.x) {
            let a = o.pose_prev.inverse_transform_point(*xa);
            let b = o.pose.inverse_transform_point(*xb);
            crossed += path_enters(a, b, inside) as usize;
            ended_inside += inside(b) as usize;
        }
    }
    (crossed, ended_inside)
}

fn plate() -> (Obstacle, impl Fn(Vec3) -> bool + Copy) {
    let he = Vec3::new(0.001, 0.2, 0.2); // 2 mm thick
    let o = Obstacle::cuboid(
        "plate",
        he,
        Pose::from_translation(Vec3::new(-0.4, 0.0, 0.0)),
    )
    .unwrap();
    (o, move |p: Vec3| p.abs().cmplt(he).all())
}

fn thin_cylinder() -> (Obstacle, impl Fn(Vec3) -> bool + Copy) {
    let (r, hh) = (0.005, 0.2);
    // Axis (local y) along world z.
    let pose = Pose::from_xyz_rpy([-0.4, 0.0, 0.0], [std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
    let o = Obstacle::cylinder("rod", r, hh, pose).unwrap();
    (o, move |p: Vec3| {
        p.y.abs() < hh && p.x * p.x + p.z * p.z < r * r
    })
}

#[test]
fn continuous_mode_never_tunnels_thin_fast_obstacles() {
    for speed in [5.0, 20.0] {
        let (o, inside) = plate();
        let (crossed, ended) = sweep(DetectionMode::Continuous, o, speed, inside);
        assert_eq!((crossed, ended), (0, 0), "plate at {speed} m/s");
        let (o, inside) = thin_cylinder();
        let (crossed, ended) = sweep(DetectionMode::Continuous, o, speed, inside);
        assert_eq!((crossed, ended), (0, 0), "cylinder at {speed} m/s");
    }
}

/// Documents what the discrete modes do: at 20 m/s (0.33 m per step) the 2 mm plate and the
/// 5 mm rod jump over the sheet, so particles end up behind them (paths cross the obstacle).
#[test]
fn discrete_modes_tunnel_at_high_speed() {
    for mode in [DetectionMode::Spheres, DetectionMode::Proximity] {
        let (o, inside) = plate();
        let (crossed, _) = sweep(mode, o, 20.0, inside);
        assert!(crossed > 100, "{mode:?} plate: {crossed} crossings");
        let (o, inside) = thin_cylinder();
        let (crossed, _) = sweep(mode, o, 20.0, inside);
        assert!(crossed > 0, "{mode:?} rod: {crossed} crossings");
    }
}

fn tilted_plane(angle: f64) -> Obstacle {
    Obstacle::plane(
        "slope",
        Vec3::Z,
        Pose::from_xyz_rpy([0.0; 3], [angle, 0.0, 0.0]),
    )
    .unwrap()
}

/// Runs a particle on a plane tilted by `angle` (about x) for `steps`; returns its velocity
/// along the downhill direction.
fn slide(angle: f64, mu: f64, steps: usize, mode: DetectionMode) -> f64 {
    let th = 0.002;
    let o = tilted_plane(angle);
    let n = o.pose.transform_vector(Vec3::Z);
    let downhill = (G - n * G.dot(n)).normalize();
    let mut p = Particles::new(vec![n * th]);
    let mut st = stage(mode, vec![o], 1, th, mu);
    for s in 0..steps {
        p.step(&mut st, s as f64 * H, G);
    }
    p.v[0].dot(downhill)
}

#[test]
fn friction_threshold_is_tan_angle_equals_mu() {
    let mu: f64 = 0.4;
    let a_crit = mu.atan();
    for mode in [DetectionMode::Proximity, DetectionMode::Continuous] {
        let below = slide(a_crit * 0.97, mu, 120, mode);
        let above = slide(a_crit * 1.03, mu, 120, mode);
        assert!(
            below.abs() < 1e-9,
            "{mode:?}: sliding below threshold at {below} m/s"
        );
        assert!(
            above > 0.01,
            "{mode:?}: stuck above threshold ({above} m/s)"
        );
    }
}

#[test]
fn sliding_acceleration_matches_coulomb() {
    let g = 9.81;
    for (angle_deg, mu) in [(30.0f64, 0.2), (45.0, 0.5), (20.0, 0.0)] {
        let a = angle_deg.to_radians();
        let steps = 90;
        let v = slide(a, mu, steps, DetectionMode::Continuous);
        let expect = g * (a.sin() - mu * a.cos()) * steps as f64 * H;
        assert!(
            (v - expect).abs() < 0.01 * expect,
            "{angle_deg} deg mu {mu}: v {v} vs {expect}"
        );
    }
}

#[test]
fn particles_rest_on_sphere_with_small_penetration() {
    let (r, th) = (0.3, 0.005);
    for mode in [
        DetectionMode::Spheres,
        DetectionMode::Proximity,
        DetectionMode::Continuous,
    ] {
        let sphere = Obstacle::sphere("ball", r, Pose::IDENTITY).unwrap();
        // A cap of particles within 15 degrees of the top (tan 15 < mu: they stick), 2 cm above.
        let mut x = Vec::new();
        for i in -3..=3 {
            for j in -3..=3 {
                let (u, w) = (i as f64 * 0.04, j as f64 * 0.04);
                let dir = Vec3::new(u.sin(), w.sin(), 1.0).normalize();
                x.push(dir * (r + th + 0.02));
            }
        }
        let mut p = Particles::new(x);
        let mut st = stage(mode, vec![sphere], p.x.len(), th, 0.5);
        let mut touched = false;
        for s in 0..120 {
            let rep = p.step(&mut st, s as f64 * H, G);
            touched |= rep.contacts > 0;
            assert!(
                rep.deepest_penetration < 0.1 * th,
                "{mode:?} step {s}: {}",
                rep.deepest_penetration
            );
        }
        assert!(touched);
        for x in &p.x {
            let gap = x.length() - r;
            assert!(gap > 0.9 * th && gap < 1.1 * th, "{mode:?}: gap {gap}");
        }
        // Resting: velocities ~ 0 (gravity per step is removed by the contact).
        assert!(
            p.v.iter().all(|v| v.length() < 1e-6),
            "{mode:?} not at rest"
        );
    }
}

#[test]
fn moving_platform_carries_resting_particle_through_friction() {
    let th = 0.002;
    let speed = 0.5;
    let run = |mu: f64| {
        let platform = Obstacle::cuboid(
            "platform",
            Vec3::new(1.0, 1.0, 0.05),
            Pose::from_translation(Vec3::new(0.0, 0.0, -0.05)),
        )
        .unwrap()
        .with_motion(Motion::Velocity {
            linear: Vec3::new(speed, 0.0, 0.0),
            angular: Vec3::ZERO,
        });
        let mut p = Particles::new(vec![Vec3::new(0.0, 0.0, th)]);
        let mut st = stage(DetectionMode::Continuous, vec![platform], 1, th, mu);
        for s in 0..60 {
            p.step(&mut st, s as f64 * H, G);
        }
        (p.x[0], p.v[0], st.contacts().to_vec())
    };
    let (x, v, contacts) = run(0.8);
    assert!((v.x - speed).abs() < 1e-6, "carried velocity {}", v.x);
    assert!((x.z - th).abs() < 1e-4, "height {}", x.z);
    // It catches up within mu g = 7.8 m/s^2, i.e. ~4 steps: nearly the platform's 0.5 m.
    assert!(x.x > 0.45, "travelled {}", x.x);
    assert_eq!(contacts.len(), 1);
    assert!((contacts[0].surface_velocity - Vec3::new(speed, 0.0, 0.0)).length() < 1e-4);
    assert!((contacts[0].normal - Vec3::Z).length() < 1e-4);
    // Without friction the platform slides underneath.
    let (x, v, _) = run(0.0);
    assert!(v.x.abs() < 1e-12 && x.x.abs() < 1e-12, "{v} {x}");
}

#[test]
fn kinematic_vertices_are_never_moved() {
    for mode in [
        DetectionMode::Spheres,
        DetectionMode::Proximity,
        DetectionMode::Continuous,
    ] {
        let sphere = Obstacle::sphere("ball", 0.3, Pose::IDENTITY).unwrap();
        let (plate, _) = plate();
        let plate = plate.with_motion(Motion::Velocity {
            linear: Vec3::new(20.0, 0.0, 0.0),
            angular: Vec3::ZERO,
        });
        // Pinned particles inside the sphere and in the plate's path.
        let x: Vec<Vec3> = vec![
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 0.29),
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.5, 0.0, 0.0005),
        ];
        let mut p = Particles::new(x.clone());
        p.w = vec![0.0; x.len()];
        let mut st = stage(mode, vec![sphere, plate], x.len(), 0.005, 0.5);
        for s in 0..10 {
            p.step(&mut st, s as f64 * H, G);
            assert_eq!(p.x, x, "{mode:?}");
            assert!(p.v.iter().all(|v| *v == Vec3::ZERO));
        }
    }
}

/// A two-sided mesh plate (2 triangles) thrown up through falling particles at 10 m/s.
#[test]
fn mesh_obstacle_blocks_particles_from_both_sides() {
    let verts = [
        Vec3::new(-0.3, -0.3, 0.0),
        Vec3::new(0.3, -0.3, 0.0),
        Vec3::new(0.3, 0.3, 0.0),
        Vec3::new(-0.3, 0.3, 0.0),
    ];
    let idx = [[0, 1, 2], [0, 2, 3]];
    let th = 0.002;
    let mesh = Obstacle::mesh(
        "tray",
        &verts,
        &idx,
        Pose::from_translation(Vec3::new(0.0, 0.0, -0.5)),
    )
    .unwrap()
    .with_motion(Motion::Velocity {
        linear: Vec3::new(0.0, 0.0, 10.0),
        angular: Vec3::ZERO,
    });
    let mut x = Vec::new();
    for i in -5..=5 {
        for j in -5..=5 {
            x.push(Vec3::new(i as f64 * 0.02, j as f64 * 0.02, 0.0));
        }
    }
    let mut p = Particles::new(x);
    let mut st = stage(DetectionMode::Continuous, vec![mesh], p.x.len(), th, 0.3);
    for s in 0..12 {
        p.step(&mut st, s as f64 * H, G);
        let o = &st.obstacles()[0];
        for x in &p.x {
            let local = o.pose.inverse_transform_point(*x);
            assert!(
                local.z > 0.9 * th,
                "step {s}: particle below the tray at {local}"
            );
        }
    }
}

#[test]
fn bad_inputs_name_the_culprit() {
    let e = Obstacle::sphere("ball", -1.0, Pose::IDENTITY)
        .unwrap_err()
        .to_string();
    assert!(e.contains("ball") && e.contains("radius"), "{e}");
    let e = Obstacle::mesh("m", &[Vec3::ZERO], &[[0, 1, 2]], Pose::IDENTITY)
        .unwrap_err()
        .to_string();
    assert!(e.contains("triangle 0"), "{e}");
    let e = CollisionStage::new(
        CollisionSettings::default(),
        vec![],
        vec![[0, 1, 7]],
        3,
        vec![0.0; 3],
        vec![0.0; 3],
    )
    .err()
    .map(|e| e.to_string())
    .unwrap_or_default();
    assert!(e.contains("triangle 0") && e.contains('7'), "{e}");
    let e = CollisionStage::new(
        CollisionSettings::default(),
        vec![],
        vec![],
        3,
        vec![0.0; 2],
        vec![0.0; 3],
    )
    .err()
    .map(|e| e.to_string())
    .unwrap_or_default();
    assert!(e.contains("thickness"), "{e}");
    // Response-mode helper used by the implicit solver.
    assert!(ResponseMode::Filter.uses_filter() && !ResponseMode::Projection.uses_filter());
}

/// A 2 mm paddle spinning at 30 rad/s about the z axis (tip speed 9 m/s) through a ring of
/// particles: continuous mode keeps every particle path out of the paddle in its local frame.
#[test]
fn continuous_mode_handles_rotating_obstacles() {
    let he = Vec3::new(0.3, 0.001, 0.1);
    let paddle = Obstacle::cuboid("paddle", he, Pose::IDENTITY)
        .unwrap()
        .with_motion(Motion::Velocity {
            linear: Vec3::ZERO,
            angular: Vec3::new(0.0, 0.0, 30.0),
        });
    let mut x = Vec::new();
    for k in 0..72 {
        let a = 0.1 + k as f64 * std::f64::consts::TAU / 72.0;
        for r in [0.1, 0.2, 0.28] {
            x.push(Vec3::new(r * a.cos(), r * a.sin(), 0.0));
        }
    }
    let mut p = Particles::new(x);
    let mut st = stage(
        DetectionMode::Continuous,
        vec![paddle],
        p.x.len(),
        0.001,
        0.3,
    );
    let inside = |q: Vec3| q.abs().cmplt(he).all();
    let mut contacts = 0;
    for s in 0..20 {
        let x0 = p.x.clone();
        contacts += p.step(&mut st, s as f64 * H, Vec3::ZERO).contacts;
        let o = &st.obstacles()[0];
        for (xa, xb) in x0.iter().zip(&p.x) {
            let a = o.pose_prev.inverse_transform_point(*xa);
            let b = o.pose.inverse_transform_point(*xb);
            assert!(!inside(b), "step {s}: ended inside at {b}");
            // The straight local path may touch the faces or slip round the tip, never cross.
            assert!(!path_enters(a, b, inside), "step {s}: crossed {a} -> {b}");
        }
    }
    assert!(contacts > 100);
}

/// Filter response: penetration removed along the normal, velocity projected, but no tangential
/// position change (the implicit solver's filter takes over); projection moves it by h dv_t.
#[test]
fn filter_mode_only_corrects_the_normal_position() {
    let th = 0.002;
    let run = |response| {
        let settings = CollisionSettings {
            mode: DetectionMode::Continuous,
            response,
            ..CollisionSettings::default()
        };
        let o = tilted_plane(0.2);
        let n = o.pose.transform_vector(Vec3::Z);
        let mut st =
            CollisionStage::new(settings, vec![o], Vec::new(), 1, vec![th], vec![0.5]).unwrap();
        let x0 = [n * th];
        let mut v = [G * H];
        let mut x = [x0[0] + v[0] * H];
        let before = x[0];
        st.resolve(&x0, &mut x, &mut v, &[1.0], H, &SolverFeedback::default());
        assert_eq!(st.contacts().len(), 1);
        assert!((st.contacts()[0].normal - n).length() < 1e-12);
        assert!(v[0].length() < 1e-12, "stuck: {}", v[0]);
        (x[0] - before, n)
    };
    let (dx, n) = run(ResponseMode::Filter);
    assert!(
        (dx - n * dx.dot(n)).length() < 1e-15,
        "tangential move {dx}"
    );
    let (dx, n) = run(ResponseMode::Projection);
    let tangential = dx - n * dx.dot(n);
    let expect = (G - n * G.dot(n)).length() * H * H;
    assert!(
        (tangential.length() - expect).abs() < 1e-12,
        "{tangential} vs {expect}"
    );
}
