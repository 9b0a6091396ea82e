//! `drape render` draws the scene's static obstacles: a scene YAML recorded with
//! `drape record` and drawn with `drape render` has pixels of the obstacles' colour where each
//! obstacle projects, a ground plane under the cloth, and none of either without them.
#![cfg(feature = "ros")]

use drape::render::{bounds, read_frames, Camera, RenderOptions};
use drape::Vec3;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A 0.6 m cloth centred at height `z`, held flat by its four corners, and `obstacles`.
fn scene(z: f64, obstacles: &str) -> String {
    format!(
        "name: render_obstacles
duration: 0.1
effects: [gravity, stretch, shear]
solver: {{ integrator: implicit, dt: 0.02 }}
cloths:
  - name: sheet
    grid: {{ size: [0.6, 0.6], resolution: [8, 8], pose: {{ xyz: [0, 0, {z:?}] }} }}
    pins: [ {{ region: top_left }}, {{ region: top_right }}, {{ region: bottom_left }}, {{ region: bottom_right }} ]
{obstacles}"
    )
}

/// A ball and a box on either side of the cloth (at z = 1), well below it and clear of it (no
/// contact). The default camera looks from azimuth -60 degrees, 22 degrees up: the line from
/// either one to the camera rises through z = 1 about 1.7 m away, far from the cloth.
const BALL: [f64; 3] = [0.8, 0.0, 0.3];
const BOX: [f64; 3] = [-0.8, 0.0, 0.3];

fn solids() -> String {
    format!(
        "obstacles:
  - {{ name: ball, shape: {{ type: sphere, radius: 0.15 }}, pose: {{ xyz: {BALL:?} }} }}
  - {{ name: crate, shape: {{ type: box, half_extents: [0.1, 0.1, 0.1] }}, pose: {{ xyz: {BOX:?} }} }}
"
    )
}

fn drape(args: &[&str], paths: &[&Path]) {
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .args(paths)
        .output()
        .expect("drape runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Records `scene` and renders its last frame (320x320); returns the bag and the RGB pixels.
fn record_and_render(dir: &Path, name: &str, scene: &str) -> (PathBuf, Vec<u8>) {
    let yaml = dir.join(format!("{name}.yaml"));
    std::fs::write(&yaml, scene).expect("scene written");
    let bag = dir.join(format!("{name}.mcap"));
    let png = dir.join(format!("{name}.png"));
    drape(
        &["record", "--quiet", "--scene"],
        &[&yaml, Path::new("--out"), &bag],
    );
    drape(&["render"], &[&bag, Path::new("--out"), &png]);
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&png).expect("png written"),
    ));
    let mut reader = decoder.read_info().expect("a png");
    let mut rgb = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgb).expect("png decodes");
    assert_eq!((info.width, info.height), (320, 320));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    (bag, rgb)
}

/// Obstacle green: the obstacles' base colour (0.40, 0.62, 0.42) keeps green at least 1.3x red
/// and blue under any shade (ambient and diffuse scale all three alike; the white specular
/// highlight adds the same to each and is small). Cloth is orange, background and ground grey.
fn is_obstacle(p: &[u8]) -> bool {
    let (r, g, b) = (f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
    g > 1.3 * r && g > 1.3 * b
}

/// Ground grey (0.80, 0.80, 0.76): blue under green by ~5 % of it; the background's blue is
/// above its green.
fn is_ground(p: &[u8]) -> bool {
    let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
    (r - g).abs() <= 3 && g - b >= 3 && g > 40
}

fn pixel(rgb: &[u8], (x, y): (usize, usize)) -> &[u8] {
    &rgb[(y * 320 + x) * 3..][..3]
}

/// The pixel where world point `p` projects, with the camera the renderer framed `bag` with.
fn projects(bag: &Path, p: Vec3) -> (usize, usize) {
    let o = RenderOptions::default();
    let frames = read_frames(bag, &o).expect("frames");
    let (c, r) = bounds(&frames);
    let cam = Camera::framing(
        c,
        r,
        o.azimuth.to_radians(),
        o.elevation.to_radians(),
        o.width,
        o.height,
    );
    let (x, y, _) = cam.project(p).expect("in front of the camera");
    assert!((0.0..320.0).contains(&x) && (0.0..320.0).contains(&y));
    (x as usize, y as usize)
}

#[test]
fn static_obstacles_are_drawn_where_they_project() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (bag, rgb) = record_and_render(dir.path(), "solids", &scene(1.0, &solids()));
    for centre in [BALL, BOX] {
        let (x, y) = projects(&bag, Vec3::from(centre));
        // The obstacle's centre and its 5x5 neighbourhood (a 0.1 m half size projects to tens
        // of pixels at this framing) are obstacle-coloured.
        for dy in 0..5 {
            for dx in 0..5 {
                let p = pixel(&rgb, (x + dx - 2, y + dy - 2));
                assert!(is_obstacle(p), "{centre:?} at ({x}, {y}): {p:?}");
            }
        }
    }
    let green = rgb.chunks(3).filter(|p| is_obstacle(p)).count();
    assert!(green > 500, "{green} obstacle pixels");
    // Without obstacles the same cloth has none.
    let (_, bare) = record_and_render(dir.path(), "bare", &scene(1.0, ""));
    let none = bare.chunks(3).filter(|p| is_obstacle(p)).count();
    assert_eq!(none, 0, "obstacle colour without obstacles");
}

#[test]
fn a_ground_plane_is_drawn_under_the_cloth_without_changing_the_framing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ground = "obstacles:\n  - { name: ground, shape: { type: plane, normal: [0, 0, 1] } }\n";
    let (bag, rgb) = record_and_render(dir.path(), "ground", &scene(0.15, ground));
    let (bare_bag, bare) = record_and_render(dir.path(), "bare", &scene(0.15, ""));
    // The unbounded plane is not framed: both pictures frame the cloth alone.
    let frames = read_frames(&bag, &RenderOptions::default()).expect("frames");
    assert_eq!(frames[0].planes.len(), 1);
    let bare_frames = read_frames(&bare_bag, &RenderOptions::default()).expect("frames");
    assert_eq!(bounds(&frames), bounds(&bare_frames));
    // A point of the ground beside the cloth on the camera's side (the cloth spans |y| <= 0.3),
    // within the framed sphere (radius ~0.42 about the cloth's centre).
    let below = projects(&bag, Vec3::new(0.1, -0.35, 0.0));
    assert!(is_ground(pixel(&rgb, below)), "{:?}", pixel(&rgb, below));
    assert!(!is_ground(pixel(&bare, below)), "{:?}", pixel(&bare, below));
    let grey = rgb.chunks(3).filter(|p| is_ground(p)).count();
    let none = bare.chunks(3).filter(|p| is_ground(p)).count();
    assert!(
        grey > 2000 && none < 50,
        "ground pixels {grey} vs {none} without"
    );
}
