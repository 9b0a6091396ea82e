//! Real robots as a user brings them: the Franka Panda, the KUKA iiwa and the UFactory xArm6 of
//! `pybullet_data` (`pip install pybullet`), with the collision meshes they ship, moving at their
//! URDFs' joint-velocity limits. Nobody tuned drape on these robots; the cases are written as a
//! user would script them: a towel held near the flange and swung or whipped, cloth wiped off a
//! table by the flange, a towel picked from a table with the grasp rule.
//!
//! Besides the catalogue's usual criteria each case judges how deep any free cloth vertex sits
//! inside a link, by the mesh's winding number rather than drape's contact code (mesh links have
//! no inside test in the contact stage, so its own penetration figure cannot see a vertex that
//! went through one).

use super::self_contact::case;
use super::setup::{fill, impact_stretch_bound, pick, G};
use super::{Case, Criteria, EnergyCheck, HardError, Resolution};
use crate::scene::Scene;
use std::path::PathBuf;
use std::process::Command;

/// Where `pybullet_data` is: `$PYBULLET_DATA`, else what the `pybullet_data` Python module says.
fn pybullet_data(case: &'static str) -> Result<PathBuf, HardError> {
    if let Some(dir) = std::env::var_os("PYBULLET_DATA").filter(|d| !d.is_empty()) {
        return Ok(PathBuf::from(dir));
    }
    let missing = |why: String| HardError::MissingData {
        case,
        message: format!(
            "pybullet_data not found ({why}): `python3 -m pip install pybullet`, or set \
             PYBULLET_DATA to its folder"
        ),
    };
    let out = Command::new("python3")
        .args([
            "-c",
            "import pybullet_data; print(pybullet_data.getDataPath())",
        ])
        .output()
        .map_err(|e| missing(format!("python3 did not run: {e}")))?;
    if !out.status.success() {
        return Err(missing(
            String::from_utf8_lossy(&out.stderr).trim().to_string(),
        ));
    }
    Ok(PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()))
}

/// The stepping and towel of every case: implicit at 60 Hz, two substeps a frame; a terry towel
/// of 250 g/m^2, 1500 N/m, 4 mm thick.
const COMMON: &str = r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666, substeps: 2 }
"#;
const TOWEL: &str = "{ density: 0.25, stretch: 1500.0, shear: 150.0, bend_warp: 1.0e-4, \
    bend_weft: 1.0e-4, damping: { spring: 0.05, air: 0.1 }, thickness: 0.004, friction: 0.4 }";
const DENSITY: f64 = 0.25;
const STRETCH: f64 = 1500.0;
const THICKNESS: f64 = 0.004;

/// Parses a case's scene with its URDF under pybullet_data, self-collision (and its exact count)
/// switched as asked.
fn scene(
    case: &'static str,
    template: &str,
    values: &[(&str, String)],
    self_collision: bool,
) -> Result<Scene, HardError> {
    let data = pybullet_data(case)?;
    let mut all = vec![
        ("DATA", data.display().to_string()),
        ("TOWEL", TOWEL.to_string()),
        ("COMMON", COMMON.to_string()),
    ];
    all.extend(values.iter().map(|(k, v)| (*k, v.clone())));
    let mut s = Scene::from_yaml(&fill(template, &all), case)
        .map_err(|source| HardError::Scene { case, source })?;
    s.collision.self_collision = self_collision;
    s.collision.count_self_intersections = self_collision;
    Ok(s)
}

/// Criteria of a real-robot case: links up to `link_speed` (m/s), cloth flung at most 3x that
/// and falling at most `fall` m, everything within `reach` m of the root; no vertex deeper in a
/// contact layer or a link's solid than the towel's thickness; edges within the impact bound of
/// a front at the link speed on a towel of `area` hanging from one spring; with self-collision,
/// no intersecting triangle pair. Obstacles do work the runner cannot observe: energy is
/// reported, not judged.
fn criteria(reach: f64, link_speed: f64, fall: f64, area: f64, self_collision: bool) -> Criteria {
    let mut c = Criteria::base(reach, 3.0 * link_speed + (2.0 * G * fall).sqrt());
    c.energy = EnergyCheck::NotMeasured;
    c.max_penetration = Some(THICKNESS);
    c.max_inside_solid = Some(THICKNESS);
    c.max_stretch = Some(impact_stretch_bound(link_speed, STRETCH, DENSITY, area));
    c.max_self_intersections = self_collision.then_some(0);
    c
}

