//! The frames of a bag: its cloth markers (decoded only when a frame is drawn), the robot at
//! the frame's link poses and the scene's obstacles, and the box the camera frames.

use super::marker::MarkerHead;
use super::obstacles;
use super::options::{Pick, RenderError, RenderOptions, MAX_SHEET_PIXELS};
use super::raster::Mesh;
use super::recorded::Recorded;
use super::shapes;
use crate::ros::msg::{RosString, TFMessage};
use crate::ros::read_topic;
use crate::{Pose, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One frame of a bag: each cloth as a welded mesh in its colour, the robot's shapes and the
/// scene's solid obstacles (`meshes`, which the camera frames), and the scene's planes as
/// (point, normal).
#[derive(Debug, Clone)]
pub struct Frame {
    pub time_ns: u64,
    /// Seconds since the bag's first cloth frame.
    pub seconds: f64,
    /// The scene's name (or the bag's file name), written on the tile.
    pub scene: String,
    /// The first `cloths` of `meshes` are the cloths.
    pub cloths: usize,
    pub meshes: Vec<Mesh>,
    pub planes: Vec<(Vec3, Vec3)>,
}

/// Colours of the cloths, in the order of the bag's cloth pieces: apart from the robot's
/// blue-grey, the obstacles' green and the grey ground. The first cloth keeps the marker's
/// own colour when it has one.
pub const CLOTH_PALETTE: [[f64; 3]; 6] = [
    [0.85, 0.35, 0.20],
    [0.58, 0.32, 0.75],
    [0.92, 0.74, 0.15],
    [0.85, 0.25, 0.52],
    [0.15, 0.68, 0.78],
    [0.55, 0.38, 0.22],
];

/// A bag opened for drawing: its bytes, the times of its cloth frames, and the robot and the
/// scene obstacles (small beside the cloth, read whole). Cloth markers are decoded only when
/// a frame is drawn, so memory does not grow with the number of frames.
pub(super) struct Source {
    pub bag: crate::ros::bag::BagBytes,
    pub times: Vec<u64>,
    robot: Option<(shapes::RobotShapes, TfSeries)>,
    obstacles: Vec<(u64, MarkerHead)>,
    scene: String,
    /// Triangles of each cloth, in marker order (empty: the marker is one cloth).
    pieces: Vec<usize>,
}

impl Source {
    pub fn open(bag: &Path, o: &RenderOptions) -> Result<Source, RenderError> {
        let bytes = crate::ros::bag::BagBytes::read(bag)?;
        let mut times = Vec::new();
        for m in bytes.topic::<MarkerHead>("/drape/mesh")? {
            times.push(m?.0);
        }
        if times.is_empty() {
            // The same checks and messages as a whole read (no such topic, truncated, empty).
            let mesh = read_topic::<MarkerHead>(bag, "/drape/mesh")?;
            if mesh.messages.is_empty() {
                return Err(RenderError::Empty {
                    path: bag.to_path_buf(),
                });
            }
        }
        let recorded = Recorded::of(&bytes);
        let robot = if o.robot {
            robot_of(bag, &recorded, &o.package_paths)
        } else {
            None
        };
        // A bag without scene obstacles has no such topic: the scene it names may have some.
        let obstacles = match read_topic::<MarkerHead>(bag, "/drape/obstacles") {
            Ok(t) => t.messages,
            Err(_) => recorded.static_obstacles(bag),
        };
        Ok(Source {
            scene: recorded.name(bag),
            pieces: recorded.info.cloth_pieces.iter().map(|(_, n)| *n).collect(),
            bag: bytes,
            times,
            robot,
            obstacles,
        })
    }

    /// The frames `pick` chooses, as indices into [`Source::times`].
    pub fn chosen(&self, pick: &Pick) -> Vec<usize> {
        let n = self.times.len();
        let t0 = self.times[0];
        match pick {
            Pick::Last => vec![n - 1],
            Pick::All => (0..n).collect(),
            Pick::Spread(k) => {
                let k = (*k).clamp(1, n);
                if k == 1 {
                    vec![n - 1]
                } else {
                    (0..k).map(|i| i * (n - 1) / (k - 1)).collect()
                }
            }
            Pick::Times(ts) => ts
                .iter()
                .map(|t| {
                    let target = t0 as f64 + t * 1e9;
                    (0..n)
                        .min_by(|&a, &b| {
                            let da = (self.times[a] as f64 - target).abs();
                            let db = (self.times[b] as f64 - target).abs();
                            da.total_cmp(&db)
                        })
                        .unwrap_or(n - 1)
                })
                .collect(),
        }
    }

    /// The frame of cloth marker `m` at `t`: the cloth, the robot at its poses, the obstacles;
    /// a non-finite cloth point is an error naming the frame.
    pub fn frame(&self, t: u64, m: &MarkerHead) -> Result<Frame, RenderError> {
        if let Some(k) = m
            .points
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()))
        {
            return Err(RenderError::NonFinite {
                path: self.bag.path().to_path_buf(),
                time: t.saturating_sub(self.times[0]) as f64 * 1e-9,
                point: k,
            });
        }
        let mut meshes = cloth_meshes(m, &self.pieces);
        let cloths = meshes.len();
        if let Some((shapes, tf)) = &self.robot {
            let poses = tf_at(tf, t);
            meshes.extend(shapes.meshes(&poses));
        }
        let o = obstacles::at(&self.obstacles, t);
        meshes.extend(o.meshes);
        Ok(Frame {
            time_ns: t,
            seconds: t.saturating_sub(self.times[0]) as f64 * 1e-9,
            scene: self.scene.clone(),
            cloths,
            meshes,
            planes: o.planes,
        })
    }

    /// The cloth markers at `indices` (ascending, no repeats), decoded in one pass.
    pub fn markers(
        &self,
        indices: &[usize],
        mut each: impl FnMut(usize, u64, MarkerHead) -> Result<(), RenderError>,
    ) -> Result<(), RenderError> {
        let mut want = indices.iter().copied().peekable();
        for (k, m) in self.bag.topic::<MarkerHead>("/drape/mesh")?.enumerate() {
            let Some(&next) = want.peek() else { break };
            let (t, m) = m?;
            if k == next {
                want.next();
                each(k, t, m)?;
            }
        }
        Ok(())
    }
}

