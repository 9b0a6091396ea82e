//! The contact benchmark: scene S1 (a 1 m cloth dropped flat onto a fixed sphere, 2 s,
//! `benches/scenes/bench_s1.yaml`) and S2 (the same cloth hanging from two corners, no contact,
//! `benches/scenes/bench_s2.yaml`) at 32x32, 64x64 and 128x128, and the robot towel
//! (`config/robot_towel.yaml` at 64x64 with self-collision, 2 s of its script), each run once
//! as a whole simulation on each linear path (`solver.linear: pcg` and `direct`) side by side.
//!
//! `cargo bench --bench contact` prints one row per run: wall seconds per simulated second
//! (the steps alone, scene build excluded), p99 and max structural edge stretch (length over
//! rest, worst frame of the run and at the end), the deepest vertex below the sphere's radius
//! (S1), CG iterations per frame (mean and max, and for S1 split into the frames before the
//! first contact and those with contacts), force evaluations per frame, the contacts at the
//! end, and where a frame's wall time went: the linear solves' setup (the Cholesky
//! factorisations on the direct path, the multigrid's builds and updates on PCG), the solves'
//! iterations, the assembly of the systems, the collision stage and the rest (force passes,
//! Newton checks, the guard). A summary per scene and resolution sets the paths side by side.
//! `DRAPE_BENCH_LINEAR=direct` runs one path only, `DRAPE_BENCH_TOWEL=0` skips the towel.
//! `DRAPE_BENCH_RES=64` (comma separated) picks resolutions, `DRAPE_BENCH_SCENES=s1` scenes,
//! `DRAPE_BENCH_STRAIN_LIMIT=0.01` adds `material.strain_limit` and
//! `DRAPE_BENCH_FRICTION=5` sets the cloth's friction (neither is the scene's material);
//! `DRAPE_BENCH_LINEARISATION=0.2` sets `solver.linearisation_tolerance` (Newton iterations while
//! a spring stretches more than that beyond its linearised prediction; 1e9: the energy check
//! alone); `DRAPE_BENCH_SUBSTEPS=4` sets `solver.substeps` (the scene's is 1: what the step size
//! contributes to the stretch). It uses only `Simulation`'s public metrics, so the same file
//! runs on an older checkout, for a ratio between two builds on one machine.

use drape::cloth::topology::{springs, SpringKind};
use drape::integrate::LinearSolver;
use drape::robot::RobotDriver;
use drape::scene::Scene;
use drape::sim::Simulation;
use std::path::Path;
use std::time::Instant;

/// The sphere of S1 (centre z, radius), as in `benches/scenes/bench_s1.yaml`.
const SPHERE: ([f64; 3], f64) = ([0.0, 0.0, 0.5], 0.3);

/// What one run measured.
#[derive(Debug, Default)]
struct Run {
    frames: usize,
    wall_s: f64,
    sim_s: f64,
    /// Wall time in the solves' iterations, their setup, the assembly and the collision stage
    /// (s, summed over the run).
    cg_s: f64,
    setup_s: f64,
    assembly_s: f64,
    collision_s: f64,
    factorisations: u64,
    /// Worst frame's p99 and max structural stretch, and the end state's.
    p99_worst: f64,
    max_worst: f64,
    p99_end: f64,
    max_end: f64,
    /// The frame of the worst max stretch, and the frames whose max stretch exceeds 1.02.
    worst_frame: usize,
    frames_over: usize,
    /// Deepest vertex below the sphere's radius (m; 0: none inside) and frames with any.
    penetration: f64,
    penetrating_frames: usize,
    /// CG iterations per frame: all frames, frames without contacts before the first contact,
    /// frames with contacts.
    cg: Vec<u32>,
    cg_free: Vec<u32>,
    cg_contact: Vec<u32>,
    force_evaluations: u64,
    subdivisions: u64,
    contacts_end: usize,
    contacts_max: usize,
}

