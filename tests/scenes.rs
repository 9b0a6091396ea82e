//! Scene-level checks: static equilibrium, anisotropic materials, the divergence guard, and
//! effects that cost nothing when a scene does not name them.

use drape::effects::State;
use drape::scene::Scene;
use drape::sim::{DivergencePolicy, Simulation};
use drape::Vec3;
use std::path::Path;

fn load(name: &str) -> Scene {
    Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config")
            .join(name),
    )
    .unwrap()
}

fn run(sim: &mut Simulation, seconds: f64) {
    let n = (seconds / sim.settings.dt).round() as usize;
    for _ in 0..n {
        sim.step().unwrap();
    }
}

/// Largest net non-damping force on a free vertex, relative to its weight.
fn max_residual(sim: &Simulation) -> f64 {
    let c = &sim.cloth;
    let zero = vec![Vec3::ZERO; c.len()];
    let mut f = vec![Vec3::ZERO; c.len()];
    sim.effects().forces(
        &State {
            t: sim.time(),
            x: &c.x,
            v: &zero,
        },
        &mut f,
    );
    let pinned: Vec<usize> = c.kinematic.iter().map(|(i, _)| *i as usize).collect();
    (0..c.len())
        .filter(|i| !pinned.contains(i))
        .map(|i| f[i].length() / (c.mass[i] * 9.81))
        .fold(0.0, f64::max)
}

#[test]
fn hanging_cloth_reaches_static_equilibrium_with_implicit_at_60_hz() {
    let mut scene = load("hanging.yaml");
    scene.cloths[0].grid.resolution = [16, 16];
    scene.cloths[0].material.damping.air = 1.0;
    let mut sim = scene.build().unwrap();
    run(&mut sim, 20.0);
    let m = sim.last_metrics().clone();
    let r = max_residual(&sim);
    eprintln!(
        "residual {r:e}, speed {:e}, cg {}",
        m.max_speed, m.cg_iterations
    );
    // After 20 s at an air-damping rate of 1/s the slowest mode has decayed by e^-20 ~ 2e-9.
    assert!(
        r < 1e-6,
        "net force on a free vertex is {r:e} of its weight"
    );
    assert!(m.max_speed < 1e-3, "still moving at {} m/s", m.max_speed);
}

/// Fold statistics of a lattice cloth: mean absolute normal curvature and the number of sign
/// changes of the normal curvature along grid lines, separately along u (warp) and v (weft).
#[derive(Debug, Clone, Copy)]
struct Folds {
    curvature_u: f64,
    curvature_v: f64,
    sign_changes_u: usize,
    sign_changes_v: usize,
}

fn folds(sim: &Simulation) -> Folds {
    let c = &sim.cloth;
    let l = c.pieces[0].panel.lattice.as_ref().unwrap();
    let normals = c.vertex_normals();
    let at = |i: usize, j: usize| j * l.nu + i;
    // Normal curvature along one direction; tiny values (below 1% of 1/size) count as flat so that
    // numerical noise on a flat sheet is not a fold.
    let curv = |a: usize, b: usize, cc: usize, h: f64| {
        let k = (c.x[a] - 2.0 * c.x[b] + c.x[cc]).dot(normals[b]) / (h * h);
        if k.abs() < 0.01 {
            0.0
        } else {
            k
        }
    };
    let line = |ks: Vec<f64>| {
        let nz: Vec<f64> = ks.iter().copied().filter(|k| *k != 0.0).collect();
        let changes = nz
            .windows(2)
            .filter(|w| w[0].signum() != w[1].signum())
            .count();
        (ks.iter().map(|k| k.abs()).sum::<f64>(), ks.len(), changes)
    };
    let (mut su, mut nu_, mut cu) = (0.0, 0, 0);
    for j in 0..l.nv {
        let (s, n, ch) = line(
            (1..l.nu - 1)
                .map(|i| curv(at(i - 1, j), at(i, j), at(i + 1, j), l.du))
                .collect(),
        );
        su += s;
        nu_ += n;
        cu += ch;
    }
    let (mut sv, mut nv_, mut cv) = (0.0, 0, 0);
    for i in 0..l.nu {
        let (s, n, ch) = line(
            (1..l.nv - 1)
                .map(|j| curv(at(i, j - 1), at(i, j), at(i, j + 1), l.dv))
                .collect(),
        );
        sv += s;
        nv_ += n;
        cv += ch;
    }
    Folds {
        curvature_u: su / nu_ as f64,
        curvature_v: sv / nv_ as f64,
        sign_changes_u: cu,
        sign_changes_v: cv,
    }
}

