//! The simulation side of the node: owns the scene, the simulation and the robot; takes
//! commands (joint states, clock ticks, robot descriptions, reset, pause) and emits
//! ready-to-publish messages at fixed rates. No DDS here, so all of it runs in tests with a
//! synthetic clock.

use super::outputs::{diagnostics, obstacle_markers, DiagnosticsInput};
use super::pacer::{Pacer, Schedule};
use crate::robot::{JointInput, JointInputError, JointPositions, JointSource, RobotDriver};
use crate::ros::msg::{ColorRGBA, DiagnosticArray, Marker, MarkerArray, PointCloud2, Time};
use crate::ros::{mesh_marker, point_cloud, Distro};
use crate::scene::{Scene, SceneError};
use crate::sim::Simulation;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

/// Seconds over which the robot moves from its initial pose to the last commanded one after a
/// reset, so attached cloth is carried, not torn.
const RESET_BLEND_S: f64 = 0.5;

/// Something for the simulation thread to do.
#[derive(Debug, Clone)]
pub enum Command {
    /// A joint state: its header stamp (0: unstamped) and content.
    Joints {
        stamp_ns: i64,
        input: JointInput,
    },
    /// A URDF (e.g. from `/robot_description`): rebuild the scene with this robot.
    RobotDescription(String),
    /// Simulated clock time (s) from `/clock`; ignored on the wall clock.
    Clock(f64),
    /// Restore the initial cloth; answered by [`Output::ResetDone`] with the same id.
    Reset {
        id: u64,
    },
    Pause(bool),
    PublishRate(f64),
    /// New constant wind velocity (m/s) for a scene that names wind; kept across resets.
    Wind([f64; 3]),
    Stop,
}

/// Log severity of an [`Output::Log`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    Info,
    Warn,
    Error,
}

/// Something for the DDS side to publish.
#[derive(Debug, Clone)]
pub enum Output {
    Frame {
        mesh: Box<Marker>,
        points: Box<PointCloud2>,
    },
    Obstacles(MarkerArray),
    Diagnostics(DiagnosticArray),
    Log {
        level: Level,
        text: String,
    },
    ResetDone {
        id: u64,
        result: Result<String, String>,
    },
}

/// How the loop publishes.
#[derive(Debug, Clone)]
pub struct LoopConfig {
    /// Node name: diagnostics status name and marker namespace.
    pub name: String,
    pub distro: Distro,
    /// Empty: the robot's root link, else `world`.
    pub frame_id: String,
    pub publish_rate: f64,
    /// 0: no obstacle markers.
    pub obstacles_rate: f64,
    pub diagnostics_rate: f64,
    pub max_backlog_steps: u32,
    pub paused: bool,
    pub color: [f32; 4],
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            name: "drape".into(),
            distro: Distro::Jazzy,
            frame_id: String::new(),
            publish_rate: 30.0,
            obstacles_rate: 2.0,
            diagnostics_rate: 1.0,
            max_backlog_steps: 6,
            paused: false,
            color: [0.85, 0.35, 0.2, 1.0],
        }
    }
}

/// Why joint states were dropped, counted per reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DroppedInputs {
    pub non_finite: u64,
    pub wrong_length: u64,
    pub unknown_joint: u64,
    pub out_of_order: u64,
    /// Duplicate names, free joints, or no robot in the scene.
    pub other: u64,
}

impl DroppedInputs {
    pub fn total(&self) -> u64 {
        self.non_finite + self.wrong_length + self.unknown_joint + self.out_of_order + self.other
    }
}

/// Running totals since start.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoopStats {
    pub steps: u64,
    pub frames: u64,
    pub joint_states: u64,
    pub dropped: DroppedInputs,
    pub divergences: u64,
    pub descriptions_loaded: u64,
    pub description_failures: u64,
    pub resets: u64,
}