/// Waypoints of one swinging joint: at `rest` for `start` s, then to each of `targets` in turn
/// at `speed` (rad/s), held `hold` s at each; `row(q)` writes a waypoint's positions. Returns the
/// waypoint lines and the time the last hold ends.
fn swing(
    start: f64,
    rest: f64,
    targets: &[f64],
    speed: f64,
    hold: f64,
    row: impl Fn(f64) -> String,
) -> (String, f64) {
    let point = |t: f64, q: f64| format!("      - {{ t: {t:.4}, positions: [{}] }}\n", row(q));
    let mut text = point(0.0, rest) + &point(start, rest);
    let (mut t, mut q) = (start, rest);
    for &next in targets {
        // Rounded up to the 0.1 ms the waypoints are written with, so that no stroke is faster
        // than `speed`.
        t = ((t + (next - q).abs() / speed) * 1e4).ceil() / 1e4;
        q = next;
        text += &point(t, q);
        t += hold;
        text += &point(t, q);
    }
    (text, t)
}

const PANDA_WHIP: &str = r#"
name: panda_whip
@COMMON@
cloths:
  - name: towel
    grid: { size: [0.3, 0.3], resolution: [@RES@, @RES@], pose: { xyz: [0.457, 0.0, 0.300], rpy: [1.5707963267948966, 0.0, 0.0] } }
    material: @TOWEL@
robot:
  urdf: @DATA@/franka_panda/panda.urdf
  trajectory:
    names: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, panda_joint5, panda_joint6, panda_joint7]
    points:
      - { t: 0.0000, positions: [0.0000, -0.7850, 0.0000, -2.3560, 0.0000, 1.5710, 0.7850] }
      - { t: 0.3000, positions: [0.0000, -0.7850, 0.0000, -2.3560, 0.0000, 1.5710, 0.7850] }
      - { t: 1.2742, positions: [-2.1187, 1.2249, 1.5285, -2.3061, -0.0265, 1.6771, 0.8784] }
      - { t: 2.2631, positions: [-0.1846, -0.9259, -0.4989, -2.1380, -0.1723, 2.0793, -0.0461] }
      - { t: 2.7545, positions: [-0.3157, -0.3942, -1.1499, -1.0693, 0.7911, 0.9527, -1.1851] }
      - { t: 3.2391, positions: [-0.2163, 0.6598, -1.4350, -1.7495, 0.6042, -0.0800, -1.8530] }
      - { t: 4.3642, positions: [1.6730, -1.4319, -2.7330, -0.5628, -0.3896, 2.8563, -2.8851] }
      - { t: 5.8294, positions: [-1.5138, 1.4599, -1.9401, -2.0539, -0.8246, 1.1021, -1.4936] }
      - { t: 6.2477, positions: [-2.4236, 1.0584, -1.4085, -1.5471, 0.2229, 0.9152, -0.7016] }
      - { t: 6.6698, positions: [-2.0149, 0.5864, -1.1983, -0.6291, 1.0538, 0.9278, -0.4880] }
      - { t: 7.0768, positions: [-2.9000, -0.0310, -0.4846, -0.8348, 0.2690, 1.0450, -0.0007] }
      - { t: 7.3329, positions: [-2.4812, -0.3317, -0.6311, -0.8145, 0.9373, 1.0952, -0.2568] }
      - { t: 7.8520, positions: [-2.5060, -1.4607, -1.7267, -0.3264, 2.0969, 1.3189, -0.5122] }
      - { t: 8.3840, positions: [-2.9000, -1.4553, -0.5697, -0.1000, 2.1920, 2.1835, -1.1550] }
      - { t: 8.8833, positions: [-2.8669, -0.3694, -0.3830, -0.1981, 1.6383, 2.2987, -0.0579] }
  attach:
    - { cloth: towel, link: panda_hand, near: { point: [0, 0, 0.14], radius: 0.02 } }
