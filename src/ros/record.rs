//! Offline recording: runs a simulation for a duration and writes the cloth at the scene's
//! publish rate to a rosbag2 MCAP file. The file is always finished, also on a stop request
//! (Ctrl-C) and on a simulation error, so it is never left unreadable.
//!
//! The output is never one of the run's inputs (scene, URDF, meshes, joints bag: compared by
//! device and inode, so symlinks and hard links count), it is written to a temporary file beside
//! it and renamed into place when finished, and no non-finite value is ever written: a frame
//! with one stops the run with an error naming it.

use crate::robot::RobotDriver;
use crate::ros::msg::{
    ColorRGBA, DiagnosticArray, Header, JointState, Marker, PointCloud2, RosString, TFMessage,
    Time, Transform, TransformStamped,
};
use crate::ros::obstacles;
use crate::ros::telemetry::{FrameQuality, RunQuality, RunSummary};
use crate::ros::{
    bag::RunInfo, mesh_marker, offered_qos_profiles, point_cloud, BagError, BagWriter, Distro,
    Durability, Reliability, TopicId,
};
use crate::sim::{DivergenceError, Simulation};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// How to record.
#[derive(Debug, Clone)]
pub struct RecordOptions {
    /// Simulated seconds to record.
    pub duration: f64,
    /// Messages per simulated second.
    pub publish_rate: f64,
    pub distro: Distro,
    /// Frame the cloth is expressed in.
    pub frame_id: String,
    /// Topics are `<prefix>/mesh` and `<prefix>/points`.
    pub topic_prefix: String,
    pub color: [f32; 4],
    /// Also write each frame's step wall time on `/diagnostics` (off by default: with it the
    /// same scene no longer gives the same bag bytes).
    pub wall_time_in_bag: bool,
    /// Write straight into `out` instead of a hidden file beside it renamed at the end: for a
    /// caller that already writes to a staging name of its own and renames it (a sweep job's
    /// `.part`), so a killed job leaves exactly that one partial file for its rerun to remove.
    pub in_place: bool,
    /// The scene file the run was built from and the scene's name: written (the file made
    /// absolute) with the cloth pieces to the bag's `drape` metadata ([`RunInfo`]), so that
    /// `drape render` finds the robot's meshes and the scene's obstacles as the run did.
    pub scene_file: Option<PathBuf>,
    pub scene_name: Option<String>,
    /// The folders the run searched for `package://` meshes besides the scene's own
    /// (`--package-path`), also written to the metadata.
    pub package_paths: Vec<PathBuf>,
}

impl Default for RecordOptions {
    fn default() -> Self {
        Self {
            duration: 5.0,
            publish_rate: 30.0,
            distro: Distro::Jazzy,
            frame_id: "world".into(),
            topic_prefix: "/drape".into(),
            color: [0.85, 0.35, 0.2, 1.0],
            wall_time_in_bag: false,
            in_place: false,
            scene_file: None,
            scene_name: None,
            package_paths: Vec::new(),
        }
    }
}

/// What a recording did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RecordSummary {
    pub frames_written: u64,
    pub steps: u64,
    pub simulated_seconds: f64,
    pub subdivisions: u64,
    /// True when a stop request ended the run early.
    pub interrupted: bool,
    /// Totals of the per-frame quality written on `/diagnostics`.
    pub quality: RunQuality,
    /// Wall time of the run (s).
    pub wall_seconds: f64,
}