/// Measurements since the last diagnostics message.
#[derive(Debug, Clone, Default)]
struct Window {
    clock_start: f64,
    sim_start: f64,
    steps: u64,
    step_time_sum: f64,
    step_time_max: f64,
    deepest_penetration: f64,
    dropped_at_start: u64,
    divergences_at_start: u64,
}

/// The simulation thread's state machine. Drive it with [`SimLoop::handle`] and
/// [`SimLoop::tick`] (or [`run`] on a thread).
pub struct SimLoop {
    scene: Scene,
    cfg: LoopConfig,
    sim: Simulation,
    driver: Option<RobotDriver>,
    frame_id: String,
    commanded: Option<JointPositions>,
    /// A changed joint command arrived that no step has reached yet.
    fresh_command: bool,
    last_stamp: Option<i64>,
    pacer: Pacer,
    publish: Schedule,
    obstacles: Option<Schedule>,
    diagnostics: Schedule,
    paused: bool,
    stats: LoopStats,
    window: Window,
    contacts: usize,
    energy: f64,
}

impl SimLoop {
    /// Builds the scene; simulation time 0 is clock time `now`. The robot holds the scene's
    /// t = 0 pose until joint states arrive (its scripted trajectory is not used).
    pub fn new(scene: Scene, mut cfg: LoopConfig, now: f64) -> Result<SimLoop, SceneError> {
        // Rates come validated from the parameters; a bad one from elsewhere falls back.
        let defaults = LoopConfig::default();
        for (rate, default) in [
            (&mut cfg.publish_rate, defaults.publish_rate),
            (&mut cfg.diagnostics_rate, defaults.diagnostics_rate),
        ] {
            if super::params::positive_rate(*rate).is_err() {
                log::warn!("rate {rate} Hz is unusable; using {default} Hz");
                *rate = default;
            }
        }
        if !(cfg.obstacles_rate.is_finite() && cfg.obstacles_rate >= 0.0) {
            cfg.obstacles_rate = 0.0;
        }
        let (sim, driver) = scene.build_with_robot()?;
        let dt = sim.settings.dt;
        let mut s = SimLoop {
            pacer: Pacer::new(dt, cfg.max_backlog_steps, now),
            publish: Schedule::new(cfg.publish_rate, now),
            obstacles: (cfg.obstacles_rate > 0.0).then(|| Schedule::new(cfg.obstacles_rate, now)),
            diagnostics: Schedule::new(cfg.diagnostics_rate, now + 1.0 / cfg.diagnostics_rate),
            paused: cfg.paused,
            frame_id: String::new(),
            scene,
            cfg,
            sim,
            driver: None,
            commanded: None,
            fresh_command: false,
            last_stamp: None,
            stats: LoopStats::default(),
            window: Window {
                clock_start: now,
                ..Window::default()
            },
            contacts: 0,
            energy: 0.0,
        };
        s.install_robot(driver);
        Ok(s)
    }

    pub fn simulation(&self) -> &Simulation {
        &self.sim
    }

    pub fn driver(&self) -> Option<&RobotDriver> {
        self.driver.as_ref()
    }

    pub fn stats(&self) -> &LoopStats {
        &self.stats
    }

    pub fn frame_id(&self) -> &str {
        &self.frame_id
    }

    pub fn paused(&self) -> bool {
        self.paused
    }

    /// Steps forgiven by the backlog policy.
    pub fn dropped_steps(&self) -> u64 {
        self.pacer.dropped_steps()
    }

    /// Clock time that output stamps are based on: the clock time of the current state.
    pub fn clock_of_state(&self) -> f64 {
        self.pacer.clock_of(self.sim.time())
    }

    /// Re-anchors every schedule at clock time `now` (first `/clock` message, or clock jump).
    pub fn sync_clock(&mut self, now: f64) {
        self.pacer.hold(now, self.sim.time());
        self.publish = Schedule::new(self.cfg.publish_rate, now);
        if let Some(o) = &mut self.obstacles {
            *o = Schedule::new(self.cfg.obstacles_rate, now);
        }
        self.diagnostics = Schedule::new(
            self.cfg.diagnostics_rate,
            now + 1.0 / self.cfg.diagnostics_rate,
        );
        self.start_window(now);
    }

