//! Offline recording: runs a simulation for a duration and writes the cloth at the scene's
//! publish rate to a rosbag2 MCAP file. The file is always finished, also on a stop request
//! (Ctrl-C) and on a simulation error, so it is never left unreadable.

use crate::ros::msg::{ColorRGBA, Marker, PointCloud2, Time};
use crate::ros::{mesh_marker, point_cloud, BagError, BagWriter, Distro, TopicId};
use crate::sim::{DivergenceError, Simulation};
use std::path::Path;
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
}

#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error(transparent)]
    Bag(#[from] BagError),
    /// The simulation diverged; the bag holds everything up to the last good frame.
    #[error("{error} (the bag was finished with {frames} frames before the failure)")]
    Diverged {
        error: Box<DivergenceError>,
        frames: u64,
    },
    #[error("invalid recording option: {0}")]
    Options(String),
}

struct Topics {
    mesh: TopicId,
    points: TopicId,
}

/// Runs `sim` and records it to `out`. `stop` is polled every step; `progress` gets the simulated
/// time after each step.
pub fn record(
    sim: &mut Simulation,
    out: &Path,
    opts: &RecordOptions,
    stop: &AtomicBool,
    mut progress: impl FnMut(f64),
) -> Result<RecordSummary, RecordError> {
    if !(opts.duration.is_finite() && opts.duration > 0.0) {
        return Err(RecordError::Options(format!(
            "duration must be > 0 (got {})",
            opts.duration
        )));
    }
    if !(opts.publish_rate.is_finite() && opts.publish_rate > 0.0) {
        return Err(RecordError::Options(format!(
            "publish rate must be > 0 (got {})",
            opts.publish_rate
        )));
    }
    let mut bag = BagWriter::create(out)?;
    let topics = Topics {
        mesh: bag.add_topic::<Marker>(&format!("{}/mesh", opts.topic_prefix), opts.distro, None)?,
        points: bag.add_topic::<PointCloud2>(
            &format!("{}/points", opts.topic_prefix),
            opts.distro,
            None,
        )?,
    };
    let result = run(sim, &mut bag, &topics, opts, stop, &mut progress);
    // Finish the file whatever happened; a finish error wins only if the run itself succeeded.
    let finished = bag.finish();
    let summary = result?;
    finished?;
    Ok(summary)
}

fn run(
    sim: &mut Simulation,
    bag: &mut BagWriter,
    topics: &Topics,
    opts: &RecordOptions,
    stop: &AtomicBool,
    progress: &mut impl FnMut(f64),
) -> Result<RecordSummary, RecordError> {
    let mut s = RecordSummary::default();
    let period = 1.0 / opts.publish_rate;
    let t_end = sim.time() + opts.duration;
    let eps = 1e-9 * sim.settings.dt;
    write_frame(sim, bag, topics, opts)?;
    s.frames_written += 1;
    let mut next_publish = sim.time() + period;
    while sim.time() + eps < t_end {
        if stop.load(Ordering::Relaxed) {
            s.interrupted = true;
            break;
        }
        let m = sim.step().map_err(|error| RecordError::Diverged {
            error,
            frames: s.frames_written,
        })?;
        s.steps += 1;
        s.subdivisions += m.subdivisions as u64;
        if sim.time() + eps >= next_publish {
            write_frame(sim, bag, topics, opts)?;
            s.frames_written += 1;
            // Skip publish instants a long frame step jumped over rather than bunching them.
            while next_publish <= sim.time() + eps {
                next_publish += period;
            }
        }
        progress(sim.time());
    }
    s.simulated_seconds = sim.time();
    Ok(s)
}

fn write_frame(
    sim: &Simulation,
    bag: &mut BagWriter,
    topics: &Topics,
    opts: &RecordOptions,
) -> Result<(), BagError> {
    let ns = (sim.time() * 1e9).round().max(0.0) as u64;
    let stamp = Time::from_nanos(ns);
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
    Ok(())
}
