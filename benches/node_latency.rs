//! Latency of the live node: from a joint-state message to the first `~/points` message that
//! shows it (the cloth vertices attached to the moving link have moved), on drape_bot holding
//! the towel of config/robot_towel.yaml at 24x24 and 64x64 vertices, published at 30 Hz.
//!
//! Rows through DDS (the real node) and "direct" rows that talk to the simulation thread over
//! channels (the node's pipeline without middleware), with the age of the state the detecting
//! message carries (arrival minus its stamp, the clock time its step was due): latency minus age
//! is how long after the message that step was due (negative while the simulation lags).
//! Each step of the arm is a 0.3 rad jump of the shoulder, which the node reaches at the joint's
//! velocity limit (`joint_velocity_limits`); one self-collision row has the limits off, each
//! jump reached in one step.
//!
//! Runs DDS, so it re-executes itself inside a private network namespace (root, iproute2):
//! `cargo bench --bench node_latency`. Prints a table.

#[path = "../tests/support/netns.rs"]
mod netns;

use drape::cloth::Kinematic;
use drape::robot::JointInput;
use drape::ros::msg::{DiagnosticArray, Header, JointState, PointCloud2, Time};
use drape::ros::node::{
    context, run_node, thread, ClockMode, Command, LoopConfig, Network, NodeParams, Output,
    QualityBounds, SimLoop, WallClock,
};
use drape::scene::Scene;
use ros2_client::qos::History;
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

const RATE: f64 = 30.0;
const TRIALS: usize = 20;
/// Shoulder positions the arm jumps between (rad); the palm moves ~15 cm.
const POSES: [f64; 2] = [-1.5, -1.2];
/// An attached vertex moving more than this shows the new joint state (m).
const MOVED: f64 = 0.01;
const JOINT: &str = "right_shoulder_pitch";

struct Row {
    res: usize,
    solver: Solver,
    dds: bool,
    latencies_ms: Vec<f64>,
    /// Clock time from the detecting message's stamp (the clock time of its state) to its arrival.
    age_ms: Vec<f64>,
    step_ms: String,
    rtf: String,
    /// The quality the node ran at in its last diagnostics (level, substeps, CG tolerance, cap).
    quality: String,
}

fn cloud_xyz(c: &PointCloud2, idx: &[usize]) -> Vec<[f32; 3]> {
    let step = c.point_step as usize;
    idx.iter()
        .map(|&i| {
            let f = |k: usize| {
                let o = i * step + 4 * k;
                c.data
                    .get(o..o + 4)
                    .and_then(|b| b.try_into().ok())
                    .map_or(f32::NAN, f32::from_le_bytes)
            };
            [f(0), f(1), f(2)]
        })
        .collect()
}

fn max_moved(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            let d: f32 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum();
            f64::from(d.sqrt())
        })
        .fold(0.0, f64::max)
}

fn diag(d: &DiagnosticArray, key: &str) -> String {
    d.status
        .first()
        .and_then(|s| s.values.iter().find(|kv| kv.key == key))
        .map_or_else(|| "?".into(), |kv| kv.value.clone())
}

/// Solver settings of a row.
#[derive(Clone, Copy, PartialEq)]
enum Solver {
    /// The scene's (two substeps, default CG), fixed (`adaptive_quality: false`).
    Scene,
    /// The node's adaptive quality (the default): the scene's settings lowered, within the
    /// default bounds (one substep, CG tolerance 1e-2, at most 50 iterations), as far as real
    /// time needs.
    Adaptive,
    /// Adaptive, with the scene's self-collision on (the self-collision latency row).
    AdaptiveSelf,
    /// The same with `joint_velocity_limits: false`: each jump reached in one step.
    AdaptiveSelfUnlimited,
}

