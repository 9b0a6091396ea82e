//! `drape render` draws what a bag holds with no flags: a scene YAML recorded with
//! `drape record` and drawn with `drape render` has pixels of the obstacles' colour where each
//! obstacle projects (also when only the scene the bag names has them), a ground plane under
//! the cloth, the robot with the meshes the recording found, each cloth in its own colour, a
//! view that shows the cloth, and the scene's name and the time on each tile.
#![cfg(feature = "ros")]

use drape::render::{read_frames, view, RenderOptions, CLOTH_PALETTE, DEFAULT_AZIMUTH};
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

/// The pixel where world point `p` projects, with the camera the renderer chose for `bag`.
fn projects(bag: &Path, p: Vec3) -> (usize, usize) {
    let o = RenderOptions::default();
    let frames = read_frames(bag, &o).expect("frames");
    let cam = view(&frames, &o).camera(o.elevation, o.width, o.height);
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
    let o = RenderOptions::default();
    assert_eq!(view(&frames, &o), view(&bare_frames, &o));
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

// ------------------------------------------------------------------ robot, cloths, labels

/// Runs drape in `cwd` (a folder that is neither the scene's nor the repository) and returns its
/// stderr; fails on a non-zero exit.
fn drape_in(cwd: &Path, args: &[&std::ffi::OsStr]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .current_dir(cwd)
        .args(args)
        .output()
        .expect("drape runs");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    err
}

fn read_png(path: &Path) -> (usize, usize, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).expect("png written"),
    ));
    let mut reader = decoder.read_info().expect("a png");
    let mut rgb = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgb).expect("png decodes");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    (info.width as usize, info.height as usize, rgb)
}

/// Records `scene` (written to `dir/scene/<name>.yaml`) into `dir/<name>.mcap` from `dir/elsewhere`.
fn record_in(dir: &Path, name: &str, scene: &str) -> PathBuf {
    std::fs::create_dir_all(dir.join("scene")).expect("scene folder");
    std::fs::create_dir_all(dir.join("elsewhere")).expect("cwd");
    let yaml = dir.join("scene").join(format!("{name}.yaml"));
    std::fs::write(&yaml, scene).expect("scene written");
    let bag = dir.join(format!("{name}.mcap"));
    drape_in(
        &dir.join("elsewhere"),
        &[
            "record".as_ref(),
            "--quiet".as_ref(),
            "--scene".as_ref(),
            yaml.as_os_str(),
            "--out".as_ref(),
            bag.as_os_str(),
        ],
    );
    bag
}

/// Renders `bag` to `dir/<out>` from `dir/elsewhere` with `flags`; the stderr and the pixels.
fn render_in(dir: &Path, bag: &Path, out: &str, flags: &[&str]) -> (String, Vec<u8>) {
    let png = dir.join(out);
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "render".as_ref(),
        bag.as_os_str(),
        "--out".as_ref(),
        png.as_os_str(),
    ];
    args.extend(flags.iter().map(std::ffi::OsStr::new));
    let err = drape_in(&dir.join("elsewhere"), &args);
    let (w, h, rgb) = read_png(&png);
    assert_eq!((w, h), (320, 320), "{out}");
    (err, rgb)
}

/// The bundled robot copied into `dir/robot` (URDF and, if `with_mesh`, its head mesh): a
/// package found only through the URDF's own folder.
fn robot_package(dir: &Path, with_mesh: bool) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf");
    std::fs::create_dir_all(dir.join("robot/meshes")).expect("robot folder");
    std::fs::copy(src.join("drape_bot.urdf"), dir.join("robot/drape_bot.urdf")).expect("urdf");
    if with_mesh {
        std::fs::copy(
            src.join("meshes/head.stl"),
            dir.join("robot/meshes/head.stl"),
        )
        .expect("mesh");
    }
}

/// A cape hung 5 cm behind drape_bot's torso (as the README's robot_cape scene): from the
/// default azimuth the torso hides most of it.
const CAPE: &str = "name: render_cape
duration: 0.1
effects: [gravity, stretch, shear]
solver: { integrator: implicit, dt: 0.02 }
cloths:
  - name: cape
    grid: { size: [0.6, 0.6], resolution: [10, 10], pose: { xyz: [-0.2, 0.0, 0.4], rpy: [1.5707963267948966, 0.0, 1.5707963267948966] } }
robot:
  urdf: ../robot/drape_bot.urdf
  attach:
    - { cloth: cape, link: torso, region: top_edge }
collision: { mode: continuous }
";

