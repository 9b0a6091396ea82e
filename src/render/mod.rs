//! `drape render`: pictures of recorded bags without ROS or Foxglove, for dataset thumbnails and
//! the README.
//!
//! Reads `/drape/mesh` (the cloth, a TRIANGLE_LIST Marker), `/drape/obstacles` (the scene's
//! own obstacles, one Marker each, when it has any; see [`obstacles`]) and, for robot scenes,
//! `/robot_description` and `/tf`: the robot's collision shapes are drawn at the link poses of
//! the frame. Planes are drawn as a square under what the tile frames. Each picked frame of each bag is one tile, shaded by the software rasteriser in
//! [`raster`]; tiles are laid out in a grid (bags side by side by default, or the frames of one
//! bag as a strip). A `.gif` output animates the frames instead.

mod animation;
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
    /// A cloth frame with a NaN or infinite point: drawn, it would be blank or garbage.
    #[error("{}: the cloth frame at {time:.3} s on /drape/mesh has a non-finite point (point {point})", path.display())]
    NonFinite {
        path: PathBuf,
        time: f64,
        point: usize,
    },
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
    /// More tiles than a PNG sheet holds (`--frames`, `--at` or many bags).
    #[error("{tiles} tiles of {width}x{height} pixels: more than the {max} pixels a sheet may have (fewer --frames or --at times, or a smaller --size)", max = MAX_SHEET_PIXELS)]
    SheetTooLarge {
        tiles: usize,
        width: usize,
        height: usize,
    },
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

/// Most pixels of a PNG sheet (all its tiles): about 100 MB of RGB held at once.
pub const MAX_SHEET_PIXELS: usize = 32 << 20;

/// A bag opened for drawing: its bytes, the times of its cloth frames, and the robot and the
/// scene obstacles (small beside the cloth, read whole). Cloth markers are decoded only when
/// a frame is drawn, so memory does not grow with the number of frames.
pub(super) struct Source {
    pub bag: crate::ros::bag::BagBytes,
    pub times: Vec<u64>,
    robot: Option<(shapes::RobotShapes, TfSeries)>,
    obstacles: Vec<(u64, MarkerHead)>,
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
        let robot = if o.robot {
            robot_of(bag, &o.package_paths)
        } else {
            None
        };
        // A bag without scene obstacles has no such topic.
        let obstacles = read_topic::<MarkerHead>(bag, "/drape/obstacles")
            .map(|t| t.messages)
            .unwrap_or_default();
        Ok(Source {
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
        let mut meshes = vec![cloth_mesh(m)];
        if let Some((shapes, tf)) = &self.robot {
            let poses = tf_at(tf, t);
            meshes.extend(shapes.meshes(&poses));
        }
        let o = obstacles::at(&self.obstacles, t);
        meshes.extend(o.meshes);
        Ok(Frame {
            time_ns: t,
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

/// The box around the meshes of frames added one at a time (planes left out: unbounded).
#[derive(Debug, Clone, Copy)]
pub(super) struct Extent {
    lo: Vec3,
    hi: Vec3,
}

impl Extent {
    pub fn new() -> Extent {
        Extent {
            lo: Vec3::splat(f64::INFINITY),
            hi: Vec3::splat(f64::NEG_INFINITY),
        }
    }

    pub fn add(&mut self, f: &Frame) {
        for m in &f.meshes {
            for p in &m.positions {
                if p.is_finite() {
                    self.lo = self.lo.min(*p);
                    self.hi = self.hi.max(*p);
                }
            }
        }
    }

    /// Centre and radius of the bounding sphere (a unit sphere at the origin when empty).
    pub fn sphere(&self) -> (Vec3, f64) {
        if !self.lo.is_finite() {
            return (Vec3::ZERO, 1.0);
        }
        let c = (self.lo + self.hi) / 2.0;
        (c, ((self.hi - self.lo).length() / 2.0).max(0.05))
    }
}

/// Bounding sphere of the meshes of some frames (planes left out: unbounded): what each
/// tile's camera frames.
pub fn bounds(frames: &[Frame]) -> (Vec3, f64) {
    let mut e = Extent::new();
    for f in frames {
        e.add(f);
    }
    e.sphere()
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
    let mut count = 0usize;
    for bag in bags {
        let frames = read_frames(bag, o)?;
        count += frames.len();
        if count.saturating_mul(o.width * o.height) > MAX_SHEET_PIXELS {
            return Err(RenderError::SheetTooLarge {
                tiles: count,
                width: o.width,
                height: o.height,
            });
        }
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
/// frames (all frames unless picked otherwise) with the bags side by side, drawn and encoded one
/// frame at a time.
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
        let mut file = crate::output::Output::create(out, &inputs)?;
        animation::render_gif(bags, &mut file, o).map_err(|e| match e {
            animation::GifError::Render(r) => r,
            animation::GifError::Write(w) => write_err(w),
        })?;
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