    /// Clock time of the next thing to do.
    pub fn next_wake(&self) -> f64 {
        let mut t = self.publish.next().min(self.diagnostics.next());
        if let Some(o) = &self.obstacles {
            t = t.min(o.next());
        }
        if !self.paused {
            t = t.min(self.pacer.next_due(self.sim.time()));
        }
        t
    }

    /// Applies one command at clock time `now`. Returns false for [`Command::Stop`].
    pub fn handle(&mut self, cmd: Command, now: f64, out: &mut Vec<Output>) -> bool {
        match cmd {
            Command::Joints { stamp_ns, input } => self.on_joints(stamp_ns, &input, out),
            Command::RobotDescription(urdf) => self.on_description(urdf, now, out),
            Command::Clock(_) => {}
            Command::Reset { id } => {
                let result = self.rebuild(now).map(|()| {
                    self.stats.resets += 1;
                    "cloth restored to its initial state".to_string()
                });
                let result = result.map_err(|e| e.to_string());
                if let Err(e) = &result {
                    log(out, Level::Error, format!("reset failed: {e}"));
                }
                out.push(Output::ResetDone { id, result });
            }
            Command::Pause(p) => {
                if p != self.paused {
                    self.paused = p;
                    self.pacer.hold(now, self.sim.time());
                    log(
                        out,
                        Level::Info,
                        if p { "paused" } else { "resumed" }.to_string(),
                    );
                }
            }
            Command::PublishRate(r) => {
                if super::params::positive_rate(r).is_ok() {
                    self.cfg.publish_rate = r;
                    self.publish.set_rate(r, now);
                }
            }
            Command::Wind(v) => {
                let v = crate::Vec3::from_array(v);
                match self.scene.wind.as_mut() {
                    Some(w) if self.sim.set_wind_velocity(v) => {
                        // The scene is what a reset rebuilds from: the new wind survives it.
                        w.velocity = v;
                        log(out, Level::Info, format!("wind set to {v:?} m/s"));
                    }
                    _ => log(
                        out,
                        Level::Warn,
                        format!("wind {v:?} ignored: the scene names no wind effect"),
                    ),
                }
            }
            Command::Stop => return false,
        }
        true
    }

    /// Runs one step if one is due at clock time `now` and emits the outputs due. Returns true
    /// while more steps are owed: call again with a fresh `now` (one step per call keeps
    /// publishing on schedule when the solver is slower than real time).
    ///
    /// A step that reached a changed joint command publishes at once when the next publish
    /// instant is less than a step away (that instant is taken early, the rate is unchanged):
    /// the new pose is out one step sooner than if it waited for the instant.
    pub fn tick(&mut self, now: f64, out: &mut Vec<Output>) -> bool {
        let mut owed = 0;
        let mut reached = false;
        if self.paused {
            self.pacer.hold(now, self.sim.time());
        } else {
            owed = self.pacer.due_steps(now, self.sim.time());
            if owed > 0 {
                reached = std::mem::take(&mut self.fresh_command);
                self.step_once(now, out);
            }
        }
        let lead = if reached { self.pacer.dt() } else { 0.0 };
        if self.publish.due_within(now, lead) {
            out.push(self.frame());
            self.stats.frames += 1;
        }
        if self.obstacles.as_mut().is_some_and(|o| o.due(now)) {
            if let Some(d) = &self.driver {
                let stamp = time_of(self.clock_of_state());
                out.push(Output::Obstacles(obstacle_markers(
                    d,
                    self.cfg.distro,
                    stamp,
                    &self.frame_id,
                )));
            }
        }
        if self.diagnostics.due(now) {
            out.push(Output::Diagnostics(self.diagnostics_message(now)));
            self.start_window(now);
        }
        owed > 1
    }

