//! `drape render`: pictures of recorded bags without ROS or Foxglove, for dataset thumbnails and
//! the README.
//!
//! Reads `/drape/mesh` (the cloth, a TRIANGLE_LIST Marker; each cloth piece the bag's metadata
//! lists in its own colour), `/drape/obstacles` (the scene's own obstacles, one Marker each, when
//! it has any; see [`obstacles`]) and, for robot scenes, `/robot_description` and `/tf`: the
//! robot's collision shapes are drawn at the link poses of the frame. The scene file the bag's
//! metadata names is read again (see `recorded.rs`) to find the robot's meshes where the
//! recording found them and to draw the scene's static obstacles a bag lacks. Planes are drawn as
//! a square under what the tile frames. Each picked frame of each bag is one tile, shaded by the
//! software rasteriser in [`raster`], seen from the side that shows the most cloth ([`view()`])
//! and labelled with the scene's name and the time; tiles are laid out in a grid (bags side by
//! side by default, or the frames of one bag as a strip). A `.gif` output animates the frames
//! instead.

mod animation;
mod draw;
mod frames;
mod label;
mod marker;
pub mod obstacles;
mod options;
pub mod raster;
mod recorded;
mod shapes;
mod view;

pub use draw::{draw_frame, sheet};
pub use frames::{read_frames, Frame, CLOTH_PALETTE};
pub use options::{
    Pick, RenderError, RenderOptions, WriteError, DEFAULT_SHEET_WIDTH, DEFAULT_TILE,
    MAX_SHEET_PIXELS,
};
pub use raster::{Camera, Image, Mesh, Raster};
pub use view::{bounds, view, View, DEFAULT_AZIMUTH};

use std::path::{Path, PathBuf};

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
        let v = view(&frames, o);
        out.push(frames.iter().map(|f| draw_frame(f, &v, o)).collect());
    }
    Ok(out)
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
