//! One frame as one tile, and tiles laid out in one picture.

use super::frames::Frame;
use super::label::draw_label;
use super::obstacles;
use super::options::RenderOptions;
use super::raster::{Image, Raster};
use super::view::View;

/// Draws one frame as one tile seen as `view` says, labelled with the scene and the time
/// unless `o.label` is off.
pub fn draw_frame(frame: &Frame, view: &View, o: &RenderOptions) -> Image {
    let cam = view.camera(o.elevation, o.width, o.height);
    let mut r = Raster::new(o.width, o.height, &cam);
    for &(point, normal) in &frame.planes {
        r.draw(
            &cam,
            &obstacles::plane_square(point, normal, (view.center, view.radius)),
        );
    }
    for m in &frame.meshes {
        r.draw(&cam, m);
    }
    let mut img = r.image;
    if o.label {
        draw_label(&mut img, &frame.scene, frame.seconds);
    }
    img
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
