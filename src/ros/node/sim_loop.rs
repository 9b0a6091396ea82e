//! The simulation side of the node ([`SimLoop`]): owns the scene, the simulation and the robot; takes
//! commands (joint states, clock ticks, robot descriptions, reset, pause) and emits
//! ready-to-publish messages at fixed rates. No DDS here, so all of it runs in tests with a
//! synthetic clock.

use super::clock::time_of;
use super::config::LoopConfig;
use super::joints::JointGate;
use super::messages::{Command, DroppedInputs, Level, LoopStats, Output};
use super::outputs::{diagnostics, obstacle_markers, DiagnosticsInput};
use super::pacer::{Pacer, Schedule};
use super::params::positive_rate;
use super::quality::{Decision, Quality, QualityController, QualityStatus};
use crate::input::error_line;
use crate::integrate::IntegratorKind;
use crate::robot::{JointInput, JointSource, RobotDriver};
use crate::ros::msg::{ColorRGBA, DiagnosticArray};
use crate::ros::telemetry::FrameQuality;
use crate::ros::{mesh_marker, point_cloud};
use crate::scene::{Scene, SceneError};
use crate::sim::Simulation;
use std::sync::Arc;
use std::time::Instant;

/// Seconds over which the robot moves from its initial pose to the last commanded one after a
/// reset, so attached cloth is carried, not torn.
const RESET_BLEND_S: f64 = 0.5;

/// A model of a step's wall time (s) at a quality ([`SimLoop::set_step_cost`]).
type StepCost = Box<dyn FnMut(&Quality) -> f64 + Send>;

