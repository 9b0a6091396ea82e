//! Latency of the live node: from a joint-state message to the first `~/points` message that
//! shows it (the cloth vertices attached to the moving link have moved), on drape_bot holding
//! the towel of config/robot_towel.yaml at 24x24 and 64x64 vertices, published at 30 Hz.
//!
//! Runs DDS, so it re-executes itself inside a private network namespace (root, iproute2):
//! `cargo bench --bench node_latency`. Prints a table.

#[path = "../tests/support/netns.rs"]
mod netns;

use drape::cloth::Kinematic;
use drape::ros::msg::{DiagnosticArray, Header, JointState, PointCloud2, Time};
use drape::ros::node::{context, run_node, Network, NodeParams};
use drape::scene::Scene;
use ros2_client::qos::History;
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

const RATE: f64 = 30.0;
const TRIALS: usize = 20;
/// Shoulder positions the arm jumps between (rad); the palm moves ~15 cm.
const POSES: [f64; 2] = [-1.5, -1.2];
/// An attached vertex moving more than this shows the new joint state (m).
const MOVED: f64 = 0.01;

struct Row {
    res: usize,
    solver: &'static str,
    latencies_ms: Vec<f64>,
    step_ms: String,
    rtf: String,
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

/// `preview`: the README's real-time preview solver settings (one substep, CG tolerance 1e-2,
/// at most 50 iterations) instead of the scene's (two substeps, default CG).
fn measure(res: usize, preview: bool) -> Row {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut scene = Scene::load(format!("{root}/config/robot_towel.yaml").as_ref()).unwrap();
    scene.cloths[0].grid.resolution = [res, res];
    if preview {
        scene.solver.substeps = 1;
        scene.solver.cg_tolerance = 1e-2;
        scene.solver.cg_max_iterations = 50;
    }
    if let Some(r) = scene.robot.as_mut() {
        r.urdf = format!("{root}/urdf/drape_bot.urdf");
    }
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
    let path = dir.path().join("scene.yaml");
    std::fs::write(&path, serde_yaml_ng::to_string(&scene).unwrap()).unwrap();
    let params = NodeParams {
        scene: path,
        publish_rate: RATE,
        obstacles_rate: 0.0,
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
    let topic = |name: &str, pkg: &str, ty: &str| {
        peer.create_topic(
            &Name::parse(name).unwrap(),
            MessageTypeName::new(pkg, ty),
            &q,
        )
        .unwrap()
    };
    let (jt, pt, dt) = (
        topic("/joint_states", "sensor_msgs", "JointState"),
        topic("/drape/points", "sensor_msgs", "PointCloud2"),
        topic("/diagnostics", "diagnostic_msgs", "DiagnosticArray"),
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
    let send = |s: f64| {
        joints
            .publish(JointState {
                header: Header::new(Time::default(), ""),
                name: vec!["right_shoulder_pitch".into()],
                position: vec![s],
                ..JointState::default()
            })
            .unwrap();
    };

    // Hold the first pose while discovery completes and the towel settles.
    let mut last: Option<Vec<[f32; 3]>> = None;
    let settle = Instant::now();
    while settle.elapsed() < Duration::from_secs(3) {
        send(POSES[0]);
        while let Ok(Some((c, _))) = points.take() {
            last = Some(cloud_xyz(&c, &attached));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(last.is_some(), "no ~/points from the node");
    let mut latencies_ms = Vec::new();
    for trial in 0..TRIALS {
        let target = POSES[(trial + 1) % 2];
        let before = last.clone().unwrap_or_default();
        let sent = Instant::now();
        send(target);
        let mut next_send = sent + Duration::from_millis(20);
        let mut seen = false;
        // Keep streaming the new pose at 50 Hz, like a joint_state_publisher.
        while sent.elapsed() < Duration::from_millis(700) {
            while let Ok(Some((c, _))) = points.take() {
                let xyz = cloud_xyz(&c, &attached);
                if !seen && max_moved(&xyz, &before) > MOVED {
                    latencies_ms.push(sent.elapsed().as_secs_f64() * 1e3);
                    seen = true;
                }
                last = Some(xyz);
            }
            if Instant::now() >= next_send {
                send(target);
                next_send += Duration::from_millis(20);
            }
            std::thread::sleep(Duration::from_micros(500));
        }
    }
    let mut last_diag = None;
    while let Ok(Some((d, _))) = diags.take() {
        last_diag = Some(d);
    }
    stop.store(true, Ordering::Relaxed);
    node.join().unwrap().unwrap();
    let (step_ms, rtf) = last_diag.map_or(("?".into(), "?".into()), |d| {
        (diag(&d, "step_time_mean_ms"), diag(&d, "real_time_factor"))
    });
    Row {
        res,
        solver: if preview { "preview" } else { "scene" },
        latencies_ms,
        step_ms,
        rtf,
    }
}

fn main() {
    if !netns::enter("node_latency") {
        return;
    }
    let rows: Vec<Row> = [(24, false), (64, false), (64, true)]
        .into_iter()
        .map(|(res, preview)| measure(res, preview))
        .collect();
    let period = 1e3 / RATE;
    println!("\nnode latency: joint state -> first ~/points showing it ({RATE} Hz, {TRIALS} steps of the arm)");
    println!("| cloth | solver | seen | median ms | p90 ms | max ms | median / max in publish periods | step ms | real-time factor |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let mut l = r.latencies_ms.clone();
        l.sort_by(f64::total_cmp);
        let at = |q: f64| {
            l.get(((l.len() as f64 - 1.0) * q).round() as usize)
                .copied()
                .unwrap_or(f64::NAN)
        };
        println!(
            "| {0}x{0} | {9} | {1}/{TRIALS} | {2:.1} | {3:.1} | {4:.1} | {5:.2} / {6:.2} | {7} | {8} |",
            r.res,
            l.len(),
            at(0.5),
            at(0.9),
            at(1.0),
            at(0.5) / period,
            at(1.0) / period,
            r.step_ms,
            r.rtf,
            r.solver
        );
    }
}
