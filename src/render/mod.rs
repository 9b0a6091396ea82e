//! `drape render`: pictures of recorded bags without ROS or Foxglove, for dataset thumbnails and
//! the README.
//!
//! Reads `/drape/mesh` (the cloth, a TRIANGLE_LIST Marker), `/drape/obstacles` (the scene's
//! own obstacles, one Marker each, when it has any; see [`obstacles`]) and, for robot scenes,
//! `/robot_description` and `/tf`: the robot's collision shapes are drawn at the link poses of
//! the frame. Planes are drawn as a square under what the tile frames. Each picked frame of each bag is one tile, shaded by the software rasteriser in
//! [`raster`]; tiles are laid out in a grid (bags side by side by default, or the frames of one
//! bag as a strip). A `.gif` output animates the frames instead.

mod marker;
pub mod obstacles;
pub mod raster;
mod shapes;

use marker::MarkerHead;

pub use raster::{Camera, Image, Mesh, Raster};

use crate::ros::msg::{RosString, TFMessage};
use crate::ros::{read_topic, BagError};
use crate::{Pose, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Which frames of each bag to draw.
#[derive(Debug, Clone, PartialEq)]
pub enum Pick {
    /// The last frame.
    Last,
    /// The frames nearest these times (s).
    Times(Vec<f64>),
    /// `n` frames evenly spread from the first to the last.
    Spread(usize),
    /// Every frame (for animations).
    All,
}

/// How to draw.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Tile size in pixels.
    pub width: usize,
    pub height: usize,
    pub pick: Pick,
    /// Tiles per row (default: the bags side by side when one frame is picked, else the frames
    /// of each bag in a row).
    pub columns: Option<usize>,
    /// Camera azimuth and elevation (degrees).
    pub azimuth: f64,
    pub elevation: f64,
    /// Draw the robot's collision shapes when the bag has a robot.
    pub robot: bool,
    /// Where `package://` meshes of the bag's robot are searched.
    pub package_paths: Vec<PathBuf>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 320,
            height: 320,
            pick: Pick::Last,
            columns: None,
            azimuth: -60.0,
            elevation: 22.0,
            robot: true,
            package_paths: Vec::new(),
        }
    }
}

/// Why a picture could not be made; the cause, if any, is the `source()`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    #[error(transparent)]
    Bag(#[from] BagError),
    #[error("{}: no cloth frames on /drape/mesh", path.display())]
    Empty { path: PathBuf },
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: WriteError,
    },
    /// The picture would overwrite an input, or cannot be written whole.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    #[error("tile size {width}x{height} is out of range (at most 16 million pixels)")]
    TileSize { width: usize, height: usize },
    #[error("no bag to render")]
    NoBags,
}

/// Why a PNG or GIF could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Png(#[from] png::EncodingError),
    #[error(transparent)]
    Gif(#[from] gif::EncodingError),
    #[error("no frames to animate")]
    NoFrames,
    #[error("{width}x{height} pixels is too large for a GIF (at most 65535 a side)")]
    TooLargeForGif { width: usize, height: usize },
}

/// One frame of a bag: the cloth as a welded mesh, the robot's shapes and the scene's solid
/// obstacles (`meshes`, which the camera frames), and the scene's planes as (point, normal).
#[derive(Debug, Clone)]
pub struct Frame {
    pub time_ns: u64,
    pub meshes: Vec<Mesh>,
    pub planes: Vec<(Vec3, Vec3)>,
}