/// Measurements since the last diagnostics message.
#[derive(Debug, Clone, Default)]
struct Window {
    clock_start: f64,
    sim_start: f64,
    steps: u64,
    step_time_sum: f64,
    step_time_max: f64,
    /// The simulation's metrics over the window's steps (the state values of the last one).
    sim: FrameQuality,
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
    joints: JointGate,
    pacer: Pacer,
    publish: Schedule,
    obstacles: Option<Schedule>,
    diagnostics: Schedule,
    paused: bool,
    stats: LoopStats,
    window: Window,
    /// Adaptive quality (fixed at the scene's when `cfg.quality` is `None`).
    quality: QualityController,
    /// A model of a step's wall time replacing the measured one (tests, benches).
    step_cost: Option<StepCost>,
    last_step_wall: f64,
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
            if positive_rate(*rate).is_err() {
                log::warn!("rate {rate} Hz is unusable; using {default} Hz");
                *rate = default;
            }
        }
        if !(cfg.obstacles_rate.is_finite() && cfg.obstacles_rate >= 0.0) {
            cfg.obstacles_rate = 0.0;
        }
        let (sim, driver) = scene.build_with_robot()?;
        let dt = sim.settings.dt;
        let full = Quality {
            substeps: scene.solver.substeps,
            cg_tolerance: scene.solver.cg_tolerance,
            cg_max_iterations: scene.solver.cg_max_iterations,
            linearisation_tolerance: scene.solver.linearisation_tolerance,
        };
        // Only the implicit integrator adapts: fewer substeps make explicit ones unstable.
        let implicit = scene.solver.integrator == IntegratorKind::Implicit;
        let bounds = cfg.quality.unwrap_or_default();
        let quality = QualityController::new(full, &bounds, cfg.quality.is_some() && implicit);
        let velocity_limits = cfg.joint_velocity_limits;
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
            joints: JointGate::new(velocity_limits),
            stats: LoopStats::default(),
            window: Window {
                clock_start: now,
                ..Window::default()
            },
            quality,
            step_cost: None,
            last_step_wall: 0.0,
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

    /// The quality the loop runs at, as `/diagnostics` reports it.
    pub fn quality(&self) -> QualityStatus {
        self.quality.status()
    }

    /// Every quality the controller may choose, the scene's first.
    pub fn quality_ladder(&self) -> &[Quality] {
        self.quality.ladder()
    }

    /// Replaces the measured wall time of each step by `cost(quality)` (s), so the adaptive
    /// quality can be driven on a synthetic clock (tests, benches).
    pub fn set_step_cost(&mut self, cost: impl FnMut(&Quality) -> f64 + Send + 'static) {
        self.step_cost = Some(Box::new(cost));
    }

    /// Wall time (s) of the last step, measured or from [`SimLoop::set_step_cost`].
    pub fn last_step_wall(&self) -> f64 {
        self.last_step_wall
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
                let result = result.map_err(Arc::new);
                if let Err(e) = &result {
                    log(
                        out,
                        Level::Error,
                        format!("reset failed: {}", error_line(&**e)),
                    );
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
                if positive_rate(r).is_ok() {
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
                reached = std::mem::take(&mut self.joints.fresh);
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
        let result = self.sim.step();
        let mut wall = start.elapsed().as_secs_f64();
        if let Some(cost) = &mut self.step_cost {
            wall = cost(&self.quality.quality());
        }
        self.last_step_wall = wall;
        self.stats.steps += 1;
        self.window.steps += 1;
        self.window.step_time_sum += wall;
        self.window.step_time_max = self.window.step_time_max.max(wall);
        match result {
            Ok(m) => {
                let q = &mut self.window.sim;
                q.add_step(&m);
                q.max_edge_stretch = q.max_edge_stretch.max(self.sim.cloth.max_edge_stretch());
                let dt = self.sim.settings.dt;
                let decision = self.quality.update(wall, dt);
                self.adapt(decision, out);
            }
            Err(e) => {
                self.stats.divergences += 1;
                log(
                    out,
                    Level::Error,
                    format!(
                        "simulation diverged, restoring the initial cloth: {}",
                        error_line(&*e)
                    ),
                );
                if let Some(q) = self.quality.on_divergence() {
                    log(
                        out,
                        Level::Warn,
                        format!("diverged at reduced quality: not going below {q} again"),
                    );
                }
                if let Err(e) = self.rebuild(now) {
                    let e = error_line(&e);
                    log(out, Level::Error, format!("cannot rebuild the scene: {e}"));
                }
            }
        }
    }

    /// Applies the controller's decision to the simulation and says what changed.
    fn adapt(&mut self, decision: Decision, out: &mut Vec<Output>) {
        let s = self.quality.status();
        match decision {
            Decision::Keep => {}
            Decision::Lowered { quality, load } | Decision::Raised { quality, load } => {
                self.apply_quality();
                let dir = if matches!(decision, Decision::Lowered { .. }) {
                    "lowered"
                } else {
                    "raised"
                };
                log(
                    out,
                    Level::Info,
                    format!(
                        "quality {dir} to level {} of {} ({quality}): steps took {load:.2}x \
                         real time",
                        s.level,
                        s.levels - 1
                    ),
                );
            }
            Decision::CannotHold { quality, load } => log(
                out,
                Level::Warn,
                format!(
                    "cannot hold real time even at the lowest allowed quality ({quality}): \
                     steps take {load:.2}x real time (real-time factor {:.2})",
                    1.0 / load
                ),
            ),
        }
    }

    /// Sets the controller's quality on the simulation (after a change or a rebuild, which
    /// starts from the scene's quality).
    fn apply_quality(&mut self) {
        let q = self.quality.quality();
        self.sim.set_quality(q.substeps, q.solver());
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
            sim: &w.sim,
            stats: &self.stats,
            dropped_steps: self.pacer.dropped_steps(),
            new_drops: self.stats.dropped.total() - w.dropped_at_start,
            new_divergences: self.stats.divergences - w.divergences_at_start,
            quality: self.quality.status(),
        })
    }

    fn start_window(&mut self, now: f64) {
        self.window = Window {
            clock_start: now,
            sim_start: self.sim.time(),
            dropped_at_start: self.stats.dropped.total(),
            divergences_at_start: self.stats.divergences,
            sim: self.window.sim.next_window(),
            ..Window::default()
        };
    }

    fn on_joints(&mut self, stamp_ns: i64, input: &JointInput, out: &mut Vec<Output>) {
        let (t, dt) = (self.sim.time(), self.sim.settings.dt);
        match self
            .joints
            .accept(self.driver.as_mut(), t, dt, stamp_ns, input)
        {
            Ok(()) => self.stats.joint_states += 1,
            Err(why) => {
                why.count(&mut self.stats.dropped);
                drop_warning(out, &self.stats.dropped, &why.to_string());
            }
        }
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
                self.apply_quality();
                self.joints.clear();
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
                    format!(
                        "robot_description rejected, keeping the current robot: {}",
                        error_line(&e)
                    ),
                );
            }
        }
    }

    /// Rebuilds the scene (reset or divergence), keeping the current robot description; the
    /// robot blends back to the last commanded pose.
    fn rebuild(&mut self, now: f64) -> Result<(), SceneError> {
        let (sim, driver) = self.scene.build_with_robot()?;
        self.sim = sim;
        self.apply_quality();
        self.install_robot(driver);
        self.pacer.hold(now, self.sim.time());
        Ok(())
    }

    /// Makes the robot hold its initial pose (blending to the commanded one if any) and picks
    /// the output frame.
    fn install_robot(&mut self, mut driver: Option<RobotDriver>) {
        if let Some(d) = driver.as_mut() {
            let q0 = d.joint_positions().clone();
            let stream = match &self.joints.commanded {
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