/// The frames of a bag to draw (only the picked markers are decoded and kept).
pub fn read_frames(bag: &Path, o: &RenderOptions) -> Result<Vec<Frame>, RenderError> {
    let src = Source::open(bag, o)?;
    let chosen = src.chosen(&o.pick);
    if chosen
        .len()
        .saturating_mul(o.width.saturating_mul(o.height))
        > MAX_SHEET_PIXELS
    {
        return Err(RenderError::SheetTooLarge {
            tiles: chosen.len(),
            width: o.width,
            height: o.height,
        });
    }
    let mut unique = chosen.clone();
    unique.sort_unstable();
    unique.dedup();
    let mut frames: HashMap<usize, Frame> = HashMap::new();
    src.markers(&unique, |k, t, m| {
        frames.insert(k, src.frame(t, &m)?);
        Ok(())
    })?;
    Ok(chosen
        .iter()
        .filter_map(|k| frames.get(k).cloned())
        .collect())
}

/// The marker's triangle soup as one mesh per cloth (`pieces`: triangles of each, in order;
/// ignored unless they add up to the marker's triangles), each in its palette colour and
/// welded by exact position (the recorder writes each vertex's coordinates identically in
/// every triangle), with smooth normals.
fn cloth_meshes(m: &MarkerHead, pieces: &[usize]) -> Vec<Mesh> {
    let triangles = m.points.len() / 3;
    let whole = [triangles];
    let counts = if pieces.iter().sum::<usize>() == triangles && !pieces.is_empty() {
        pieces
    } else {
        &whole[..]
    };
    let own = [m.color.r, m.color.g, m.color.b].map(f64::from);
    let mut out = Vec::with_capacity(counts.len());
    let mut first = 0;
    for (k, &n) in counts.iter().enumerate() {
        let color = if k == 0 && own.iter().any(|c| *c > 0.0) {
            own
        } else {
            CLOTH_PALETTE[k % CLOTH_PALETTE.len()]
        };
        out.push(weld(&m.points[3 * first..3 * (first + n)], color));
        first += n;
    }
    out
}

/// A triangle soup welded by exact position, with smooth normals.
fn weld(points: &[crate::ros::msg::Point], color: [f64; 3]) -> Mesh {
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut mesh = Mesh {
        color,
        ..Mesh::default()
    };
    let mut tri = [0u32; 3];
    for (k, p) in points.iter().enumerate() {
        let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let next = mesh.positions.len() as u32;
        let i = *index.entry(key).or_insert_with(|| {
            mesh.positions.push(Vec3::new(p.x, p.y, p.z));
            next
        });
        tri[k % 3] = i;
        if k % 3 == 2 {
            mesh.triangles.push(tri);
        }
    }
    mesh.smooth_normals();
    mesh
}

type TfSeries = Vec<(u64, TFMessage)>;

/// The robot's shapes and its `/tf` messages, when the bag has a robot; its meshes are looked
/// for where the run found them (see [`Recorded::urdf_options`]), and those still missing are
/// named in one warning while the rest is drawn.
fn robot_of(
    bag: &Path,
    recorded: &Recorded,
    package_paths: &[PathBuf],
) -> Option<(shapes::RobotShapes, TfSeries)> {
    let desc = read_topic::<RosString>(bag, "/robot_description").ok()?;
    let urdf = &desc.messages.first()?.1.data;
    let (dir, opts) = recorded.urdf_options(package_paths);
    let shapes = match shapes::RobotShapes::from_urdf(urdf, dir.as_deref(), &opts) {
        Ok(s) => s,
        Err(e) => {
            let e = crate::input::error_line(&e);
            log::warn!("{}: the robot is not drawn: {e}", bag.display());
            return None;
        }
    };
    if !shapes.missing.is_empty() {
        log::warn!(
            "{}: robot meshes not found, drawn without them: {} (add --package-path)",
            bag.display(),
            shapes.missing.join(", ")
        );
    }
    let tf = read_topic::<TFMessage>(bag, "/tf").ok()?.messages;
    Some((shapes, tf))
}

/// Link poses (by child frame name) of the last `/tf` at or before `t`.
fn tf_at(tf: &TfSeries, t: u64) -> HashMap<String, Pose> {
    let msg = tf
        .iter()
        .take_while(|(s, _)| *s <= t)
        .last()
        .or(tf.first())
        .map(|(_, m)| m);
    let mut out = HashMap::new();
    if let Some(m) = msg {
        for ts in &m.transforms {
            let tr = &ts.transform;
            let q =
                glam::DQuat::from_xyzw(tr.rotation.x, tr.rotation.y, tr.rotation.z, tr.rotation.w);
            out.insert(
                ts.child_frame_id.clone(),
                Pose::new(
                    Vec3::new(tr.translation.x, tr.translation.y, tr.translation.z),
                    q.normalize(),
                ),
            );
        }
    }
    out
}