fn load(file: &str, res: usize, linear: LinearSolver) -> (Simulation, Option<RobotDriver>) {
    let dir = if file == TOWEL {
        "config"
    } else {
        "benches/scenes"
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir).join(file);
    let mut s = Scene::load(&path).expect("bundled bench scene");
    s.cloths[0].grid.resolution = [res, res];
    s.solver.linear = linear;
    if file == TOWEL {
        s.collision.self_collision = true;
    }
    // Not the scene's material: a strain limit added on request, to see what it buys.
    s.cloths[0].material.strain_limit = std::env::var("DRAPE_BENCH_STRAIN_LIMIT")
        .ok()
        .and_then(|l| l.parse().ok());
    if let Some(mu) = std::env::var("DRAPE_BENCH_FRICTION")
        .ok()
        .and_then(|m| m.parse().ok())
    {
        s.cloths[0].material.friction = mu;
    }
    if let Some(t) = std::env::var("DRAPE_BENCH_LINEARISATION")
        .ok()
        .and_then(|t| t.parse().ok())
    {
        s.solver.linearisation_tolerance = t;
    }
    // Not the scene's settings either: substeps per 1/60 s frame, to see what the step size
    // contributes to the landing's stretch.
    if let Some(n) = std::env::var("DRAPE_BENCH_SUBSTEPS")
        .ok()
        .and_then(|n| n.parse().ok())
    {
        s.solver.substeps = n;
    }
    s.build_with_robot().expect("valid scene")
}

/// The robot towel scene (`config/`), run with self-collision on.
const TOWEL: &str = "robot_towel.yaml";

/// Structural edges (vertex pair, rest length) of the first cloth piece.
fn structural(sim: &Simulation) -> Vec<(usize, usize, f64)> {
    sim.cloth
        .pieces
        .iter()
        .flat_map(|p| springs(p, SpringKind::Structural))
        .map(|s| (s.i as usize, s.j as usize, s.rest))
        .collect()
}

/// p99 and max of length over rest across `edges`.
fn stretch(sim: &Simulation, edges: &[(usize, usize, f64)], ratios: &mut Vec<f64>) -> (f64, f64) {
    ratios.clear();
    ratios.extend(
        edges
            .iter()
            .map(|&(i, j, rest)| (sim.cloth.x[i] - sim.cloth.x[j]).length() / rest),
    );
    ratios.sort_by(f64::total_cmp);
    let p99 = ratios[((ratios.len() as f64 * 0.99).ceil() as usize).clamp(1, ratios.len()) - 1];
    (p99, ratios[ratios.len() - 1])
}

fn run(file: &str, res: usize, sphere: bool, linear: LinearSolver) -> Run {
    let (mut sim, mut driver) = load(file, res, linear);
    let edges = structural(&sim);
    let mut ratios = Vec::with_capacity(edges.len());
    let frames = (2.0 / sim.settings.dt).round() as usize;
    let centre = drape::Vec3::from_array(SPHERE.0);
    let mut r = Run {
        frames,
        ..Run::default()
    };
    let mut touched = false;
    for f in 0..frames {
        let t = Instant::now();
        if let Some(d) = driver.as_mut() {
            let at = sim.time() + sim.settings.dt;
            d.advance(&mut sim, at);
        }
        let m = sim.step().expect("bench scene stays stable");
        r.wall_s += t.elapsed().as_secs_f64();
        (r.cg_s, r.collision_s) = (r.cg_s + m.cg_time_s, r.collision_s + m.collision_time_s);
        (r.setup_s, r.assembly_s) = (r.setup_s + m.setup_time_s, r.assembly_s + m.assembly_time_s);
        r.factorisations += u64::from(m.factorisations);
        r.cg.push(m.cg_iterations);
        touched |= m.contacts > 0;
        if m.contacts > 0 {
            r.cg_contact.push(m.cg_iterations);
        } else if !touched {
            r.cg_free.push(m.cg_iterations);
        }
        r.force_evaluations += u64::from(m.force_evaluations);
        r.subdivisions += u64::from(m.subdivisions);
        r.contacts_end = m.contacts;
        r.contacts_max = r.contacts_max.max(m.contacts);
        let (p99, max) = stretch(&sim, &edges, &mut ratios);
        r.p99_worst = r.p99_worst.max(p99);
        if max > r.max_worst {
            (r.max_worst, r.worst_frame) = (max, f);
        }
        r.frames_over += usize::from(max > 1.02);
        (r.p99_end, r.max_end) = (p99, max);
        if sphere {
            let deepest = sim
                .cloth
                .x
                .iter()
                .map(|x| SPHERE.1 - (*x - centre).length())
                .fold(0.0, f64::max);
            r.penetration = r.penetration.max(deepest);
            r.penetrating_frames += usize::from(deepest > 0.0);
        }
    }
    r.sim_s = frames as f64 * sim.settings.dt;
    r
}

fn mean(v: &[u32]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len() as f64
}

fn max(v: &[u32]) -> u32 {
    v.iter().copied().max().unwrap_or(0)
}

fn list<T: std::str::FromStr>(var: &str, default: Vec<T>) -> Vec<T> {
    match std::env::var(var) {
        Ok(s) => s.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) => default,
    }
}