/// How the bench talks to the simulation: through DDS (the real node), or straight to the
/// simulation thread over channels (the node's pipeline without DDS).
// One value per row: the size of the DDS variant does not matter.
#[allow(clippy::large_enum_variant)]
enum Link {
    Dds {
        stop: Arc<AtomicBool>,
        node: std::thread::JoinHandle<
            Result<drape::ros::node::NodeSummary, drape::ros::node::NodeError>,
        >,
        joints: ros2_client::Publisher<JointState>,
        points: ros2_client::Subscription<PointCloud2>,
        diags: ros2_client::Subscription<DiagnosticArray>,
        _ctx: ros2_client::Context,
        _peer: ros2_client::Node,
    },
    Direct {
        stop: Arc<AtomicBool>,
        sim: std::thread::JoinHandle<()>,
        cmd: mpsc::Sender<Command>,
        out: mpsc::Receiver<Output>,
        diags: Vec<DiagnosticArray>,
    },
}

impl Link {
    fn send(&self, s: f64) {
        match self {
            Link::Dds { joints, .. } => joints
                .publish(JointState {
                    header: Header::new(Time::default(), ""),
                    name: vec![JOINT.into()],
                    position: vec![s],
                    ..JointState::default()
                })
                .unwrap(),
            Link::Direct { cmd, .. } => cmd
                .send(Command::Joints {
                    stamp_ns: 0,
                    input: JointInput {
                        names: vec![JOINT.into()],
                        positions: vec![s],
                        velocities: None,
                    },
                })
                .unwrap(),
        }
    }

    fn clouds(&mut self) -> Vec<PointCloud2> {
        let mut v = Vec::new();
        match self {
            Link::Dds { points, .. } => {
                while let Ok(Some((c, _))) = points.take() {
                    v.push(c);
                }
            }
            Link::Direct { out, diags, .. } => {
                for o in out.try_iter() {
                    match o {
                        Output::Frame { points, .. } => v.push(*points),
                        Output::Diagnostics(d) => diags.push(d),
                        _ => {}
                    }
                }
            }
        }
        v
    }

    /// Stops the node; returns its last diagnostics.
    fn finish(mut self) -> Option<DiagnosticArray> {
        self.clouds();
        match self {
            Link::Dds {
                stop, node, diags, ..
            } => {
                let mut last = None;
                while let Ok(Some((d, _))) = diags.take() {
                    last = Some(d);
                }
                stop.store(true, Ordering::Relaxed);
                node.join().unwrap().unwrap();
                last
            }
            Link::Direct {
                stop,
                sim,
                mut diags,
                ..
            } => {
                stop.store(true, Ordering::Relaxed);
                sim.join().unwrap();
                diags.pop()
            }
        }
    }
}

fn scene_for(res: usize) -> Scene {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut scene = Scene::load(format!("{root}/config/robot_towel.yaml").as_ref()).unwrap();
    scene.cloths[0].grid.resolution = [res, res];
    // What `drape node` runs the scene with (the direct rows do not go through it).
    let levels = &mut scene.solver.guard.max_contact_split_levels;
    levels.get_or_insert(NodeParams::default().max_contact_split_levels);
    if let Some(r) = scene.robot.as_mut() {
        r.urdf = format!("{root}/urdf/drape_bot.urdf");
    }
    scene
}