/// The robot's blue-grey (0.45, 0.55, 0.68): blue over green over red, blue 1.2 to 1.8 times
/// red under any shade (ambient and diffuse scale all three alike; the specular highlight adds
/// the same to each). Background and ground have red equal to green; no cloth colour is close.
fn is_robot(p: &[u8]) -> bool {
    let (r, g, b) = (f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
    b > g + 4.0 && g > r + 4.0 && b > 1.2 * r && b < 1.8 * r
}

/// Pixels within `tol` of a shade of `color` (same channel ratios, any brightness; the
/// specular highlight is left out by requiring the darkest channel to keep its ratio).
fn is_shade_of(p: &[u8], color: [f64; 3], tol: f64) -> bool {
    let max = color.iter().copied().fold(0.0, f64::max);
    let k = p.iter().map(|&c| f64::from(c)).fold(0.0, f64::max) / (255.0 * max);
    k > 0.15
        && p.iter()
            .zip(color)
            .all(|(&c, want)| (f64::from(c) - 255.0 * want * k).abs() <= tol * 255.0 * k)
}

fn count(rgb: &[u8], f: impl Fn(&[u8]) -> bool) -> usize {
    rgb.chunks(3).filter(|p| f(p)).count()
}

#[test]
fn the_robot_is_drawn_with_the_meshes_the_recording_found_and_without_flags() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    robot_package(d, true);
    let bag = record_in(d, "cape", CAPE);
    let (err, rgb) = render_in(d, &bag, "cape.png", &[]);
    assert!(!err.contains("not found"), "{err}");
    let (_, bare) = render_in(d, &bag, "bare.png", &["--no-robot"]);
    let robot = count(&rgb, is_robot);
    assert_eq!(count(&bare, is_robot), 0, "robot colour without the robot");
    assert!(robot > 3000, "{robot} robot pixels");
    // The head is the robot's one mesh: without its file the rest is drawn, the head is
    // named in one warning, and fewer pixels are the robot's.
    let with_head = read_frames(&bag, &RenderOptions::default()).expect("frames")[0]
        .meshes
        .len();
    std::fs::remove_file(d.join("robot/meshes/head.stl")).expect("mesh removed");
    let (err, headless) = render_in(d, &bag, "headless.png", &[]);
    let warnings: Vec<&str> = err.lines().filter(|l| l.contains("head.stl")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(warnings[0].contains("not found"), "{err}");
    let without = count(&headless, is_robot);
    assert!(without > 1000 && without < robot, "{without} vs {robot}");
    let frames = read_frames(&bag, &RenderOptions::default()).expect("frames");
    assert_eq!(frames[0].meshes.len(), with_head - 1);
}

#[test]
fn the_view_shows_a_cape_the_default_azimuth_hides_behind_the_torso() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    robot_package(d, true);
    let bag = record_in(d, "cape", CAPE);
    let cloth = |p: &[u8]| is_shade_of(p, CLOTH_PALETTE[0], 0.12);
    let (_, chosen) = render_in(d, &bag, "chosen.png", &[]);
    let default = format!("{DEFAULT_AZIMUTH}");
    let (_, hidden) = render_in(d, &bag, "hidden.png", &["--azimuth", &default]);
    let (seen, behind) = (count(&chosen, cloth), count(&hidden, cloth));
    assert!(
        seen > 2 * behind && seen > 3000,
        "{seen} cloth pixels in the chosen view, {behind} from the default azimuth"
    );
    // The view still frames the robot: it is drawn too.
    assert!(count(&chosen, is_robot) > 3000);
}

#[test]
fn each_cloth_has_its_own_colour() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let sheet = |name: &str, x: f64| {
        format!(
            "  - name: {name}
    grid: {{ size: [0.4, 0.4], resolution: [6, 6], pose: {{ xyz: [{x:?}, 0, 1] }} }}
    pins: [ {{ region: top_left }}, {{ region: top_right }}, {{ region: bottom_left }}, {{ region: bottom_right }} ]
"
        )
    };
    let scene = format!(
        "name: two_sheets
duration: 0.1
effects: [gravity, stretch, shear]
solver: {{ integrator: implicit, dt: 0.02 }}
cloths:
{}{}",
        sheet("left", -0.35),
        sheet("right", 0.35)
    );
    let bag = record_in(d, "two", &scene);
    let (_, rgb) = render_in(d, &bag, "two.png", &[]);
    let at = |x: f64| {
        let (px, py) = projects(&bag, Vec3::new(x, 0.0, 1.0));
        pixel(&rgb, (px, py)).to_vec()
    };
    let (left, right) = (at(-0.35), at(0.35));
    assert!(is_shade_of(&left, CLOTH_PALETTE[0], 0.12), "{left:?}");
    assert!(is_shade_of(&right, CLOTH_PALETTE[1], 0.12), "{right:?}");
    // Each colour covers a good part of the picture.
    for c in &CLOTH_PALETTE[..2] {
        let n = count(&rgb, |p| is_shade_of(p, *c, 0.12));
        assert!(n > 1500, "{n} pixels of {c:?}");
    }
}

