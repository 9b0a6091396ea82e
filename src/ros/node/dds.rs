//! The DDS side of the node (ros2-client over RustDDS): subscriptions feed commands to the
//! simulation thread, its outputs are published here, services and parameters are served
//! here. Nothing in this file does physics.

use super::clock::{ClockMode, WallClock};
use super::config::LoopConfig;
use super::endpoints::{context, endpoints, Endpoints};
use super::messages::{Command, Level, Output};
use super::network::Network;
use super::params::{positive_rate, NodeParams};
use super::sim_loop::SimLoop;
use super::NodeError;
use crate::robot::JointInput;
use crate::ros::msg::TriggerResponse;
use crate::ros::Distro;
use crate::scene::Scene;
use ros2_client::log::LogLevel;
use ros2_client::{
    NodeLoggingHandle, NodeName, NodeOptions, ParameterValue, RmwRequestId, RosoutRaw,
};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long the DDS loop waits for simulation output before polling inputs again.
const POLL: Duration = Duration::from_millis(2);
/// At most this many samples are taken from one reader per poll (a flood cannot starve the
/// rest of the loop).
const MAX_TAKE: usize = 256;

/// What a node run did, reported after shutdown.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NodeSummary {
    pub frames_published: u64,
    pub joint_states_received: u64,
}

/// Polls `f` on a thread to completion (the spinner's futures are woken by RustDDS threads,
/// so a parking executor is all they need).
fn block_on<F: std::future::Future>(f: F) -> F::Output {
    use std::task::{Context as TaskContext, Poll, Wake, Waker};
    struct Unpark(std::thread::Thread);
    impl Wake for Unpark {
        fn wake(self: Arc<Self>) {
            self.0.unpark();
        }
    }
    let waker = Waker::from(Arc::new(Unpark(std::thread::current())));
    let mut cx = TaskContext::from_waker(&waker);
    let mut f = std::pin::pin!(f);
    loop {
        match f.as_mut().poll(&mut cx) {
            Poll::Ready(v) => return v,
            Poll::Pending => std::thread::park_timeout(Duration::from_millis(100)),
        }
    }
}

/// Parameters served through ros2-client's parameter services. Live: `publish_rate`,
/// `paused`, and `wind` (constant air velocity `[x, y, z]` m/s) when the scene names wind; the
/// others are read-only and reject changes.
fn node_options(p: &NodeParams, wind: Option<[f64; 3]>, cmd: Sender<Command>) -> NodeOptions {
    let read_only: Vec<(&'static str, ParameterValue)> = vec![
        ("use_sim_time", ParameterValue::Boolean(p.use_sim_time)),
        (
            "scene",
            ParameterValue::String(p.scene.display().to_string()),
        ),
        ("frame_id", ParameterValue::String(p.frame_id.clone())),
    ];
    let mut o = NodeOptions::new()
        .enable_rosout(true)
        .start_parameter_services(true)
        .declare_parameter("publish_rate", ParameterValue::Double(p.publish_rate))
        .declare_parameter("paused", ParameterValue::Boolean(p.paused));
    if let Some(w) = wind {
        o = o.declare_parameter("wind", ParameterValue::DoubleArray(w.to_vec()));
    }
    for (k, v) in &read_only {
        o = o.declare_parameter(k, v.clone());
    }
    let validator = move |name: &str, value: &ParameterValue| -> Result<(), String> {
        match (name, value) {
            ("publish_rate", ParameterValue::Double(r)) => positive_rate(*r),
            ("publish_rate", ParameterValue::Integer(r)) => positive_rate(*r as f64),
            ("publish_rate", _) => Err("publish_rate must be a number".into()),
            ("paused", ParameterValue::Boolean(_)) => Ok(()),
            ("paused", _) => Err("paused must be a boolean".into()),
            ("wind", ParameterValue::DoubleArray(v)) if wind.is_some() => {
                wind_velocity(v).map(|_| ())
            }
            ("wind", _) if wind.is_some() => Err("wind must be [x, y, z] in m/s".into()),
            ("wind", _) => Err("the scene names no wind effect".into()),
            _ => match read_only.iter().find(|(k, _)| *k == name) {
                Some((_, v)) if v == value => Ok(()),
                Some(_) => Err(format!(
                    "{name} is read-only; restart the node to change it"
                )),
                None => Err(format!("unknown parameter {name}")),
            },
        }
    };
    let action = move |name: &str, value: &ParameterValue| -> Result<(), String> {
        let c = match (name, value) {
            ("publish_rate", ParameterValue::Double(r)) => Command::PublishRate(*r),
            ("publish_rate", ParameterValue::Integer(r)) => Command::PublishRate(*r as f64),
            ("paused", ParameterValue::Boolean(b)) => Command::Pause(*b),
            ("wind", ParameterValue::DoubleArray(v)) => Command::Wind(wind_velocity(v)?),
            _ => return Ok(()),
        };
        cmd.send(c)
            .map_err(|_| "the simulation has stopped".to_string())
    };
    o.parameter_validator(Box::new(validator))
        .parameter_set_action(Box::new(action))
}