collision: { mode: continuous }
"#;

fn panda_whip(
    name: &'static str,
    res: Resolution,
    self_collision: bool,
) -> Result<Case, HardError> {
    let s = scene(
        name,
        PANDA_WHIP,
        &[("RES", pick(res, 16, 24).to_string())],
        self_collision,
    )?;
    // Waypoints random within the joint limits, each reached at the fastest joint's velocity
    // limit (2.175-2.61 rad/s): the hand moves up to ~2.5 m/s at 0.8 m reach, and the towel's
    // far corner 0.42 m further out adds ~1 m/s. A waypoint whose stroke `drape check` found
    // carrying the held corner inside another link of the arm (`scene::lint`) was drawn again,
    // as a user told so would: a real arm cannot sweep what it holds through itself. The shoulder is 0.33 m above the root and the
    // arm reaches 0.86 m from it with the held point 0.14 m past the hand: 1.35 m, and the towel
    // hangs 0.42 m (its diagonal) beyond.
    let crit = criteria(1.8, 3.5, 0.6, 0.3 * 0.3, self_collision);
    case(
        name,
        &format!(
            "Franka Panda whipping a 0.3 m towel held 14 cm out from its hand through random \
             waypoints at its joint-velocity limits that keep the held corner out of the arm's \
             other links, self-collision {}",
            on_off(self_collision)
        ),
        &s,
        6.0,
        crit,
    )
}

pub(super) fn panda_towel_whip(res: Resolution) -> Result<Case, HardError> {
    panda_whip("real_panda_towel_whip", res, false)
}

pub(super) fn panda_self_towel_whip(res: Resolution) -> Result<Case, HardError> {
    panda_whip("real_panda_self_towel_whip", res, true)
}

const KUKA_WHIP: &str = r#"
name: kuka_whip
@COMMON@
cloths:
  - name: towel
    grid: { size: [0.4, 0.4], resolution: [@RES@, @RES@], pose: { xyz: [1.054, 0.0, 0.158], rpy: [1.5707963267948966, 0.0, 0.0] } }
    material: @TOWEL@
robot:
  urdf: @DATA@/kuka_iiwa/model.urdf
  trajectory:
    names: [lbr_iiwa_joint_1, lbr_iiwa_joint_2, lbr_iiwa_joint_4]
    points:
@POINTS@  attach:
    - { cloth: towel, link: lbr_iiwa_link_7, near: { point: [0, 0, 0.07], radius: 0.02 } }
collision: { mode: continuous }
"#;

fn kuka_whip(name: &'static str, res: Resolution, self_collision: bool) -> Result<Case, HardError> {
    // The base joint swings between +-1.2 rad at 9.3 rad/s (93 % of its 10 rad/s limit) with the
    // arm bent forward, held 0.15 s at each end, so the towel whips around the flange and wrist.
    let targets = [1.2, -1.2, 1.2, -1.2, 1.2, -1.2, 1.2, -1.2];
    let (points, _) = swing(0.3, 0.0, &targets, 9.3, 0.15, |q| format!("{q}, 1.0, -1.0"));
    let s = scene(
        name,
        KUKA_WHIP,
        &[("RES", pick(res, 20, 30).to_string()), ("POINTS", points)],
        self_collision,
    )?;
    // The flange is ~0.9 m from the base axis: 9.3 rad/s moves it at ~8 m/s at most; the towel
    // reaches 0.57 m (its diagonal) beyond it.
    let crit = criteria(1.6, 8.5, 0.6, 0.4 * 0.4, self_collision);
    case(
        name,
        &format!(
            "KUKA iiwa whipping a 0.4 m towel held by a corner 7 cm past its flange: the base \
             joint swings +-1.2 rad at 93 % of its velocity limit, self-collision {}",
            on_off(self_collision)
        ),
        &s,
        3.0,
        crit,
    )
}

pub(super) fn kuka_towel_whip(res: Resolution) -> Result<Case, HardError> {
    kuka_whip("real_kuka_towel_whip", res, false)
}