#[test]
fn each_tile_is_labelled_with_the_scene_and_the_time() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let bag = record_in(d, "label", &scene(1.0, ""));
    let (_, labelled) = render_in(d, &bag, "labelled.png", &[]);
    let (_, bare) = render_in(d, &bag, "bare.png", &["--no-label"]);
    let (_, first) = render_in(d, &bag, "first.png", &["--at", "0"]);
    // The label is dark text in the top left corner: two lines of 7-pixel glyphs, the longer
    // `render_obstacles` (16 glyphs of 6 pixels).
    let corner = |x: usize, y: usize| x < 4 + 16 * 6 + 2 && y < 4 + 17 + 2;
    let mut inside = 0;
    for y in 0..320 {
        for x in 0..320 {
            let (a, b) = (pixel(&labelled, (x, y)), pixel(&bare, (x, y)));
            if a != b {
                assert!(corner(x, y), "({x}, {y}) changed outside the label");
                inside += 1;
            }
        }
    }
    let ink = (0..320 * 320)
        .filter(|k| corner(k % 320, k / 320) && labelled[k * 3] < 60)
        .count();
    assert!(
        inside > 150 && ink > 60,
        "{inside} label pixels, {ink} dark"
    );
    // The time line differs between the first frame and the last; the name line does not.
    let rows_differ = |y0: usize, y1: usize| {
        (y0..y1).any(|y| (0..120).any(|x| pixel(&labelled, (x, y)) != pixel(&first, (x, y))))
    };
    assert!(!rows_differ(0, 12), "the name line");
    assert!(rows_differ(13, 24), "the time line");
}

/// A bag holding only cloth frames and, in its metadata, the scene it was recorded from:
/// the scene's obstacles are drawn from the scene file.
#[test]
fn obstacles_of_the_scene_a_bag_names_are_drawn_when_the_bag_lacks_them() {
    use drape::ros::bag::{BagWriter, RunInfo};
    use drape::ros::msg::{Marker, Point};
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::create_dir_all(d.join("elsewhere")).expect("cwd");
    let yaml = d.join("solids.yaml");
    std::fs::write(&yaml, scene(1.0, &solids())).expect("scene");
    let write = |name: &str, info: Option<RunInfo>| {
        let bag = d.join(name);
        let mut w = BagWriter::create(&bag).expect("bag");
        if let Some(info) = info {
            w.write_run_info(&info).expect("metadata");
        }
        let t = w
            .add_topic::<Marker>("/drape/mesh", drape::ros::Distro::Jazzy, None)
            .expect("topic");
        let p = |x: f64, y: f64| Point { x, y, z: 1.0 };
        let m = Marker {
            r#type: Marker::TRIANGLE_LIST,
            points: vec![
                p(-0.3, -0.3),
                p(0.3, -0.3),
                p(0.3, 0.3),
                p(-0.3, -0.3),
                p(0.3, 0.3),
                p(-0.3, 0.3),
            ],
            ..Marker::default()
        };
        w.write(t, 0, &m).expect("frame");
        w.finish().expect("finish");
        bag
    };
    let named = write(
        "named.mcap",
        Some(RunInfo {
            scene: Some(yaml.clone()),
            ..RunInfo::default()
        }),
    );
    let bare = write("bare.mcap", None);
    let (_, rgb) = render_in(d, &named, "named.png", &[]);
    let (_, none) = render_in(d, &bare, "bare.png", &[]);
    let green = count(&rgb, is_obstacle);
    assert!(green > 500, "{green} obstacle pixels");
    assert_eq!(count(&none, is_obstacle), 0);
    for centre in [BALL, BOX] {
        let (x, y) = projects(&named, Vec3::from(centre));
        assert!(is_obstacle(pixel(&rgb, (x, y))), "{centre:?}");
    }
}