/// A wind parameter value: three finite numbers (m/s).
fn wind_velocity(v: &[f64]) -> Result<[f64; 3], String> {
    match v {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(format!(
            "wind must be three finite numbers [x, y, z] in m/s, got {v:?}"
        )),
    }
}

/// Logs to the process log and `/rosout`, both.
fn rosout(h: &NodeLoggingHandle, level: Level, text: &str) {
    let l = match level {
        Level::Info => {
            log::info!("{text}");
            LogLevel::Info
        }
        Level::Warn => {
            log::warn!("{text}");
            LogLevel::Warn
        }
        Level::Error => {
            log::error!("{text}");
            LogLevel::Error
        }
    };
    h.rosout_raw(
        ros2_client::builtin_interfaces::Time::now(),
        l,
        h.base_name(),
        text,
        file!(),
        "drape::node",
        line!(),
    );
}

/// Warns about a failing DDS call once a second at most.
struct Throttle {
    last: Option<Instant>,
    suppressed: u64,
}

impl Throttle {
    fn new() -> Self {
        Self {
            last: None,
            suppressed: 0,
        }
    }

    fn warn(&mut self, text: impl FnOnce() -> String) {
        if self
            .last
            .is_some_and(|t| t.elapsed() < Duration::from_secs(1))
        {
            self.suppressed += 1;
            return;
        }
        let n = std::mem::take(&mut self.suppressed);
        log::warn!(
            "{}{}",
            text(),
            if n > 0 {
                format!(" ({n} more suppressed)")
            } else {
                String::new()
            }
        );
        self.last = Some(Instant::now());
    }
}