fn main() {
    // `cargo bench` passes `--bench`; a filter argument is not used.
    let resolutions: Vec<usize> = list("DRAPE_BENCH_RES", vec![32, 64, 128]);
    let scenes: Vec<String> = list("DRAPE_BENCH_SCENES", vec!["s1".into(), "s2".into()]);
    let paths: Vec<LinearSolver> = [LinearSolver::Pcg, LinearSolver::Direct]
        .into_iter()
        .filter(|p| std::env::var("DRAPE_BENCH_LINEAR").map_or(true, |l| l == p.name()))
        .collect();
    println!(
        "scene res path | wall s / sim s | stretch p99 max (worst frame) at frame, frames over \
         1.02 | p99 max (end) | penetration below r (m, frames) | CG/frame mean max | before \
         contact | with contact | force evals/frame | subdiv | contacts end max | \
         factorisations/frame | ms/frame: setup (factorisation), solves, assembly, collision, rest"
    );
    let mut runs: Vec<(String, usize)> = Vec::new();
    for res in &resolutions {
        for scene in &scenes {
            match scene.as_str() {
                "s1" => runs.push(("bench_s1.yaml".into(), *res)),
                "s2" => runs.push(("bench_s2.yaml".into(), *res)),
                other => eprintln!("unknown scene {other} (s1, s2)"),
            }
        }
    }
    if std::env::var("DRAPE_BENCH_TOWEL").map_or(true, |t| t != "0") {
        runs.push((TOWEL.into(), 64));
    }
    let mut table = Vec::new();
    for (file, res) in &runs {
        let name = match file.as_str() {
            "bench_s1.yaml" => "S1",
            "bench_s2.yaml" => "S2",
            _ => "towel",
        };
        for path in &paths {
            let r = run(file, *res, name == "S1", *path);
            let f = r.frames as f64;
            let rest = r.wall_s - r.cg_s - r.setup_s - r.assembly_s - r.collision_s;
            println!(
                "{name} {res}x{res} {} | {:.3} | {:.4} {:.4} at {}, {} | {:.4} {:.4} | {:.2e} {} \
                 | {:.1} {} | {:.1} {} | {:.1} {} | {:.2} | {} | {} {} | {:.2} | {:.1} {:.1} \
                 {:.1} {:.1} {:.1}",
                path.name(),
                r.wall_s / r.sim_s,
                r.p99_worst,
                r.max_worst,
                r.worst_frame,
                r.frames_over,
                r.p99_end,
                r.max_end,
                r.penetration,
                r.penetrating_frames,
                mean(&r.cg),
                max(&r.cg),
                mean(&r.cg_free),
                max(&r.cg_free),
                mean(&r.cg_contact),
                max(&r.cg_contact),
                r.force_evaluations as f64 / f,
                r.subdivisions,
                r.contacts_end,
                r.contacts_max,
                r.factorisations as f64 / f,
                1e3 * r.setup_s / f,
                1e3 * r.cg_s / f,
                1e3 * r.assembly_s / f,
                1e3 * r.collision_s / f,
                1e3 * rest / f,
            );
            table.push((name, *res, *path, r));
        }
    }
    let find = |n: &str, res: usize, p: LinearSolver| {
        table
            .iter()
            .find(|(m, r, q, _)| *m == n && *r == res && *q == p)
            .map(|(_, _, _, r)| r)
    };
    // The paths side by side: wall seconds per simulated second and direct over PCG.
    println!("side by side: scene res | wall s / sim s PCG, direct | direct / PCG");
    for (file, res) in &runs {
        let name = match file.as_str() {
            "bench_s1.yaml" => "S1",
            "bench_s2.yaml" => "S2",
            _ => "towel",
        };
        if let (Some(p), Some(d)) = (
            find(name, *res, LinearSolver::Pcg),
            find(name, *res, LinearSolver::Direct),
        ) {
            let (wp, wd) = (p.wall_s / p.sim_s, d.wall_s / d.sim_s);
            println!("{name} {res}x{res} | {wp:.3} {wd:.3} | {:.2}", wd / wp);
        }
    }
    // Contact against the same cloth without contact (S2), per resolution and path.
    for res in &resolutions {
        for path in &paths {
            if let (Some(s1), Some(s2)) = (find("S1", *res, *path), find("S2", *res, *path)) {
                println!(
                    "{res}x{res} {}: CG per frame with contact (S1) / without (S2) = {:.2}; \
                     wall S1 / S2 = {:.2}",
                    path.name(),
                    mean(&s1.cg_contact) / mean(&s2.cg).max(1e-9),
                    s1.wall_s / s2.wall_s.max(1e-9),
                );
            }
        }
    }
}