pub(super) fn kuka_self_towel_whip(res: Resolution) -> Result<Case, HardError> {
    kuka_whip("real_kuka_self_towel_whip", res, true)
}

/// The xArm6's joint-velocity limit (rad/s), the same for every joint in its URDF, which
/// writes it `3.14` (not pi).
#[allow(clippy::approx_constant)]
const XARM_LIMIT: f64 = 3.14;

const XARM_WHIP: &str = r#"
name: xarm6_whip
@COMMON@
cloths:
  - name: towel
    grid: { size: [0.3, 0.3], resolution: [@RES@, @RES@], pose: { xyz: [0.5717, 0.0, 0.0311], rpy: [1.5707963267948966, 0.0, 0.0] } }
    material: @TOWEL@
robot:
  urdf: @DATA@/xarm/xarm6_robot.urdf
  trajectory:
    names: [joint1, joint2, joint3, joint4, joint5, joint6]
    points:
@POINTS@  attach:
    - { cloth: towel, link: link6, near: { point: [0.06, 0.0, 0.01], radius: 0.02 } }
collision: { mode: continuous }
"#;

fn xarm_whip(name: &'static str, res: Resolution, self_collision: bool) -> Result<Case, HardError> {
    // The base joint swings +-1.5 rad at its 3.14 rad/s limit, the flange turning with it at the
    // same rate and the wrist pitching a third as fast, so the towel, held 6 cm off the flange's
    // axis, swings out and winds round the flange.
    let targets = [1.5, -1.5, 1.5, -1.5];
    let (points, end) = swing(0.3, 0.0, &targets, XARM_LIMIT, 0.15, |q| {
        format!("{q}, 0.0, -0.5, 0.0, {:.4}, {q}", 0.5 + q / 3.0)
    });
    let s = scene(
        name,
        XARM_WHIP,
        &[("RES", pick(res, 16, 24).to_string()), ("POINTS", points)],
        self_collision,
    )?;
    // The flange is ~0.45 m from the base axis and the towel reaches 0.42 m beyond it: 0.87 m at
    // 3.14 rad/s is 2.7 m/s.
    let crit = criteria(1.4, 2.7, 0.6, 0.3 * 0.3, self_collision);
    case(
        name,
        &format!(
            "UFactory xArm6 swinging a 0.3 m towel held 6 cm off its flange's axis: base and \
             flange joints at their 3.14 rad/s limit, +-1.5 rad, self-collision {}",
            on_off(self_collision)
        ),
        &s,
        end + 0.3,
        crit,
    )
}

pub(super) fn xarm_towel_whip(res: Resolution) -> Result<Case, HardError> {
    xarm_whip("real_xarm6_towel_whip", res, false)
}

pub(super) fn xarm_self_towel_whip(res: Resolution) -> Result<Case, HardError> {
    xarm_whip("real_xarm6_self_towel_whip", res, true)
}

const XARM_WIPE: &str = r#"
name: xarm6_wipe
@COMMON@
cloths:
  - name: towel
    grid: { size: [0.3, 0.3], resolution: [@RES@, @RES@], pose: { xyz: [0.43, 0.12, 0.084] } }
    material: @TOWEL@
obstacles:
  - { name: table, shape: { type: box, half_extents: [0.2, 0.3, 0.04] }, pose: { xyz: [0.45, 0.0, 0.04] } }
  - { name: floor, shape: { type: plane, normal: [0.0, 0.0, 1.0] } }
robot:
  urdf: @DATA@/xarm/xarm6_robot.urdf
  trajectory:
    names: [joint1, joint2, joint3, joint4, joint5, joint6]
    points:
@POINTS@collision: { mode: continuous }
"#;