#[test]
fn three_corner_materials_differ_as_the_survey_shows() {
    let mut out = Vec::new();
    for v in ["normal", "soft_stretch", "soft_bending", "soft_warp"] {
        let mut sim = load(&format!("three_corner_{v}.yaml")).build().unwrap();
        run(&mut sim, 2.0);
        let f = folds(&sim);
        eprintln!("{v}: {f:?}");
        out.push(f);
    }
    let [normal, _soft_stretch, soft_bending, soft_warp] = [out[0], out[1], out[2], out[3]];
    let folds_total = |f: &Folds| f.sign_changes_u + f.sign_changes_v;
    let curv_total = |f: &Folds| f.curvature_u + f.curvature_v;
    // Soft bending: more and finer folds (more curvature sign changes, sharper curvature).
    assert!(
        folds_total(&soft_bending) > folds_total(&normal) * 3 / 2,
        "{soft_bending:?} vs {normal:?}"
    );
    assert!(curv_total(&soft_bending) > curv_total(&normal));
    // The scene is symmetric about the diagonal, so isotropic materials fold alike along u and v...
    for f in [normal, soft_bending] {
        let (u, v) = (f.sign_changes_u as f64, f.sign_changes_v as f64);
        assert!((u - v).abs() <= 0.1 * u.max(v), "{f:?}");
    }
    // ...while the one soft along the warp folds more along u, and sits between the two others.
    assert!(
        soft_warp.sign_changes_u as f64 > 1.3 * soft_warp.sign_changes_v as f64,
        "{soft_warp:?}"
    );
    assert!(soft_warp.curvature_u > soft_warp.curvature_v);
    assert!(
        folds_total(&normal) < folds_total(&soft_warp)
            && folds_total(&soft_warp) < folds_total(&soft_bending)
    );
}

fn stiff_explicit(policy: DivergencePolicy) -> Simulation {
    let mut scene = load("hanging.yaml");
    let c = &mut scene.cloths[0];
    c.grid.resolution = [12, 12];
    c.material.stretch = 1e5;
    scene.solver.integrator = drape::integrate::IntegratorKind::SymplecticEuler;
    scene.solver.dt = 1.0 / 60.0;
    scene.solver.guard.policy = policy;
    scene.build().unwrap()
}

#[test]
fn divergence_guard_subdivides_and_stays_finite() {
    let mut sim = stiff_explicit(DivergencePolicy::Subdivide);
    let mut subdivisions = 0;
    for _ in 0..30 {
        let m = sim.step().expect("subdivision keeps the run alive");
        subdivisions += m.subdivisions;
    }
    assert!(
        subdivisions > 0,
        "a step 60x over the stability limit must be subdivided"
    );
    assert!(sim.cloth.x.iter().all(|x| x.is_finite()));
    // It stays a cloth: no vertex went far from where a hanging sheet can be.
    assert!(sim.cloth.x.iter().all(|x| x.length() < 5.0));
}

#[test]
fn divergence_guard_stops_with_a_clear_error() {
    let mut sim = stiff_explicit(DivergencePolicy::Stop);
    let err = (0..30).find_map(|_| sim.step().err()).expect("must stop");
    let msg = err.to_string();
    assert!(msg.contains("cloth 'sheet'"), "{msg}");
    assert!(msg.contains("cloths[0].material.stretch"), "{msg}");
    assert!(msg.contains("symplectic_euler"), "{msg}");
    // The state was rolled back: nothing non-finite is left for an output to publish.
    assert!(sim.cloth.x.iter().all(|x| x.is_finite()));
}

