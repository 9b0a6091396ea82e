//! The implicit step's two linear paths, `solver.linear: pcg` (multigrid-preconditioned CG) and
//! `direct` (sparse Cholesky of the filtered system), on the scenes of
//! `tests/implicit_bitwise.rs`: both solve the same systems, so their trajectories agree to what
//! the solve tolerance allows, and the direct path analyses each pattern once and refactorises
//! only when the matrix changed.

#[path = "common/bitwise.rs"]
mod bitwise;

use bitwise::bundled_scene;
use drape::integrate::{IntegratorKind, LinearPath, LinearSolver};
use drape::scene::{EffectKind, Scene};
use drape::sim::Simulation;
use std::path::Path;
use std::time::Instant;

struct Case {
    file: &'static str,
    res: usize,
    effects: Option<&'static [EffectKind]>,
    steps: usize,
}

const CASES: &[Case] = &[
    Case {
        file: "hanging.yaml",
        res: 32,
        effects: None,
        steps: 30,
    },
    Case {
        file: "hanging.yaml",
        res: 16,
        effects: Some(&EffectKind::ALL),
        steps: 30,
    },
    Case {
        file: "sphere_drape.yaml",
        res: 24,
        effects: None,
        steps: 60,
    },
    Case {
        file: "table.yaml",
        res: 24,
        effects: None,
        steps: 60,
    },
];

/// The case's scene on linear path `linear`, with the solves taken to `tol`.
fn scene(c: &Case, linear: LinearSolver, tol: f64) -> Simulation {
    let mut s = bundled_scene(c.file, c.res);
    if let Some(effects) = c.effects {
        s.effects = effects.to_vec();
    }
    if s.effects.contains(&EffectKind::Wind) && s.wind.is_none() {
        s.wind = Some(serde_yaml_ng::from_str("velocity: [3.0, 1.0, 0.5]").expect("wind"));
    }
    s.solver.integrator = IntegratorKind::Implicit;
    s.solver.linear = linear;
    s.solver.cg_tolerance = tol;
    s.solver.cg_max_iterations = 2000;
    s.build().expect("valid scene")
}

/// Largest distance between the two simulations' vertices (m).
fn gap(a: &Simulation, b: &Simulation) -> f64 {
    (a.cloth.x.iter().zip(&b.cloth.x))
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}

/// Step by step from the same positions and velocities (the direct simulation's are reset to
/// the PCG one's before each step), at a 1e-9 solve tolerance. Without contact both paths move
/// the cloth to the same place within 1e-8 m every step. With contact the step's discrete
/// decisions (friction modes from the last step's loads, holds, the Newton check) depend on
/// state the reset does not copy and can flip on a difference at the tolerance, so a few steps
/// differ by up to millimetres; the typical step (the median) still agrees within 1e-5 m.
/// The direct path reaches the tolerance in every step and analyses its pattern once.
#[test]
fn direct_and_pcg_steps_agree_to_the_solve_tolerance() {
    let tol = 1e-9;
    for c in CASES {
        let mut pcg = scene(c, LinearSolver::Pcg, tol);
        let mut direct = scene(c, LinearSolver::Direct, tol);
        let (mut gaps, mut factorisations, mut analyses, mut contacts) = (Vec::new(), 0, 0, 0);
        for step in 0..c.steps {
            direct.cloth.x.clone_from(&pcg.cloth.x);
            direct.cloth.v.clone_from(&pcg.cloth.v);
            let mp = pcg.step().expect("stable");
            let md = direct.step().expect("stable");
            assert_eq!(mp.linear_path, Some(LinearPath::Pcg));
            assert_eq!(
                md.linear_path,
                Some(LinearPath::Direct),
                "{} step {step}",
                c.file
            );
            assert!(md.cg_residual_max <= tol, "{} step {step}: {md:?}", c.file);
            gaps.push(gap(&pcg, &direct));
            factorisations += md.factorisations;
            analyses += md.analyses;
            contacts += mp.contacts;
        }
        gaps.sort_by(f64::total_cmp);
        let (median, worst) = (gaps[gaps.len() / 2], gaps[gaps.len() - 1]);
        println!(
            "{} {}: gap median {median:.2e} m, largest {worst:.2e} m, {factorisations} \
             factorisations, {contacts} contacts",
            c.file, c.res
        );
        assert_eq!(analyses, 1, "{}: one symbolic analysis per pattern", c.file);
        assert!(
            factorisations as usize >= c.steps,
            "{}: {factorisations}",
            c.file
        );
        if contacts == 0 {
            assert!(
                worst < 1e-8,
                "{} {}: paths {worst:e} m apart",
                c.file,
                c.res
            );
        } else {
            assert!(
                median < 1e-5,
                "{} {}: paths {median:e} m apart",
                c.file,
                c.res
            );
        }
    }
}

