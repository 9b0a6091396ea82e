//! Where a step of the live node's 64x64 robot_towel goes, without DDS: the robot update (FK
//! and obstacle targets), the simulation step split into the collision stage and the rest
//! (solver, guard, kinematic targets), and the output conversion (normals, mesh and points
//! messages, their CDR encoding). Scene settings and the node's lowest adaptive quality (default
//! bounds: one substep, CG 1e-2, at most 50 iterations), and the one step in which the arm jumps as in the
//! node_latency bench. Prints a table of mean milliseconds per step.
//!
//! `cargo bench --bench robot_step` (`-- RES` for another resolution).

use drape::robot::JointSource;
use drape::ros::msg::{ColorRGBA, Distro, Time};
use drape::ros::{cdr, mesh_marker, point_cloud};
use drape::scene::Scene;
use std::hint::black_box;
use std::time::Instant;

/// Steps timed after the warm-up; the arm follows the scene's trajectory meanwhile.
const STEPS: usize = 60;
const WARMUP: usize = 30;

#[derive(Default)]
struct Split {
    robot: f64,
    step: f64,
    collision: f64,
    normals: f64,
    messages: f64,
    encode: f64,
    substeps: u64,
    cg: u64,
    contacts: usize,
    /// The step in which the shoulder jumps 0.3 rad (the node_latency bench's input): wall ms
    /// and the substeps the divergence guard redid as halves.
    jump_ms: f64,
    jump_subdivisions: u32,
}

fn run(res: usize, preview: bool) -> Split {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut scene = Scene::load(format!("{root}/config/robot_towel.yaml").as_ref())
        .expect("bundled scene loads");
    scene.cloths[0].grid.resolution = [res, res];
    if preview {
        drape::ros::node::lowest_quality(&mut scene, &drape::ros::node::QualityBounds::default());
    }
    let (mut sim, driver) = scene.build_with_robot().expect("bundled scene builds");
    let mut driver = driver.expect("robot_towel has a robot");
    let mut s = Split::default();
    let mut buf = Vec::new();
    for k in 0..WARMUP + STEPS {
        let timed = k >= WARMUP;
        let t0 = Instant::now();
        let t_next = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, t_next);
        let t1 = Instant::now();
        let m = sim.step().expect("robot_towel runs");
        let t2 = Instant::now();
        let c = &sim.cloth;
        let normals = c.vertex_normals();
        let t3 = Instant::now();
        let mesh = mesh_marker(
            Distro::Jazzy,
            Time::from_nanos(1),
            "base_link",
            "drape",
            &c.x,
            &c.triangles,
            ColorRGBA::new(1.0, 0.5, 0.2, 1.0),
        );
        let points = point_cloud(Time::from_nanos(1), "base_link", &c.x, &normals);
        let t4 = Instant::now();
        buf.clear();
        cdr::encode_into(&mesh, &mut buf).expect("mesh encodes");
        cdr::encode_into(&points, &mut buf).expect("points encode");
        black_box(&buf);
        let t5 = Instant::now();
        if timed {
            let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
            s.robot += ms(t0, t1);
            s.step += ms(t1, t2);
            s.collision += m.collision_time_s * 1e3;
            s.normals += ms(t2, t3);
            s.messages += ms(t3, t4);
            s.encode += ms(t4, t5);
            s.substeps += u64::from(m.substeps);
            s.cg += u64::from(m.cg_iterations);
            s.contacts += m.contacts;
        }
    }
    // The latency bench's input: the shoulder jumps by 0.3 rad within one step.
    let t = sim.time();
    let q0 = driver.joint_positions().clone();
    let mut q1 = q0.clone();
    let j = driver
        .robot()
        .joint_index("right_shoulder_pitch")
        .expect("drape_bot has a right shoulder");
    q1.positions[j] += 0.3;
    let dt = sim.settings.dt;
    driver.set_source(JointSource::Stream(vec![(t, q0), (t + dt, q1)]), t);
    driver.advance(&mut sim, t + dt);
    let t0 = Instant::now();
    let m = sim.step().expect("robot_towel runs");
    s.jump_ms = t0.elapsed().as_secs_f64() * 1e3;
    s.jump_subdivisions = m.subdivisions;
    s
}

fn main() {
    let res: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(64);
    println!("\nrobot_towel {res}x{res}: mean ms per step over {STEPS} steps (after {WARMUP})");
    println!("| solver | robot (FK, targets) | step | of which collision | rest of step (solver, guard) | normals | mesh+points msgs | CDR encode | substeps | CG iters/step | contacts | arm-jump step ms (guard subdivisions) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for preview in [false, true] {
        let s = run(res, preview);
        let n = STEPS as f64;
        println!(
            "| {} | {:.3} | {:.2} | {:.2} | {:.2} | {:.3} | {:.3} | {:.3} | {:.1} | {:.0} | {:.0} | {:.1} ({}) |",
            if preview { "preview" } else { "scene" },
            s.robot / n,
            s.step / n,
            s.collision / n,
            (s.step - s.collision) / n,
            s.normals / n,
            s.messages / n,
            s.encode / n,
            s.substeps as f64 / n,
            s.cg as f64 / n,
            s.contacts as f64 / n,
            s.jump_ms,
            s.jump_subdivisions,
        );
    }
}