impl RecordSummary {
    /// The run summary (table and JSON) of this recording.
    pub fn run_summary(&self) -> RunSummary {
        let q = &self.quality;
        RunSummary {
            frames: self.frames_written,
            steps: self.steps,
            substeps: q.substeps,
            subdivisions: self.subdivisions,
            cg_iterations_mean: if self.steps > 0 {
                q.cg_iterations as f64 / self.steps as f64
            } else {
                0.0
            },
            cg_iterations_max: q.cg_iterations_max,
            cg_residual_max: q.cg_residual_max,
            contacts_max: q.contacts_max,
            worst_penetration_m: q.worst_penetration,
            worst_stretch: q.worst_stretch,
            self_intersections_max: q.self_intersections_max,
            simulated_s: self.simulated_seconds,
            wall_s: self.wall_seconds,
            real_time_factor: if self.wall_seconds > 0.0 {
                self.simulated_seconds / self.wall_seconds
            } else {
                0.0
            },
            interrupted: self.interrupted,
        }
    }
}

/// Why a recording failed; each names the output file or what went wrong in the run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordError {
    #[error(transparent)]
    Bag(#[from] BagError),
    /// The simulation diverged; the bag holds everything up to the last good frame.
    #[error(
        "the simulation diverged (the bag was finished with {frames} frames before the failure)"
    )]
    Diverged {
        #[source]
        error: Box<DivergenceError>,
        frames: u64,
    },
    #[error("duration must be finite and > 0 (got {value})")]
    Duration { value: f64 },
    #[error("publish rate must be finite and > 0 (got {value})")]
    PublishRate { value: f64 },
    /// `--out` names a file the run reads (the same file by device and inode).
    #[error("{}: is {kind} ({}); refusing to overwrite it", .out.display(), .input.display())]
    OntoInput {
        out: PathBuf,
        input: PathBuf,
        kind: String,
    },
    #[error(transparent)]
    Output(crate::output::OutputError),
    #[error("{}: is a directory", .out.display())]
    OutIsDirectory { out: PathBuf },
    /// A value about to be written is NaN or infinite; the run stops instead.
    #[error("{}: {what} {index} is not finite at t = {time} s; stopped (the bag was finished with {frames} frames before it)", .out.display())]
    NonFinite {
        out: PathBuf,
        what: &'static str,
        index: usize,
        time: f64,
        frames: u64,
    },
    #[error("{}: cannot move the finished bag into place from {}", .out.display(), .from.display())]
    Rename {
        out: PathBuf,
        from: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// Where the bag is written while recording: a hidden file beside `out`, renamed at the end;
/// or `out` itself when it is an existing device or FIFO (a stream, e.g. `/dev/stdout`). The
/// rules are [`crate::output`]'s.
fn staging_path(out: &Path) -> Result<Option<PathBuf>, RecordError> {
    use crate::output::{check, OutputError, Target};
    match check(out, &[]) {
        Ok(Target::Staged { tmp }) => Ok(Some(tmp)),
        Ok(Target::Stream) => Ok(None),
        Err(OutputError::IsDirectory { .. }) => Err(RecordError::OutIsDirectory {
            out: out.to_path_buf(),
        }),
        Err(OutputError::OntoInput { input, kind, .. }) => Err(RecordError::OntoInput {
            out: out.to_path_buf(),
            input,
            kind,
        }),
        Err(other) => Err(RecordError::Output(other)),
    }
}

struct Topics {
    mesh: TopicId,
    points: TopicId,
    /// `/diagnostics`: every frame's [`FrameQuality`].
    diagnostics: TopicId,
    /// `/joint_states` and `/tf` when a robot is recorded.
    robot: Option<(TopicId, TopicId)>,
    /// `<prefix>/obstacles` when the scene has obstacles of its own (one Marker per message),
    /// and whether any of them moves (then every frame writes them again).
    obstacles: Option<(TopicId, bool)>,
}

/// Runs `sim` and records it to `out`. `stop` is polled every step; `progress` gets the simulated
/// time after each step.
pub fn record(
    sim: &mut Simulation,
    out: &Path,
    opts: &RecordOptions,
    stop: &AtomicBool,
    progress: impl FnMut(f64),
) -> Result<RecordSummary, RecordError> {
    record_with_robot(sim, None, out, opts, stop, progress)
}

/// [`record`] with a robot: `driver.advance` runs before every step, and the bag also carries
/// `/joint_states`, `/tf` (every link in the root link frame) at the publish rate and
/// `/robot_description` once, offered transient-local so a late subscriber gets it.
pub fn record_with_robot(
    sim: &mut Simulation,
    driver: Option<&mut RobotDriver>,
    out: &Path,
    opts: &RecordOptions,
    stop: &AtomicBool,
    mut progress: impl FnMut(f64),
) -> Result<RecordSummary, RecordError> {
    if !(opts.duration.is_finite() && opts.duration > 0.0) {
        return Err(RecordError::Duration {
            value: opts.duration,
        });
    }
    if !(opts.publish_rate.is_finite() && opts.publish_rate > 0.0) {
        return Err(RecordError::PublishRate {
            value: opts.publish_rate,
        });
    }
    let staging = staging_path(out)?.filter(|_| !opts.in_place);
    let target = staging.as_deref().unwrap_or(out);
    let mut bag = BagWriter::create(target).map_err(|e| match e {
        // Name the file the user asked for, not the staging file beside it.
        BagError::Create { source, .. } => BagError::Create {
            path: out.to_path_buf(),
            source,
        },
        other => other,
    })?;
    let result = record_into(sim, driver, &mut bag, out, opts, stop, &mut progress);
    // Finish the file whatever happened; a finish error wins only if the run itself succeeded.
    let finished = bag.finish();
    let moved = match &staging {
        Some(tmp) if finished.is_ok() => {
            std::fs::rename(tmp, out).map_err(|source| RecordError::Rename {
                out: out.to_path_buf(),
                from: tmp.clone(),
                source,
            })
        }
        Some(tmp) => {
            let _ = std::fs::remove_file(tmp);
            Ok(())
        }
        None => Ok(()),
    };
    let summary = result?;
    finished?;
    moved?;
    Ok(summary)
}

fn record_into(
    sim: &mut Simulation,
    driver: Option<&mut RobotDriver>,
    bag: &mut BagWriter,
    out: &Path,
    opts: &RecordOptions,
    stop: &AtomicBool,
    progress: &mut impl FnMut(f64),
) -> Result<RecordSummary, RecordError> {
    bag.write_run_info(&run_info(sim, opts))?;
    let mut topics = Topics {
        mesh: bag.add_topic::<Marker>(&format!("{}/mesh", opts.topic_prefix), opts.distro, None)?,
        points: bag.add_topic::<PointCloud2>(
            &format!("{}/points", opts.topic_prefix),
            opts.distro,
            None,
        )?,
        diagnostics: bag.add_topic::<DiagnosticArray>("/diagnostics", opts.distro, None)?,
        robot: None,
        obstacles: None,
    };
    let own: Vec<_> = sim
        .collision()
        .map(|c| c.obstacles())
        .unwrap_or_default()
        .iter()
        .filter(|o| obstacles::is_scene_obstacle(o))
        .collect();
    if !own.is_empty() {
        let moving = own.iter().any(|o| obstacles::moves(o));
        let topic = bag.add_topic::<Marker>(
            &format!("{}/obstacles", opts.topic_prefix),
            opts.distro,
            None,
        )?;
        topics.obstacles = Some((topic, moving));
        write_obstacles(sim, bag, topic, opts)?;
    }
    if let Some(d) = driver.as_deref() {
        let latched = offered_qos_profiles(Reliability::Reliable, Durability::TransientLocal);
        let desc = bag.add_topic::<RosString>("/robot_description", opts.distro, Some(&latched))?;
        let ns = (sim.time() * 1e9).round().max(0.0) as u64;
        bag.write(
            desc,
            ns,
            &RosString {
                data: d.urdf_text().to_string(),
            },
        )?;
        topics.robot = Some((
            bag.add_topic::<JointState>("/joint_states", opts.distro, None)?,
            bag.add_topic::<TFMessage>("/tf", opts.distro, None)?,
        ));
    }
    run(sim, driver, bag, out, &topics, opts, stop, progress)
}

#[allow(clippy::too_many_arguments)]
fn run(
    sim: &mut Simulation,
    mut driver: Option<&mut RobotDriver>,
    bag: &mut BagWriter,
    out: &Path,
    topics: &Topics,
    opts: &RecordOptions,
    stop: &AtomicBool,
    progress: &mut impl FnMut(f64),
) -> Result<RecordSummary, RecordError> {
    let started = std::time::Instant::now();
    let mut s = RecordSummary::default();
    let period = 1.0 / opts.publish_rate;
    let t_end = sim.time() + opts.duration;
    let eps = 1e-9 * sim.settings.dt;
    let start = sim.time();
    // A frame is checked for finite values before any of it is written.
    let frame = |sim: &Simulation,
                 driver: Option<&RobotDriver>,
                 bag: &mut BagWriter,
                 n: u64,
                 quality: &mut FrameQuality| {
        check_finite(sim, driver, out, n)?;
        write_frame(sim, driver, bag, topics, opts, quality).map_err(RecordError::from)
    };
    let mut quality = FrameQuality::default();
    frame(sim, driver.as_deref(), bag, 0, &mut quality)?;
    s.quality.add_frame(&quality);
    quality = FrameQuality::default();
    s.frames_written += 1;
    // Publish instants are start + k * period, k counted (not summed, which stalls when the
    // period is below the time's resolution); the step count is bounded by the scene's checks.
    let mut k: f64 = 1.0;
    let mut next_publish = start + period;
    while sim.time() + eps < t_end {
        if stop.load(Ordering::Relaxed) {
            s.interrupted = true;
            break;
        }
        if let Some(d) = driver.as_deref_mut() {
            d.advance(sim, sim.time() + sim.settings.dt);
        }
        let m = sim.step().map_err(|error| RecordError::Diverged {
            error,
            frames: s.frames_written,
        })?;
        s.steps += 1;
        s.subdivisions += m.subdivisions as u64;
        quality.add_step(&m);
        if sim.time() + eps >= next_publish {
            frame(sim, driver.as_deref(), bag, s.frames_written, &mut quality)?;
            s.quality.add_frame(&quality);
            quality = FrameQuality::default();
            s.frames_written += 1;
            // Skip publish instants a long frame step jumped over rather than bunching them.
            k = (((sim.time() + eps - start) / period).floor() + 1.0).max(k + 1.0);
            next_publish = start + k * period;
        }
        progress(sim.time());
    }
    s.simulated_seconds = sim.time();
    s.wall_seconds = started.elapsed().as_secs_f64();
    Ok(s)
}

/// The bag's `drape` metadata: the scene and the package folders (absolute), the cloth pieces.
fn run_info(sim: &Simulation, opts: &RecordOptions) -> RunInfo {
    let absolute = |p: &PathBuf| {
        std::fs::canonicalize(p).unwrap_or_else(|_| std::path::absolute(p).unwrap_or(p.clone()))
    };
    RunInfo {
        scene: opts.scene_file.as_ref().map(absolute),
        scene_name: opts.scene_name.clone(),
        package_paths: opts.package_paths.iter().map(absolute).collect(),
        cloth_pieces: sim
            .cloth
            .pieces
            .iter()
            .map(|p| (p.name.clone(), p.triangle_count))
            .collect(),
    }
}

/// Refuses a frame with a NaN or infinite value: cloth positions, joint positions, link poses.
fn check_finite(
    sim: &Simulation,
    driver: Option<&RobotDriver>,
    out: &Path,
    frames: u64,
) -> Result<(), RecordError> {
    let err = |what, index| RecordError::NonFinite {
        out: out.to_path_buf(),
        what,
        index,
        time: sim.time(),
        frames,
    };
    if let Some(i) = sim.cloth.x.iter().position(|v| !v.is_finite()) {
        return Err(err("cloth vertex", i));
    }
    if let Some(d) = driver {
        let kin = d.robot().kinematics();
        let q = d.joint_positions();
        for (ji, j) in kin.joints().iter().enumerate() {
            if j.kind.is_scalar() && !kin.effective_position(q, ji).0.is_finite() {
                return Err(err("joint", ji));
            }
        }
        if let Some(l) = d.link_poses().iter().position(|p| !p.is_finite()) {
            return Err(err("link pose", l));
        }
    }
    Ok(())
}

fn write_frame(
    sim: &Simulation,
    driver: Option<&RobotDriver>,
    bag: &mut BagWriter,
    topics: &Topics,
    opts: &RecordOptions,
    quality: &mut FrameQuality,
) -> Result<(), BagError> {
    let ns = (sim.time() * 1e9).round().max(0.0) as u64;
    let stamp = Time::from_nanos(ns);
    quality.at_frame(sim.time(), &sim.cloth);
    let diagnostics = quality.diagnostics("drape", stamp, opts.wall_time_in_bag);
    bag.write(topics.diagnostics, ns, &diagnostics)?;
    let c = &sim.cloth;
    let [r, g, b, a] = opts.color;
    let marker = mesh_marker(
        opts.distro,
        stamp,
        &opts.frame_id,
        "drape",
        &c.x,
        &c.triangles,
        ColorRGBA::new(r, g, b, a),
    );
    bag.write(topics.mesh, ns, &marker)?;
    let cloud = point_cloud(stamp, &opts.frame_id, &c.x, &c.vertex_normals());
    bag.write(topics.points, ns, &cloud)?;
    if let (Some(d), Some((joints, tf))) = (driver, topics.robot) {
        bag.write(joints, ns, &joint_state(d, stamp))?;
        bag.write(tf, ns, &tf_message(d, stamp))?;
    }
    if let Some((topic, true)) = topics.obstacles {
        write_obstacles(sim, bag, topic, opts)?;
    }
    Ok(())
}

/// The scene's own obstacles at their current poses, one Marker message each.
fn write_obstacles(
    sim: &Simulation,
    bag: &mut BagWriter,
    topic: TopicId,
    opts: &RecordOptions,
) -> Result<(), BagError> {
    let ns = (sim.time() * 1e9).round().max(0.0) as u64;
    let all = sim.collision().map(|c| c.obstacles()).unwrap_or_default();
    let markers =
        obstacles::scene_obstacle_markers(all, opts.distro, Time::from_nanos(ns), &opts.frame_id);
    for m in &markers {
        bag.write(topic, ns, m)?;
    }
    Ok(())
}

/// Every scalar joint (mimics included) at the position FK used.
fn joint_state(d: &RobotDriver, stamp: Time) -> JointState {
    let kin = d.robot().kinematics();
    let q = d.joint_positions();
    let mut msg = JointState {
        header: Header::new(stamp, ""),
        ..JointState::default()
    };
    for (ji, j) in kin.joints().iter().enumerate() {
        if j.kind.is_scalar() {
            msg.name.push(j.name.clone());
            msg.position.push(kin.effective_position(q, ji).0);
        }
    }
    msg
}

/// Pose of every non-root link in the root link frame.
fn tf_message(d: &RobotDriver, stamp: Time) -> TFMessage {
    let kin = d.robot().kinematics();
    let root = kin.root_link();
    let header = Header::new(stamp, d.root_link());
    let transforms = d
        .link_poses()
        .iter()
        .enumerate()
        .filter(|(l, _)| *l != root)
        .map(|(l, p)| TransformStamped {
            header: header.clone(),
            child_frame_id: kin.links()[l].clone(),
            transform: Transform {
                translation: p.translation.into(),
                rotation: p.rotation.into(),
            },
        })
        .collect();
    TFMessage { transforms }
}