/// `auto` decides from counts: the hanging cloth at 64x64, whose PCG solves take about 20
/// iterations, stays on PCG; the 24x24 cloth draped on a sphere, whose solves take far more
/// than the few a factorisation costs at that size, moves to the direct path and stays.
#[test]
fn auto_takes_the_direct_path_where_it_is_predicted_cheaper() {
    if std::env::var("DRAPE_LINEAR").is_ok() {
        eprintln!("DRAPE_LINEAR forces one path: auto is not tested");
        return;
    }
    let mut s = bundled_scene("hanging.yaml", 64);
    s.solver.integrator = IntegratorKind::Implicit;
    s.solver.linear = LinearSolver::Auto;
    let mut hanging = s.build().expect("valid scene");
    for step in 0..10 {
        let m = hanging.step().expect("stable");
        assert_eq!(m.linear_path, Some(LinearPath::Pcg), "hanging step {step}");
    }
    let mut sphere = scene(&CASES[2], LinearSolver::Auto, 1e-5);
    let paths: Vec<_> = (0..CASES[2].steps)
        .map(|_| sphere.step().expect("stable").linear_path)
        .collect();
    let first = paths.iter().position(|p| *p == Some(LinearPath::Direct));
    let first = first.expect("the draped cloth moves to the direct path");
    assert!(first >= 3, "decided from three steps' counts: {paths:?}");
    assert!(
        paths[first..]
            .iter()
            .all(|p| *p == Some(LinearPath::Direct)),
        "{paths:?}"
    );
}

/// A scene file's `solver.linear` names the path, and a wrong value is an error naming the key.
#[test]
fn scene_key_names_the_path() {
    let dir = tempfile::tempdir().expect("temp dir");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/hanging.yaml");
    let text = std::fs::read_to_string(&src).expect("bundled scene");
    let with = |value: &str| {
        let t = text.replacen("solver:\n", &format!("solver:\n  linear: {value}\n"), 1);
        assert_ne!(t, text, "the scene has a solver section");
        let p = dir.path().join(format!("{value}.yaml"));
        std::fs::write(&p, t).expect("write scene");
        Scene::load(&p)
    };
    assert_eq!(
        with("direct").expect("valid").solver.linear,
        LinearSolver::Direct
    );
    assert_eq!(with("pcg").expect("valid").solver.linear, LinearSolver::Pcg);
    let err = with("cholesky").expect_err("unknown path");
    let mut text = err.to_string();
    let mut cause = std::error::Error::source(&err);
    while let Some(c) = cause {
        text += &format!(": {c}");
        cause = c.source();
    }
    assert!(
        text.contains("linear") && text.contains("cholesky.yaml") && text.contains("direct"),
        "{text}"
    );
}

/// Wall time per frame of both paths on the contact benchmark's scenes (measurement).
#[test]
#[ignore = "measurement: cargo test --release --test implicit_direct -- --ignored --nocapture"]
fn measure_paths() {
    let res: usize = std::env::var("DRAPE_RES")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(64);
    let frames: usize = std::env::var("DRAPE_FRAMES")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(60);
    for file in ["bench_s1.yaml", "bench_s2.yaml"] {
        let only = std::env::var("DRAPE_MEASURE_LINEAR").ok();
        for linear in [LinearSolver::Pcg, LinearSolver::Direct] {
            if only.as_deref().is_some_and(|o| o != linear.name()) {
                continue;
            }
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("benches/scenes")
                .join(file);
            let mut s = Scene::load(&path).expect("bench scene");
            s.cloths[0].grid.resolution = [res, res];
            s.solver.linear = linear;
            let mut sim = s.build().expect("valid");
            let (mut wall, mut setup, mut cg, mut asm, mut fac, mut its) =
                (0.0, 0.0, 0.0, 0.0, 0, 0);
            for _ in 0..frames {
                let t = Instant::now();
                let m = sim.step().expect("stable");
                wall += t.elapsed().as_secs_f64();
                (setup, cg, asm) = (
                    setup + m.setup_time_s,
                    cg + m.cg_time_s,
                    asm + m.assembly_time_s,
                );
                fac += m.factorisations;
                its += m.cg_iterations;
            }
            let f = frames as f64;
            println!(
                "{file} {res} {}: {:.2} ms/frame (setup {:.2}, solves {:.2}, assembly {:.2}), \
                 {:.1} factorisations/frame, {:.1} its/frame",
                linear.name(),
                1e3 * wall / f,
                1e3 * setup / f,
                1e3 * cg / f,
                1e3 * asm / f,
                fac as f64 / f,
                its as f64 / f
            );
        }
    }
}