/// The frames of a bag to draw.
pub fn read_frames(bag: &Path, o: &RenderOptions) -> Result<Vec<Frame>, RenderError> {
    let pick = &o.pick;
    let mesh = read_topic::<MarkerHead>(bag, "/drape/mesh")?;
    if mesh.messages.is_empty() {
        return Err(RenderError::Empty {
            path: bag.to_path_buf(),
        });
    }
    let n = mesh.messages.len();
    let t0 = mesh.messages[0].0;
    let chosen: Vec<usize> = match pick {
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
                        let da = (mesh.messages[a].0 as f64 - target).abs();
                        let db = (mesh.messages[b].0 as f64 - target).abs();
                        da.total_cmp(&db)
                    })
                    .unwrap_or(n - 1)
            })
            .collect(),
    };
    let robot_shapes = if o.robot {
        robot_of(bag, &o.package_paths)
    } else {
        None
    };
    // A bag without scene obstacles has no such topic.
    let scene_obstacles = read_topic::<MarkerHead>(bag, "/drape/obstacles")
        .map(|t| t.messages)
        .unwrap_or_default();
    let mut frames = Vec::new();
    for i in chosen {
        let (t, m) = &mesh.messages[i];
        let mut meshes = vec![cloth_mesh(m)];
        if let Some((shapes, tf)) = &robot_shapes {
            let poses = tf_at(tf, *t);
            meshes.extend(shapes.meshes(&poses));
        }
        let o = obstacles::at(&scene_obstacles, *t);
        meshes.extend(o.meshes);
        frames.push(Frame {
            time_ns: *t,
            meshes,
            planes: o.planes,
        });
    }
    Ok(frames)
}