    /// Ticks until no step is owed at `now` (a fixed clock instant, as in tests or with
    /// `/clock`).
    pub fn advance_to(&mut self, now: f64, out: &mut Vec<Output>) {
        while self.tick(now, out) {}
    }

    fn step_once(&mut self, now: f64, out: &mut Vec<Output>) {
        let t_next = self.sim.time() + self.sim.settings.dt;
        if let Some(d) = &mut self.driver {
            d.advance(&mut self.sim, t_next);
        }
        let start = Instant::now();
        let result = self.sim.step().map(|m| {
            (
                m.contacts,
                m.deepest_penetration,
                m.kinetic_energy + m.potential_energy,
            )
        });
        let wall = start.elapsed().as_secs_f64();
        self.stats.steps += 1;
        self.window.steps += 1;
        self.window.step_time_sum += wall;
        self.window.step_time_max = self.window.step_time_max.max(wall);
        match result {
            Ok((contacts, depth, energy)) => {
                self.contacts = contacts;
                self.energy = energy;
                self.window.deepest_penetration = self.window.deepest_penetration.max(depth);
            }
            Err(e) => {
                self.stats.divergences += 1;
                log(
                    out,
                    Level::Error,
                    format!("simulation diverged, restoring the initial cloth: {e}"),
                );
                if let Err(e) = self.rebuild(now) {
                    log(out, Level::Error, format!("cannot rebuild the scene: {e}"));
                }
            }
        }
    }

    fn frame(&self) -> Output {
        let stamp = time_of(self.clock_of_state());
        let c = &self.sim.cloth;
        let [r, g, b, a] = self.cfg.color;
        let mesh = mesh_marker(
            self.cfg.distro,
            stamp,
            &self.frame_id,
            &self.cfg.name,
            &c.x,
            &c.triangles,
            ColorRGBA::new(r, g, b, a),
        );
        let points = point_cloud(stamp, &self.frame_id, &c.x, &c.vertex_normals());
        Output::Frame {
            mesh: Box::new(mesh),
            points: Box::new(points),
        }
    }

    fn diagnostics_message(&self, now: f64) -> DiagnosticArray {
        let w = &self.window;
        let clock_span = now - w.clock_start;
        let sim_span = self.sim.time() - w.sim_start;
        let rtf = if clock_span > 0.0 && !self.paused {
            Some(sim_span / clock_span)
        } else {
            None
        };
        diagnostics(&DiagnosticsInput {
            name: &self.cfg.name,
            stamp: time_of(self.clock_of_state()),
            paused: self.paused,
            real_time_factor: rtf,
            step_time_mean: if w.steps > 0 {
                w.step_time_sum / w.steps as f64
            } else {
                0.0
            },
            step_time_max: w.step_time_max,
            contacts: self.contacts,
            deepest_penetration: w.deepest_penetration,
            energy: self.energy,
            stats: &self.stats,
            dropped_steps: self.pacer.dropped_steps(),
            new_drops: self.stats.dropped.total() - w.dropped_at_start,
            new_divergences: self.stats.divergences - w.divergences_at_start,
            sim_time: self.sim.time(),
        })
    }

    fn start_window(&mut self, now: f64) {
        self.window = Window {
            clock_start: now,
            sim_start: self.sim.time(),
            dropped_at_start: self.stats.dropped.total(),
            divergences_at_start: self.stats.divergences,
            ..Window::default()
        };
    }