/// Runs the node until `stop` is set (Ctrl-C / SIGTERM) or the simulation thread ends.
pub fn run_node(params: &NodeParams, stop: Arc<AtomicBool>) -> Result<NodeSummary, NodeError> {
    let distro = match params.distro {
        Some(d) => d,
        None => Distro::from_env()?,
    };
    let mut scene = Scene::load(&params.scene)?;
    scene.package_paths = params.package_paths.clone();
    if !params.robot_description.trim().is_empty() {
        if scene.robot.is_none() {
            return Err(NodeError::DescriptionWithoutRobot {
                scene: params.scene.clone(),
            });
        }
        scene.robot_urdf_text = Some(params.robot_description.clone());
    }
    let levels = &mut scene.solver.guard.max_contact_split_levels;
    levels.get_or_insert(params.max_contact_split_levels);
    let net = Network::from_env()?;
    let wall = WallClock::new();
    let cfg = LoopConfig {
        name: params.name.clone(),
        distro,
        frame_id: params.frame_id.clone(),
        publish_rate: params.publish_rate,
        obstacles_rate: params.obstacles_rate,
        diagnostics_rate: params.diagnostics_rate,
        max_backlog_steps: params.max_backlog_steps,
        joint_velocity_limits: params.joint_velocity_limits,
        paused: params.paused,
        color: params.color,
        quality: params.adaptive_quality.then_some(params.quality),
    };
    let wind = scene
        .wind
        .as_ref()
        .filter(|_| scene.has(crate::scene::EffectKind::Wind))
        .map(|w| w.velocity.to_array());
    let core = SimLoop::new(scene, cfg, wall.now())?;
    let q = core.quality();
    match core.quality_ladder().last().filter(|_| q.adaptive) {
        Some(low) => log::info!(
            "adaptive quality: from the scene's ({}) down to ({low}) in {} levels, as far as \
             real time needs",
            q.quality,
            q.levels
        ),
        None => log::info!("quality fixed at the scene's ({})", q.quality),
    }
    log::info!(
        "drape node: scene {} ({} vertices), frame `{}`, {} Hz, {} layout, domain {}{}{}",
        params.scene.display(),
        core.simulation().cloth.len(),
        core.frame_id(),
        params.publish_rate,
        distro,
        net.domain_id,
        if net.localhost_only {
            ", localhost only"
        } else {
            ""
        },
        if params.use_sim_time {
            ", sim time from /clock"
        } else {
            ""
        },
    );

    let (cmd_tx, cmd_rx) = mpsc::channel::<Command>();
    let (out_tx, out_rx) = mpsc::channel::<Output>();
    let ctx = context(net)?;
    let node_name =
        NodeName::new(&params.namespace, &params.name).map_err(|source| NodeError::NodeName {
            name: params.name.clone(),
            namespace: params.namespace.clone(),
            source,
        })?;
    let mut node = ctx
        .new_node(node_name, node_options(params, wind, cmd_tx.clone()))
        .map_err(|source| NodeError::Node {
            name: params.name.clone(),
            source,
        })?;
    let spinner = node.spinner().map_err(NodeError::Spinner)?;
    let spin_thread = std::thread::Builder::new()
        .name("drape-spin".into())
        .spawn(move || {
            if let Err(e) = block_on(spinner.spin()) {
                log::warn!("ROS spinner ended: {e:?}");
            }
        })
        .map_err(|source| NodeError::Thread {
            thread: "ROS spinner",
            source,
        })?;
    let ep = endpoints(&mut node, params)?;
    let logger = node.logging_handle();

    let mode = if params.use_sim_time {
        ClockMode::Sim
    } else {
        ClockMode::Wall
    };
    let sim_stop = Arc::new(AtomicBool::new(false));
    let sim_flag = sim_stop.clone();
    let sim_thread = std::thread::Builder::new()
        .name("drape-sim".into())
        .spawn(move || super::thread::run(core, mode, wall, cmd_rx, out_tx, &sim_flag))
        .map_err(|source| NodeError::Thread {
            thread: "simulation",
            source,
        })?;

    let result = serve(&ep, &logger, &cmd_tx, &out_rx, &stop);
    // Shut down: the simulation thread first (it may be mid-step), then DDS.
    sim_stop.store(true, Ordering::Relaxed);
    let _ = cmd_tx.send(Command::Stop);
    drop(out_rx);
    if sim_thread.join().is_err() {
        log::error!("the simulation thread panicked");
    }
    // RustDDS logs errors about sockets and entities it tears down in its own order; they
    // say nothing about the run, so the teardown is quiet.
    let level = log::max_level();
    log::set_max_level(log::LevelFilter::Off);
    drop(ep);
    drop(logger);
    drop(node);
    let _ = spin_thread.join();
    drop(ctx);
    log::set_max_level(level);
    result
}