fn dds_link(scene: &Scene, solver: Solver, dir: &std::path::Path) -> Link {
    let path = dir.join("scene.yaml");
    std::fs::write(&path, serde_yaml_ng::to_string(scene).unwrap()).unwrap();
    let params = NodeParams {
        scene: path,
        publish_rate: RATE,
        obstacles_rate: 0.0,
        adaptive_quality: solver != Solver::Scene,
        joint_velocity_limits: solver != Solver::AdaptiveSelfUnlimited,
        ..NodeParams::default()
    };
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let node = std::thread::spawn(move || run_node(&params, flag));

    let ctx = context(Network::default()).unwrap();
    let mut peer = ctx
        .new_node(
            NodeName::new("/", "bench").unwrap(),
            NodeOptions::new().enable_rosout(false),
        )
        .unwrap();
    let q = QosProfile::publisher_default().history(History::KeepLast { depth: 10 });
    let topic = |peer: &mut ros2_client::Node, name: &str, pkg: &str, ty: &str| {
        peer.create_topic(
            &Name::parse(name).unwrap(),
            MessageTypeName::new(pkg, ty),
            &q,
        )
        .unwrap()
    };
    let jt = topic(&mut peer, "/joint_states", "sensor_msgs", "JointState");
    let pt = topic(&mut peer, "/drape/points", "sensor_msgs", "PointCloud2");
    let dt = topic(
        &mut peer,
        "/diagnostics",
        "diagnostic_msgs",
        "DiagnosticArray",
    );
    let joints = peer
        .create_publisher::<JointState>(&jt, Some(q.clone()))
        .unwrap();
    let deep = q.clone().history(History::KeepLast { depth: 30 });
    let points = peer
        .create_subscription::<PointCloud2>(&pt, Some(deep.clone()))
        .unwrap();
    let diags = peer
        .create_subscription::<DiagnosticArray>(&dt, Some(deep))
        .unwrap();
    Link::Dds {
        stop,
        node,
        joints,
        points,
        diags,
        _ctx: ctx,
        _peer: peer,
    }
}

fn direct_link(scene: Scene, solver: Solver) -> Link {
    let wall = WallClock::new();
    let cfg = LoopConfig {
        publish_rate: RATE,
        obstacles_rate: 0.0,
        quality: (solver != Solver::Scene).then(QualityBounds::default),
        joint_velocity_limits: solver != Solver::AdaptiveSelfUnlimited,
        ..LoopConfig::default()
    };
    let core = SimLoop::new(scene, cfg, wall.now()).unwrap();
    let (cmd, rx) = mpsc::channel();
    let (tx, out) = mpsc::channel();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let sim = std::thread::spawn(move || thread::run(core, ClockMode::Wall, wall, rx, tx, &flag));
    Link::Direct {
        stop,
        sim,
        cmd,
        out,
        diags: Vec::new(),
    }
}

fn unix_now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

fn measure(res: usize, solver: Solver, dds: bool) -> Row {
    let mut scene = scene_for(res);
    scene.collision.self_collision =
        matches!(solver, Solver::AdaptiveSelf | Solver::AdaptiveSelfUnlimited);
    let attached: Vec<usize> = scene
        .build()
        .unwrap()
        .cloth
        .kinematic
        .iter()
        .filter(|(_, k)| matches!(k, Kinematic::Attached { .. }))
        .map(|(v, _)| *v as usize)
        .collect();
    assert!(!attached.is_empty());
    let dir = tempfile::tempdir().unwrap();
    let mut link = if dds {
        dds_link(&scene, solver, dir.path())
    } else {
        direct_link(scene, solver)
    };

    // Hold the first pose while discovery completes and the towel settles.
    let mut last: Option<Vec<[f32; 3]>> = None;
    let settle = Instant::now();
    while settle.elapsed() < Duration::from_secs(3) {
        link.send(POSES[0]);
        for c in link.clouds() {
            last = Some(cloud_xyz(&c, &attached));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(last.is_some(), "no ~/points from the node");
    let mut latencies_ms = Vec::new();
    let mut age_ms = Vec::new();
    for trial in 0..TRIALS {
        let target = POSES[(trial + 1) % 2];
        let before = last.clone().unwrap_or_default();
        let sent = Instant::now();
        link.send(target);
        let mut next_send = sent + Duration::from_millis(20);
        let mut seen = false;
        // Keep streaming the new pose at 50 Hz, like a joint_state_publisher.
        while sent.elapsed() < Duration::from_millis(700) {
            for c in link.clouds() {
                let xyz = cloud_xyz(&c, &attached);
                if !seen && max_moved(&xyz, &before) > MOVED {
                    latencies_ms.push(sent.elapsed().as_secs_f64() * 1e3);
                    age_ms.push((unix_now() - c.header.stamp.as_nanos() as f64 * 1e-9) * 1e3);
                    seen = true;
                }
                last = Some(xyz);
            }
            if Instant::now() >= next_send {
                link.send(target);
                next_send += Duration::from_millis(20);
            }
            std::thread::sleep(Duration::from_micros(500));
        }
    }
    let last_diag = link.finish();
    let (step_ms, rtf, quality) = last_diag.map_or(("?".into(), "?".into(), "?".into()), |d| {
        let quality = format!(
            "{} ({} substeps, CG {}, cap {}){}",
            diag(&d, "quality_level"),
            diag(&d, "quality_substeps"),
            // Three digits: the diagnostics' exact decimal reads like a hash in a report.
            (diag(&d, "quality_cg_tolerance").parse::<f64>())
                .map_or_else(|_| "?".to_string(), |t| format!("{t:.2e}")),
            diag(&d, "quality_cg_max_iterations"),
            match diag(&d, "real_time_factor_at_lowest_quality").as_str() {
                "n/a" | "?" => String::new(),
                f => format!(", short of real time: factor {f} at the lowest"),
            }
        );
        (
            diag(&d, "step_time_mean_ms"),
            diag(&d, "real_time_factor"),
            quality,
        )
    });
    Row {
        res,
        solver,
        dds,
        latencies_ms,
        age_ms,
        step_ms,
        rtf,
        quality,
    }
}

impl std::fmt::Display for Solver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Solver::Scene => "scene",
            Solver::Adaptive => "adaptive",
            Solver::AdaptiveSelf => "adaptive, self-collision",
            Solver::AdaptiveSelfUnlimited => "adaptive, self-collision, no velocity limits",
        })
    }
}