    fn on_joints(&mut self, stamp_ns: i64, input: &JointInput, out: &mut Vec<Output>) {
        let Some(d) = &mut self.driver else {
            self.stats.dropped.other += 1;
            drop_warning(out, &self.stats.dropped, "the scene has no robot");
            return;
        };
        if stamp_ns != 0 && self.last_stamp.is_some_and(|last| stamp_ns < last) {
            self.stats.dropped.out_of_order += 1;
            let msg = format!(
                "stamp {:.6} s is older than the last accepted one",
                stamp_ns as f64 * 1e-9
            );
            drop_warning(out, &self.stats.dropped, &msg);
            return;
        }
        let base = self
            .commanded
            .clone()
            .unwrap_or_else(|| d.joint_positions().clone());
        let mut q = base.clone();
        if let Err(e) = input.apply(d.robot().kinematics(), &mut q) {
            let slot = match e {
                JointInputError::NotFinite { .. } | JointInputError::NonFinitePose(_) => {
                    &mut self.stats.dropped.non_finite
                }
                JointInputError::Empty | JointInputError::LengthMismatch { .. } => {
                    &mut self.stats.dropped.wrong_length
                }
                JointInputError::UnknownJoint(_) => &mut self.stats.dropped.unknown_joint,
                _ => &mut self.stats.dropped.other,
            };
            *slot += 1;
            drop_warning(out, &self.stats.dropped, &e.to_string());
            return;
        }
        if stamp_ns != 0 {
            self.last_stamp = Some(stamp_ns);
        }
        self.stats.joint_states += 1;
        // Reach the new pose at the end of the next step; the simulation interpolates the links
        // across its substeps.
        let t = self.sim.time();
        let now_q = d.joint_positions().clone();
        let dt = self.sim.settings.dt;
        d.set_source(
            JointSource::Stream(vec![(t, now_q), (t + dt, q.clone())]),
            t,
        );
        self.fresh_command |= q != base;
        self.commanded = Some(q);
    }

    fn on_description(&mut self, urdf: String, now: f64, out: &mut Vec<Output>) {
        if self.scene.robot.is_none() {
            self.stats.description_failures += 1;
            log(
                out,
                Level::Error,
                "robot_description ignored: the scene has no `robot:` section".into(),
            );
            return;
        }
        if self.scene.robot_urdf_text.as_deref() == Some(urdf.as_str()) {
            return;
        }
        let mut scene = self.scene.clone();
        scene.robot_urdf_text = Some(urdf);
        match scene.build_with_robot() {
            Ok((sim, driver)) => {
                let name = driver
                    .as_ref()
                    .map_or(String::new(), |d| d.robot().name.clone());
                self.scene = scene;
                self.sim = sim;
                self.commanded = None;
                self.last_stamp = None;
                self.install_robot(driver);
                self.pacer.hold(now, self.sim.time());
                self.stats.descriptions_loaded += 1;
                log(
                    out,
                    Level::Info,
                    format!("robot_description: loaded robot `{name}`; cloth restarted"),
                );
            }
            Err(e) => {
                self.stats.description_failures += 1;
                log(
                    out,
                    Level::Error,
                    format!("robot_description rejected, keeping the current robot: {e}"),
                );
            }
        }
    }

    /// Rebuilds the scene (reset or divergence), keeping the current robot description; the
    /// robot blends back to the last commanded pose.
    fn rebuild(&mut self, now: f64) -> Result<(), SceneError> {
        let (sim, driver) = self.scene.build_with_robot()?;
        self.sim = sim;
        self.install_robot(driver);
        self.pacer.hold(now, self.sim.time());
        Ok(())
    }

    /// Makes the robot hold its initial pose (blending to the commanded one if any) and picks
    /// the output frame.
    fn install_robot(&mut self, mut driver: Option<RobotDriver>) {
        if let Some(d) = driver.as_mut() {
            let q0 = d.joint_positions().clone();
            let stream = match &self.commanded {
                Some(q) if q.positions.len() == q0.positions.len() => {
                    vec![(0.0, q0), (RESET_BLEND_S, q.clone())]
                }
                _ => vec![(0.0, q0)],
            };
            d.set_source(JointSource::Stream(stream), self.sim.time());
        }
        self.frame_id = if !self.cfg.frame_id.is_empty() {
            self.cfg.frame_id.clone()
        } else {
            driver
                .as_ref()
                .map_or_else(|| "world".to_string(), |d| d.root_link().to_string())
        };
        self.driver = driver;
    }
}