#[test]
fn effects_a_scene_does_not_name_are_never_evaluated() {
    let mut sim = load("hanging.yaml").build().unwrap();
    assert!(!sim.effects().names().contains(&"wind"));
    run(&mut sim, 0.1);
    let counts = sim.effects().evaluation_counts();
    assert!(counts.iter().all(|(n, _)| *n != "wind"));
    assert!(counts.iter().all(|(_, c)| *c > 0));

    let mut flag = load("flag.yaml").build().unwrap();
    run(&mut flag, 0.1);
    let wind = flag
        .effects()
        .evaluation_counts()
        .into_iter()
        .find(|(n, _)| *n == "wind");
    assert!(matches!(wind, Some((_, c)) if c > 0));
    // Twist is not in the flag's list, so it was not built.
    assert!(!flag.effects().names().contains(&"twist"));
}

/// The effects a built scene reports (`drape check` prints them) are the scene's own names, each
/// once: `damping` builds two terms here (along springs, against the air), which `drape check`
/// listed as `damping` twice.
#[test]
fn a_built_scene_names_each_of_its_effects_once() {
    let sim = load("hanging.yaml").build().unwrap();
    let names = sim.effects().names();
    assert_eq!(
        names.iter().filter(|n| **n == "damping").count(),
        1,
        "{names:?}"
    );
    assert!(
        sim.effects()
            .iter()
            .filter(|e| e.name() == "damping")
            .count()
            >= 2
    );
}

#[test]
fn bad_scenes_name_the_key_and_reason() {
    let base =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml"))
            .unwrap();
    let cases = [
        (
            "stretch: 2000.0",
            "stretch: -1.0",
            "cloths[0].material.stretch: must be > 0",
        ),
        (
            "dt: 0.016666666666666666",
            "dt: 0.0",
            "solver.dt: must be > 0",
        ),
        (
            "resolution: [32, 32]",
            "resolution: [100000, 100000]",
            "cloths[0].grid.resolution",
        ),
        (
            "density: 0.2",
            "density: .nan",
            "cloths[0].material.density",
        ),
        (
            "{ region: top_left }",
            "{ vertex: 5000 }",
            "cloths[0].pins[0]: vertex 5000 out of range",
        ),
        (
            "stretch: 2000.0",
            "stretchh: 2000.0",
            "unknown field `stretchh`",
        ),
        (
            "effects: [gravity,",
            "effects: [wind, gravity,",
            "wind: the effect list names wind",
        ),
    ];
    for (from, to, want) in cases {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        let err = drape::input::error_chain(&Scene::from_yaml(&text, "test.yaml").unwrap_err());
        assert!(err.contains(want), "{to}: got `{err}`");
        assert!(err.starts_with("error: test.yaml"), "{err}");
    }
}

#[test]
fn attached_vertices_follow_a_moving_frame_exactly() {
    let mut scene = load("hanging.yaml");
    scene.cloths[0].grid.resolution = [12, 12];
    scene.frames = vec![serde_yaml_ng::from_str(
        "{ name: handle, pose: { xyz: [0.4, 0.0, 2.0] }, linear_velocity: [0.0, 0.3, 0.1], angular_velocity: [0.0, 0.0, 1.5] }",
    )
    .unwrap()];
    scene.cloths[0].pins = vec![serde_yaml_ng::from_str("{ region: top_left }").unwrap()];
    scene.cloths[0].attach =
        vec![serde_yaml_ng::from_str("{ frame: handle, region: top_right }").unwrap()];
    let spec = scene.frames[0].clone();
    // The frame origin sits 10 cm from the attached corner, so its rotation moves the vertex too.
    let mut sim = scene.build().unwrap();
    let (vertex, local) = sim
        .cloth
        .kinematic
        .iter()
        .find_map(|(i, k)| match k {
            drape::cloth::Kinematic::Attached { local, .. } => Some((*i as usize, *local)),
            _ => None,
        })
        .unwrap();
    for _ in 0..120 {
        sim.step().unwrap();
        let want = spec.pose_at(sim.time()).transform_point(local);
        let err = (sim.cloth.x[vertex] - want).length();
        assert!(
            err < 1e-9,
            "attached vertex off its frame by {err} m at t = {}",
            sim.time()
        );
    }
    // The rest of the cloth follows (it is dragged along +y).
    let mean_y = sim.cloth.x.iter().map(|x| x.y).sum::<f64>() / sim.cloth.len() as f64;
    assert!(
        mean_y > 0.05,
        "cloth did not follow the handle (mean y {mean_y})"
    );
}