/// A bag only names a scene file: the folders its robot's meshes may come from are the ones
/// that scene allows (its folder here), so a mesh elsewhere is refused before it is opened, and
/// a scene path naming a FIFO neither blocks nor stops the picture.
#[test]
fn a_bag_cannot_widen_where_robot_meshes_come_from() {
    use drape::ros::bag::{BagWriter, RunInfo};
    use drape::ros::msg::{Marker, Point, RosString, TFMessage};
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    for sub in ["scene", "outside", "elsewhere"] {
        std::fs::create_dir_all(d.join(sub)).expect("folder");
    }
    let head = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/meshes/head.stl");
    for inside in ["scene/m.stl", "outside/m.stl"] {
        std::fs::copy(&head, d.join(inside)).expect("mesh");
    }
    let yaml = d.join("scene/s.yaml");
    std::fs::write(
        &yaml,
        format!("{}robot: {{ urdf: bot.urdf }}\n", scene(0.3, "")),
    )
    .expect("scene");
    let fifo = d.join("scene/fifo.yaml");
    let made = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let bag = |name: &str, mesh: &Path, scene: &Path| {
        let bag = d.join(name);
        let mut w = BagWriter::create(&bag).expect("bag");
        w.write_run_info(&RunInfo {
            scene: Some(scene.to_path_buf()),
            ..RunInfo::default()
        })
        .expect("metadata");
        let jazzy = drape::ros::Distro::Jazzy;
        let desc = w
            .add_topic::<RosString>("/robot_description", jazzy, None)
            .expect("topic");
        let urdf = format!(
            r#"<robot name="r"><link name="base"><collision><geometry><mesh filename="file://{}"/></geometry></collision></link></robot>"#,
            mesh.display()
        );
        w.write(desc, 0, &RosString { data: urdf }).expect("urdf");
        let tf = w.add_topic::<TFMessage>("/tf", jazzy, None).expect("topic");
        w.write(tf, 0, &TFMessage::default()).expect("tf");
        let mesh_topic = w
            .add_topic::<Marker>("/drape/mesh", jazzy, None)
            .expect("topic");
        let p = |x: f64, y: f64| Point { x, y, z: 0.3 };
        let m = Marker {
            r#type: Marker::TRIANGLE_LIST,
            points: vec![p(-0.3, -0.3), p(0.3, -0.3), p(0.3, 0.3)],
            ..Marker::default()
        };
        w.write(mesh_topic, 0, &m).expect("frame");
        w.finish().expect("finish");
        bag
    };
    let allowed = bag("allowed.mcap", &d.join("scene/m.stl"), &yaml);
    let (err, rgb) = render_in(d, &allowed, "allowed.png", &[]);
    assert!(
        count(&rgb, is_robot) > 300,
        "the mesh in the scene's folder is drawn: {err}"
    );
    let outside = bag("outside.mcap", &d.join("outside/m.stl"), &yaml);
    let (err, rgb) = render_in(d, &outside, "outside.png", &[]);
    assert!(err.contains("outside the allowed"), "{err}");
    assert_eq!(count(&rgb, is_robot), 0);
    // A FIFO for a scene: the input rules refuse it without opening it for reading.
    let fifo_bag = bag("fifo.mcap", &d.join("scene/m.stl"), &fifo);
    let mut child = Command::new(env!("CARGO_BIN_EXE_drape"))
        .current_dir(d.join("elsewhere"))
        .args(["render".as_ref(), fifo_bag.as_os_str(), "--out".as_ref()])
        .arg(d.join("fifo.png"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("drape runs");
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > std::time::Duration::from_secs(60) {
            let _ = child.kill();
            panic!("drape blocked on a FIFO named as the bag's scene");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    assert!(status.success());
}

/// Meshes the recording found through `--package-path` are found again from the bag when the
/// folder holds ROS packages (a `package.xml`); any other folder the bag lists is not searched.
#[test]
fn package_folders_the_recording_searched_are_searched_again_when_they_hold_packages() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    robot_package(d, false);
    let package = d.join("ws/drape_bot");
    std::fs::create_dir_all(package.join("meshes")).expect("package");
    let head = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/meshes/head.stl");
    std::fs::copy(&head, package.join("meshes/head.stl")).expect("mesh");
    std::fs::write(package.join("package.xml"), "<package/>").expect("package.xml");
    std::fs::create_dir_all(d.join("scene")).expect("scene folder");
    std::fs::create_dir_all(d.join("elsewhere")).expect("cwd");
    let yaml = d.join("scene/cape.yaml");
    std::fs::write(&yaml, CAPE).expect("scene");
    let bag = d.join("cape.mcap");
    drape_in(
        &d.join("elsewhere"),
        &[
            "record".as_ref(),
            "--quiet".as_ref(),
            yaml.as_os_str(),
            "--out".as_ref(),
            bag.as_os_str(),
            "--package-path".as_ref(),
            d.join("ws").as_os_str(),
        ],
    );
    let (err, rgb) = render_in(d, &bag, "found.png", &[]);
    assert!(!err.contains("not found"), "{err}");
    let with_head = count(&rgb, is_robot);
    std::fs::remove_file(package.join("package.xml")).expect("package.xml removed");
    let (err, rgb) = render_in(d, &bag, "plain.png", &[]);
    assert!(err.contains("not a ROS package folder"), "{err}");
    assert!(err.contains("head.stl"), "{err}");
    assert!(count(&rgb, is_robot) < with_head);
}