pub(super) fn xarm_self_wipe(res: Resolution) -> Result<Case, HardError> {
    let name = "real_xarm6_self_wipe_table";
    // The flange points down with its face 1.7 mm above the towel's mid-surface (its lower half
    // inside the towel's contact layer) and sweeps across the table at the base joint's 3.14
    // rad/s limit, shoving the towel over the table's far edge, then sweeps back.
    let (points, end) = swing(0.3, -0.5, &[1.2, -0.5], XARM_LIMIT, 0.8, |q| {
        format!("{q}, 0.51, -0.8, 0.0, 0.29, 0.0")
    });
    let s = scene(
        name,
        XARM_WIPE,
        &[("RES", pick(res, 16, 30).to_string()), ("POINTS", points)],
        true,
    )?;
    // The flange is 0.43 m from the base axis: 1.4 m/s. The towel falls 0.08 m to the floor.
    let crit = criteria(1.0, 1.4, 0.1, 0.3 * 0.3, true);
    case(
        name,
        "UFactory xArm6 wiping a towel off a table with its flange, which sweeps across the \
         table top through the towel's contact layer at the base joint's 3.14 rad/s limit and \
         back, self-collision on",
        &s,
        end,
        crit,
    )
}

const PANDA_PICK: &str = r#"
name: panda_pick
@COMMON@
cloths:
  - name: towel
    grid: { size: [0.3, 0.3], resolution: [@RES@, @RES@], pose: { xyz: [0.6, 0.0, 0.104] } }
    material: @TOWEL@
obstacles:
  - { name: table, shape: { type: box, half_extents: [0.25, 0.35, 0.05] }, pose: { xyz: [0.6, 0.0, 0.05] } }
robot:
  urdf: @DATA@/franka_panda/panda.urdf
  trajectory:
    names: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, panda_joint5, panda_joint6, panda_joint7, panda_finger_joint1]
    points:
      # pybullet's inverse kinematics for panda_grasptarget pointing down, the finger gap across
      # the towel's corner: over the corner (0.45, -0.15) 14 mm above the towel with the fingers
      # open, closed, lifted 5 cm, up to 0.42 m, carried over the table and opened there. Each
      # move takes twice what the fastest joint's velocity limit allows.
      - { t: 0.000, positions: [0.0870, 0.1818, -0.3903, -2.4861, 0.1462, 2.6500, -0.4265, 0.04] }
      - { t: 0.400, positions: [0.0870, 0.1818, -0.3903, -2.4861, 0.1462, 2.6500, -0.4265, 0.0] }
      - { t: 0.600, positions: [0.1213, 0.0594, -0.4392, -2.4800, 0.0442, 2.5333, -0.3536, 0.0] }
      - { t: 1.126, positions: [0.1986, -0.3528, -0.1728, -2.1958, -0.0618, 1.8473, 0.0531, 0.0] }
      - { t: 1.395, positions: [0.2565, -0.0762, 0.1197, -1.9149, 0.0094, 1.8393, 0.3734, 0.0] }
      - { t: 1.795, positions: [0.2731, -0.0123, 0.1895, -1.8403, 0.0024, 1.8282, 0.4619, 0.04] }
      - { t: 3.0, positions: [0.2731, -0.0123, 0.1895, -1.8403, 0.0024, 1.8282, 0.4619, 0.04] }
  grasps:
    # Between the fingertips (hand frame; the tips are 0.112 m out, the grasp target 0.103 m).
    - link: panda_hand
      fingers: [panda_finger_joint1]
      close_below: 0.01
      open_above: 0.02
      pads: { xyz: [0.0, 0.0, 0.11], half_extents: [0.01, 0.01, 0.012] }
      cloth: towel
collision: { mode: continuous }
"#;

pub(super) fn panda_self_towel_pick(res: Resolution) -> Result<Case, HardError> {
    let name = "real_panda_self_towel_pick";
    let s = scene(
        name,
        PANDA_PICK,
        &[("RES", pick(res, 16, 24).to_string())],
        true,
    )?;
    // The grasp target moves at most 0.31 m in 0.53 s (0.6 m/s), the towel's far corner swinging
    // 0.42 m below it adds as much; released 0.3 m above the table.
    let crit = criteria(1.0, 1.2, 0.35, 0.3 * 0.3, true);
    case(
        name,
        "Franka Panda picking a towel from a table by one corner with the grasp rule (the \
         fingers close on it), lifting it, carrying it and opening over the table, \
         self-collision on",
        &s,
        3.0,
        crit,
    )
}

fn on_off(b: bool) -> &'static str {
    if b {
        "on"
    } else {
        "off"
    }
}