/// The DDS loop: inputs to commands, outputs to publishers, service requests.
fn serve(
    ep: &Endpoints,
    logger: &NodeLoggingHandle,
    cmd: &Sender<Command>,
    out: &Receiver<Output>,
    stop: &AtomicBool,
) -> Result<NodeSummary, NodeError> {
    let mut summary = NodeSummary::default();
    let mut pending_resets: HashMap<u64, (bool, RmwRequestId)> = HashMap::new();
    let mut next_reset = 0u64;
    let mut read_warn = Throttle::new();
    let mut write_warn = Throttle::new();
    let send = |c: Command| cmd.send(c).map_err(|_| NodeError::SimulationStopped);
    while !stop.load(Ordering::Relaxed) {
        // Inputs.
        for _ in 0..MAX_TAKE {
            match ep.joint_states.take() {
                Ok(Some((m, _))) => {
                    summary.joint_states_received += 1;
                    send(Command::Joints {
                        stamp_ns: m.header.stamp.as_nanos(),
                        input: JointInput {
                            names: m.name,
                            positions: m.position,
                            velocities: (!m.velocity.is_empty()).then_some(m.velocity),
                        },
                    })?;
                }
                Ok(None) => break,
                Err(e) => read_warn.warn(|| format!("joint_states: undecodable sample: {e:?}")),
            }
        }
        if let Some(s) = &ep.description {
            for _ in 0..MAX_TAKE {
                match s.take() {
                    Ok(Some((m, _))) => send(Command::RobotDescription(m.data))?,
                    Ok(None) => break,
                    Err(e) => {
                        read_warn.warn(|| format!("robot_description: undecodable sample: {e:?}"))
                    }
                }
            }
        }
        if let Some(s) = &ep.clock {
            let mut latest = None;
            for _ in 0..MAX_TAKE {
                match s.take() {
                    Ok(Some((m, _))) => latest = Some(m.clock),
                    Ok(None) => break,
                    Err(e) => read_warn.warn(|| format!("clock: undecodable sample: {e:?}")),
                }
            }
            if let Some(t) = latest {
                send(Command::Clock(t.as_nanos() as f64 * 1e-9))?;
            }
        }
        // Services.
        while let Ok(Some((id, _))) = ep.reset.receive_request() {
            pending_resets.insert(next_reset, (true, id));
            send(Command::Reset { id: next_reset })?;
            next_reset += 1;
        }
        for (srv, paused) in [(&ep.pause, true), (&ep.resume, false)] {
            while let Ok(Some((id, _))) = srv.receive_request() {
                send(Command::Pause(paused))?;
                let r = TriggerResponse {
                    success: true,
                    message: if paused { "paused" } else { "running" }.into(),
                };
                if let Err(e) = srv.send_response(id, r) {
                    write_warn.warn(|| format!("pause/resume response: {e:?}"));
                }
            }
        }
        // Outputs, waiting briefly for the next one.
        let first = match out.recv_timeout(POLL) {
            Ok(o) => Some(o),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => return Err(NodeError::SimulationStopped),
        };
        for o in first.into_iter().chain(out.try_iter()) {
            let r = match o {
                Output::Frame { mesh, points } => {
                    summary.frames_published += 1;
                    let a = ep.mesh.publish(*mesh).map_err(|e| format!("mesh: {e:?}"));
                    let b = ep
                        .points
                        .publish(*points)
                        .map_err(|e| format!("points: {e:?}"));
                    a.and(b)
                }
                Output::Obstacles(m) => ep
                    .obstacles
                    .publish(m)
                    .map_err(|e| format!("obstacles: {e:?}")),
                Output::Diagnostics(d) => ep
                    .diagnostics
                    .publish(d)
                    .map_err(|e| format!("diagnostics: {e:?}")),
                Output::Log { level, text } => {
                    rosout(logger, level, &text);
                    Ok(())
                }
                Output::ResetDone { id, result } => {
                    let Some((_, req)) = pending_resets.remove(&id) else {
                        continue;
                    };
                    let (success, message) = match result {
                        Ok(m) => (true, m),
                        Err(e) => (false, crate::input::error_line(&*e)),
                    };
                    ep.reset
                        .send_response(req, TriggerResponse { success, message })
                        .map_err(|e| format!("reset response: {e:?}"))
                }
            };
            if let Err(e) = r {
                write_warn.warn(|| format!("publish failed: {e}"));
            }
        }
    }
    Ok(summary)
}