/// Rows: DDS (the node as users run it) and the same pipeline without DDS (channels straight to the
/// simulation thread), which separates the node's own latency from the middleware's.
/// `DRAPE_LATENCY_ROWS=direct` runs only the latter (quick iterations on the pipeline), `self`
/// only the self-collision row.
fn main() {
    if !netns::enter("node_latency") {
        return;
    }
    let rows = std::env::var("DRAPE_LATENCY_ROWS").unwrap_or_default();
    let mut plan = Vec::new();
    if rows == "self" {
        plan.push((64, Solver::AdaptiveSelf, true));
    } else if rows != "direct" {
        plan.extend([
            (24, Solver::Scene, true),
            (64, Solver::Scene, true),
            (64, Solver::Adaptive, true),
            (64, Solver::AdaptiveSelf, true),
            (64, Solver::AdaptiveSelfUnlimited, true),
        ]);
    }
    if rows != "self" {
        plan.extend([(24, Solver::Scene, false), (64, Solver::Adaptive, false)]);
    }
    let rows: Vec<Row> = plan
        .into_iter()
        .map(|(res, solver, dds)| measure(res, solver, dds))
        .collect();
    let period = 1e3 / RATE;
    println!("\nnode latency: joint state -> first ~/points showing it ({RATE} Hz, {TRIALS} steps of the arm)");
    println!("| cloth | solver | via | seen | median ms | p90 ms | max ms | median / max in publish periods | state age at arrival, median ms | step ms | real-time factor | quality level (settings) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let sorted = |v: &[f64]| {
            let mut v = v.to_vec();
            v.sort_by(f64::total_cmp);
            v
        };
        let (l, a) = (sorted(&r.latencies_ms), sorted(&r.age_ms));
        let at = |v: &[f64], q: f64| {
            v.get(((v.len() as f64 - 1.0) * q).round() as usize)
                .copied()
                .unwrap_or(f64::NAN)
        };
        println!(
            "| {0}x{0} | {1} | {2} | {3}/{TRIALS} | {4:.1} | {5:.1} | {6:.1} | {7:.2} / {8:.2} | {9:.1} | {10} | {11} | {12} |",
            r.res,
            r.solver,
            if r.dds { "DDS" } else { "direct" },
            l.len(),
            at(&l, 0.5),
            at(&l, 0.9),
            at(&l, 1.0),
            at(&l, 0.5) / period,
            at(&l, 1.0) / period,
            at(&a, 0.5),
            r.step_ms,
            r.rtf,
            r.quality,
        );
    }
}