/// The marker's triangle soup welded by exact position (the recorder writes each vertex's
/// coordinates identically in every triangle), with smooth normals.
fn cloth_mesh(m: &MarkerHead) -> Mesh {
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut mesh = Mesh {
        color: [m.color.r, m.color.g, m.color.b].map(f64::from),
        ..Mesh::default()
    };
    let mut tri = [0u32; 3];
    for (k, p) in m.points.iter().enumerate() {
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
    if mesh.color.iter().all(|c| *c <= 0.0) {
        mesh.color = [0.85, 0.35, 0.2];
    }
    mesh.smooth_normals();
    mesh
}

type TfSeries = Vec<(u64, TFMessage)>;

/// The robot's shapes and its `/tf` messages, when the bag has a robot.
fn robot_of(bag: &Path, package_paths: &[PathBuf]) -> Option<(shapes::RobotShapes, TfSeries)> {
    let desc = read_topic::<RosString>(bag, "/robot_description").ok()?;
    let urdf = &desc.messages.first()?.1.data;
    let shapes = match shapes::RobotShapes::from_urdf(urdf, package_paths) {
        Ok(s) => s,
        Err(e) => {
            let e = crate::input::error_line(&e);
            log::warn!("{}: the robot is not drawn: {e}", bag.display());
            return None;
        }
    };
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

/// Bounding sphere of the meshes of some frames (planes left out: unbounded): what each
/// tile's camera frames.
pub fn bounds(frames: &[Frame]) -> (Vec3, f64) {
    let mut lo = Vec3::splat(f64::INFINITY);
    let mut hi = Vec3::splat(f64::NEG_INFINITY);
    for f in frames {
        for m in &f.meshes {
            for p in &m.positions {
                if p.is_finite() {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
            }
        }
    }
    if !lo.is_finite() {
        return (Vec3::ZERO, 1.0);
    }
    let c = (lo + hi) / 2.0;
    (c, ((hi - lo).length() / 2.0).max(0.05))
}

/// Draws one frame as one tile, with a camera framing `bounds`.
pub fn draw_frame(frame: &Frame, bounds: (Vec3, f64), o: &RenderOptions) -> Image {
    let cam = Camera::framing(
        bounds.0,
        bounds.1,
        o.azimuth.to_radians(),
        o.elevation.to_radians(),
        o.width,
        o.height,
    );
    let mut r = Raster::new(o.width, o.height, &cam);
    for &(point, normal) in &frame.planes {
        r.draw(&cam, &obstacles::plane_square(point, normal, bounds));
    }
    for m in &frame.meshes {
        r.draw(&cam, m);
    }
    r.image
}

/// The tiles of every bag (bag-major), each bag framed on its own over its picked frames.
pub fn tiles(bags: &[PathBuf], o: &RenderOptions) -> Result<Vec<Vec<Image>>, RenderError> {
    if o.width == 0 || o.height == 0 || o.width * o.height > 16_000_000 {
        return Err(RenderError::TileSize {
            width: o.width,
            height: o.height,
        });
    }
    let mut out = Vec::new();
    for bag in bags {
        let frames = read_frames(bag, o)?;
        let b = bounds(&frames);
        out.push(frames.iter().map(|f| draw_frame(f, b, o)).collect());
    }
    Ok(out)
}

/// All tiles in one picture, `columns` per row.
pub fn sheet(tiles: &[Vec<Image>], o: &RenderOptions) -> Image {
    let flat: Vec<&Image> = tiles.iter().flatten().collect();
    let per_bag = tiles.first().map_or(1, Vec::len).max(1);
    let columns = o
        .columns
        .unwrap_or(if per_bag == 1 { flat.len() } else { per_bag })
        .clamp(1, flat.len().max(1));
    let rows = flat.len().div_ceil(columns).max(1);
    let mut img = Image::background(columns * o.width, rows * o.height);
    for (k, t) in flat.iter().enumerate() {
        img.blit(t, (k % columns) * o.width, (k / columns) * o.height);
    }
    img
}

/// Renders `bags` to `out`: a PNG sheet of the picked frames, or for `.gif` an animation of the
/// frames (all frames unless picked otherwise) with the bags side by side.
pub fn render(bags: &[PathBuf], out: &Path, o: &RenderOptions) -> Result<(), RenderError> {
    if bags.is_empty() {
        return Err(RenderError::NoBags);
    }
    let inputs: Vec<&Path> = bags.iter().map(PathBuf::as_path).collect();
    crate::output::check(out, &inputs)?;
    let gif = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    let write_err = |source: WriteError| RenderError::Write {
        path: out.to_path_buf(),
        source,
    };
    if gif {
        let mut opts = o.clone();
        if opts.pick == Pick::Last {
            opts.pick = Pick::All;
        }
        let t = tiles(bags, &opts)?;
        let n = t.iter().map(Vec::len).min().unwrap_or(0);
        let frames: Vec<Image> = (0..n)
            .map(|i| {
                let row: Vec<Vec<Image>> = t.iter().map(|b| vec![b[i].clone()]).collect();
                sheet(
                    &row,
                    &RenderOptions {
                        columns: Some(bags.len()),
                        ..opts.clone()
                    },
                )
            })
            .collect();
        let times = read_topic::<MarkerHead>(&bags[0], "/drape/mesh")?;
        let period_ns = times
            .messages
            .windows(2)
            .next()
            .map_or(33_333_333, |w| w[1].0.saturating_sub(w[0].0));
        let stride = match &opts.pick {
            Pick::Spread(k) if *k > 1 => (times.messages.len().saturating_sub(1)) / (k - 1),
            _ => 1,
        }
        .max(1);
        let delay_cs = ((period_ns as f64 * stride as f64) / 1e7).round().max(2.0) as u16;
        let mut file = crate::output::Output::create(out, &inputs)?;
        write_gif(&mut file, &frames, delay_cs).map_err(write_err)?;
        Ok(file.finish()?)
    } else {
        let t = tiles(bags, o)?;
        let mut file = crate::output::Output::create(out, &inputs)?;
        write_png(&mut file, &sheet(&t, o)).map_err(write_err)?;
        Ok(file.finish()?)
    }
}

/// Writes an RGB PNG to `out` (e.g. a [`crate::output::Output`]).
pub fn write_png(out: impl std::io::Write, img: &Image) -> Result<(), WriteError> {
    let mut enc = png::Encoder::new(out, img.width as u32, img.height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header()?;
    w.write_image_data(&img.rgb)?;
    Ok(w.finish()?)
}

/// Writes a looping GIF to `out`, `delay_cs` hundredths of a second per frame; every byte,
/// the trailer included, is written (or the error returned) before this returns.
pub fn write_gif(
    out: impl std::io::Write,
    frames: &[Image],
    delay_cs: u16,
) -> Result<(), WriteError> {
    let first = frames.first().ok_or(WriteError::NoFrames)?;
    let (Ok(w), Ok(h)) = (u16::try_from(first.width), u16::try_from(first.height)) else {
        return Err(WriteError::TooLargeForGif {
            width: first.width,
            height: first.height,
        });
    };
    let mut enc = gif::Encoder::new(out, w, h, &[])?;
    enc.set_repeat(gif::Repeat::Infinite)?;
    for f in frames {
        let mut frame = gif::Frame::from_rgb_speed(w, h, &f.rgb, 10);
        frame.delay = delay_cs;
        enc.write_frame(&frame)?;
    }
    let mut out = enc.into_inner()?;
    std::io::Write::flush(&mut out)?;
    Ok(())
}