/// Warns about the first few dropped inputs, then at powers of two, so a flood of bad messages
/// cannot flood the log.
fn drop_warning(out: &mut Vec<Output>, dropped: &DroppedInputs, why: &str) {
    let n = dropped.total();
    if n <= 5 || n.is_power_of_two() {
        log(
            out,
            Level::Warn,
            format!("joint state dropped ({n} so far): {why}"),
        );
    }
}

fn log(out: &mut Vec<Output>, level: Level, text: String) {
    out.push(Output::Log { level, text });
}

/// The real-time preview solver settings: one substep, CG tolerance 1e-2, at most 50 CG
/// iterations, for an implicit scene (other integrators keep their settings: fewer substeps
/// would make them unstable). Trades accuracy (stiffer-looking, less converged cloth) for a
/// step several times cheaper, so a large cloth can keep real time.
pub fn real_time_preview(scene: &mut Scene) {
    if scene.solver.integrator == crate::integrate::IntegratorKind::Implicit {
        scene.solver.substeps = 1;
        scene.solver.cg_tolerance = scene.solver.cg_tolerance.max(1e-2);
        scene.solver.cg_max_iterations = scene.solver.cg_max_iterations.min(50);
    }
}

/// ROS time from seconds (negative clamps to 0).
pub fn time_of(seconds: f64) -> Time {
    Time::from_nanos((seconds * 1e9).round().max(0.0) as u64)
}

/// Which clock paces the loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClockMode {
    /// System time (stamps are Unix time).
    Wall,
    /// `/clock` messages ([`Command::Clock`]); nothing runs before the first one.
    Sim,
}

/// Seconds since the Unix epoch, from a monotonic clock anchored once.
#[derive(Debug, Clone, Copy)]
pub struct WallClock {
    start: Instant,
    epoch: f64,
}

impl WallClock {
    pub fn new() -> WallClock {
        let epoch = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        WallClock {
            start: Instant::now(),
            epoch,
        }
    }

    pub fn now(&self) -> f64 {
        self.epoch + self.start.elapsed().as_secs_f64()
    }
}

impl Default for WallClock {
    fn default() -> Self {
        Self::new()
    }
}

