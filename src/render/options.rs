//! What `drape render` is asked for ([`RenderOptions`], [`Pick`]) and why it can fail
//! ([`RenderError`], [`WriteError`]).

use crate::ros::BagError;
use std::path::PathBuf;

/// Most pixels of a PNG sheet (all its tiles): about 100 MB of RGB held at once.
pub const MAX_SHEET_PIXELS: usize = 32 << 20;

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
    /// Camera azimuth (degrees; `None`: the one of a few that shows the most cloth, see
    /// [`super::view`]) and elevation (degrees).
    pub azimuth: Option<f64>,
    pub elevation: f64,
    /// Draw the robot's collision shapes when the bag has a robot.
    pub robot: bool,
    /// Where `package://` meshes of the bag's robot are searched, besides where the run found
    /// them and the ROS environment.
    pub package_paths: Vec<PathBuf>,
    /// Write the scene's name and the frame's time on each tile.
    pub label: bool,
}

/// Widest a default picture grows (pixels): about a README's column.
pub const DEFAULT_SHEET_WIDTH: usize = 960;
/// Side of a default square tile when the row has room for it.
pub const DEFAULT_TILE: usize = 320;

impl RenderOptions {
    /// The default square tile side for `per_row` tiles in a row: [`DEFAULT_TILE`], smaller
    /// when the row would be wider than [`DEFAULT_SHEET_WIDTH`] (at least 96).
    pub fn default_tile(per_row: usize) -> usize {
        (DEFAULT_SHEET_WIDTH / per_row.max(1)).clamp(96, DEFAULT_TILE)
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: DEFAULT_TILE,
            height: DEFAULT_TILE,
            pick: Pick::Last,
            columns: None,
            azimuth: None,
            elevation: 22.0,
            robot: true,
            package_paths: Vec::new(),
            label: true,
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