/// The simulation thread: waits for commands until the next thing is due, ticks, and sends the
/// outputs. Returns on [`Command::Stop`], on `stop`, or when either channel closes.
pub fn run(
    mut core: SimLoop,
    mode: ClockMode,
    wall: WallClock,
    rx: Receiver<Command>,
    tx: Sender<Output>,
    stop: &AtomicBool,
) {
    let mut out = Vec::new();
    let mut now = match mode {
        ClockMode::Wall => Some(wall.now()),
        ClockMode::Sim => None,
    };
    if let Some(n) = now {
        core.sync_clock(n);
    }
    let mut behind = false;
    let started = Instant::now();
    let mut warned_no_clock = false;
    while !stop.load(Ordering::Relaxed) {
        if now.is_none() && !warned_no_clock && started.elapsed() > Duration::from_secs(5) {
            warned_no_clock = true;
            out.push(Output::Log {
                level: Level::Warn,
                text: "use_sim_time is set but no /clock (rosgraph_msgs/msg/Clock) has arrived \
                       in 5 s: the simulation waits for it"
                    .into(),
            });
        }
        let wait = match (mode, now) {
            _ if behind => 0.0,
            (ClockMode::Wall, _) => (core.next_wake() - wall.now()).clamp(0.0, 0.05),
            _ => 0.05,
        };
        let mut pending = Vec::new();
        match rx.recv_timeout(Duration::from_secs_f64(wait)) {
            Ok(c) => pending.push(c),
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return,
        }
        pending.extend(rx.try_iter());
        if mode == ClockMode::Wall {
            now = Some(wall.now());
        }
        for cmd in pending {
            if let (ClockMode::Sim, Command::Clock(t)) = (mode, &cmd) {
                if now.is_none() {
                    core.sync_clock(*t);
                }
                now = Some(*t);
            }
            let t = now.unwrap_or(0.0);
            if !core.handle(cmd, t, &mut out) {
                return;
            }
        }
        behind = match now {
            Some(t) => core.tick(t, &mut out),
            None => false,
        };
        for o in out.drain(..) {
            if tx.send(o).is_err() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T0: f64 = 1000.0;

    fn towel(res: usize) -> Scene {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/robot_towel.yaml");
        let mut scene = Scene::load(path.as_ref()).expect("robot_towel scene");
        scene.cloths[0].grid.resolution = [res, res];
        scene
    }

    fn shoulder(s: f64) -> Command {
        Command::Joints {
            stamp_ns: 0,
            input: JointInput {
                names: vec!["right_shoulder_pitch".into()],
                positions: vec![s],
                velocities: None,
            },
        }
    }

    fn frames(out: &[Output]) -> usize {
        out.iter()
            .filter(|o| matches!(o, Output::Frame { .. }))
            .count()
    }

    /// Publish instants fall on even steps (T0, T0 + 2 dt, ...). A changed command before an
    /// odd step publishes right after that step instead of a step later; an unchanged one does
    /// not; and the number of frames per second stays the rate.
    #[test]
    fn a_step_reaching_a_new_command_publishes_a_step_early() {
        let mut l = SimLoop::new(towel(6), LoopConfig::default(), T0).expect("loop");
        let dt = l.simulation().settings.dt;
        let mut out = Vec::new();
        l.sync_clock(T0);
        l.advance_to(T0, &mut out);
        assert_eq!(frames(&out), 1);
        // The scene's own pose, re-sent: nothing new to show, no early frame.
        let q = l.driver().expect("robot").joint_positions().clone();
        let j = l
            .driver()
            .unwrap()
            .robot()
            .joint_index("right_shoulder_pitch");
        let s0 = q.positions[j.expect("shoulder")];
        l.handle(shoulder(s0), T0 + 0.5 * dt, &mut out);
        l.advance_to(T0 + dt, &mut out);
        assert_eq!(frames(&out), 1, "unchanged command published early");
        l.advance_to(T0 + 2.0 * dt, &mut out);
        assert_eq!(frames(&out), 2);
        // A new pose before the odd step at T0 + 3 dt: out right after it.
        l.handle(shoulder(s0 + 0.05), T0 + 2.5 * dt, &mut out);
        l.advance_to(T0 + 3.0 * dt, &mut out);
        assert_eq!(
            frames(&out),
            3,
            "new pose not published after the step reaching it"
        );
        // The instant at T0 + 4 dt was taken: none there; the grid resumes at T0 + 6 dt.
        l.advance_to(T0 + 4.0 * dt, &mut out);
        assert_eq!(frames(&out), 3);
        let mut t = T0 + 4.0 * dt;
        while t < T0 + 1.0 - 1e-9 {
            t += 0.5 * dt;
            l.advance_to(t, &mut out);
        }
        // Instants T0, T0 + 1/30, ..., T0 + 1: 31 frames, one of them early.
        assert_eq!(frames(&out), 31);
    }

    #[test]
    fn real_time_preview_changes_only_implicit_solver_settings() {
        let mut scene = towel(6);
        real_time_preview(&mut scene);
        let s = &scene.solver;
        assert_eq!(
            (s.substeps, s.cg_tolerance, s.cg_max_iterations),
            (1, 1e-2, 50)
        );
        let mut explicit = towel(6);
        explicit.solver.integrator = crate::integrate::IntegratorKind::SymplecticEuler;
        explicit.solver.substeps = 40;
        let before = explicit.solver.clone();
        real_time_preview(&mut explicit);
        assert_eq!(explicit.solver, before);
    }
}
