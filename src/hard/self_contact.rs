//! Self-collision where users need it: on a moving robot and in a garment. Each case switches
//! `self_collision` (and the stage's exact intersection count, judged at zero every substep) on
//! in a bundled robot or garment scene: a towel shaken at the joint-velocity limits, a cape under
//! swinging arms, a sleeve sewn and worn while the arm moves, a towel picked from a table.

use super::setup::{bundled_scene, fill, impact_stretch_bound, pick, G};
use super::{Case, Criteria, EnergyCheck, HardError, Resolution};
use crate::robot::{JointTrajectory, TrajectoryPoint};
use crate::scene::Scene;

/// A bundled scene (config/) with self-collision and its exact intersection count switched on,
/// grid cloths at `res` vertices per side and garments at `edge` (m) when given.
fn bundled(
    case: &'static str,
    file: &str,
    res: Option<usize>,
    edge: Option<f64>,
) -> Result<Scene, HardError> {
    let mut s = bundled_scene(case, file)?;
    self_on(&mut s);
    if let Some(r) = res {
        s.cloths.iter_mut().for_each(|c| c.grid.resolution = [r, r]);
    }
    if let Some(e) = edge {
        s.garments.iter_mut().for_each(|g| g.edge_length = e);
    }
    Ok(s)
}

fn self_on(s: &mut Scene) {
    s.collision.self_collision = true;
    s.collision.count_self_intersections = true;
}

/// A case of a scene with its robot driver.
pub(super) fn case(
    name: &'static str,
    description: &str,
    scene: &Scene,
    duration: f64,
    criteria: Criteria,
) -> Result<Case, HardError> {
    let (sim, driver) = scene
        .build_with_robot()
        .map_err(|source| HardError::Scene { case: name, source })?;
    Ok(Case {
        name,
        description: description.into(),
        sim,
        driver,
        duration,
        criteria,
    })
}

/// Criteria of a robot case: links up to `link_speed` (m/s); cloth flung off whips at most 3x the
/// link speed and falls at most `fall` m (sqrt(2 g fall)); everything stays within `reach` m of
/// the root. Obstacles do work the runner cannot observe: energy is reported, not judged.
fn robot_criteria(reach: f64, link_speed: f64, fall: f64, thickness: f64) -> Criteria {
    let mut c = Criteria::base(reach, 3.0 * link_speed + (2.0 * G * fall).sqrt());
    c.energy = EnergyCheck::NotMeasured;
    c.max_penetration = Some(thickness);
    c.max_self_intersections = Some(0);
    c
}

pub(super) fn towel_shaken(res: Resolution) -> Result<Case, HardError> {
    let name = "self_towel_shaken_at_velocity_limits";
    // Each stroke takes amplitude / limit: shoulder pitch 0.8 rad at 2.0 rad/s, elbow 1.0 rad at
    // 2.5 rad/s and wrist 1.2 rad at 3.0 rad/s all take 0.4 s (drape_bot.urdf), so every joint
    // moves at exactly its velocity limit, reversing every 0.4 s.
    let text = fill(
        r#"
name: self_towel_shaken
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666, substeps: 2 }
cloths:
  - name: towel
    grid: { size: [0.4, 0.4], resolution: [@RES@, @RES@], pose: { xyz: [0.879, -0.255, 0.392], rpy: [1.5707963267948966, 0.0, 0.0] } }
    material:
      density: 0.25
      stretch: 1500.0
      shear: 150.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: { spring: 0.05, air: 0.1 }
      thickness: 0.008
      friction: 0.4
robot:
  urdf: ../urdf/drape_bot.urdf
  trajectory:
    names: [right_shoulder_pitch, right_elbow, right_wrist]
    points:
      - { t: 0.0, positions: [-1.5, 0.0, 0.0] }
      - { t: 0.3, positions: [-1.5, 0.0, 0.0] }
      - { t: 0.7, positions: [-0.7, -1.0, 1.2] }
      - { t: 1.1, positions: [-1.5, 0.0, 0.0] }
      - { t: 1.5, positions: [-0.7, -1.0, 1.2] }
      - { t: 1.9, positions: [-1.5, 0.0, 0.0] }
      - { t: 2.3, positions: [-0.7, -1.0, 1.2] }
      - { t: 2.7, positions: [-1.5, 0.0, 0.0] }
  attach:
    - { cloth: towel, link: right_palm, near: { point: [0.0, 0.0, -0.13], radius: 0.03 } }
collision: { mode: continuous, self_collision: true, count_self_intersections: true }
"#,
        &[("RES", pick(res, 20, 40).to_string())],
    );
    let mut scene = super::setup::parse(name, &text)?;
    self_on(&mut scene);
    // The palm is ~0.75 m from the shoulder (2 rad/s: 1.5 m/s), the elbow adds 2.5 rad/s over
    // ~0.4 m (1.0 m/s) and the wrist 3 rad/s over the 0.13 m to the grip (0.4 m/s): 2.9 m/s.
    // The towel hangs 0.4 m below the grip, within 1.5 m of the root.
    let criteria = robot_criteria(1.8, 2.9, 0.6, 0.008);
    case(
        name,
        "towel held at one corner by drape_bot's gripper, shaken by shoulder, elbow and wrist at \
         their joint-velocity limits, self-collision on",
        &scene,
        pick(res, 1.5, 2.7),
        criteria,
    )
}

pub(super) fn cape_swinging(res: Resolution) -> Result<Case, HardError> {
    let name = "self_cape_under_swinging_arms";
    let scene = bundled(name, "robot_cape.yaml", Some(pick(res, 24, 48)), None)?;
    // robot_cape.yaml: shoulders move at most 0.8 rad/s-ish over 1 s strokes; hands ~0.75 m out:
    // 1.2 m/s. The cape hangs from the torso, within 1.5 m of the root, and falls at most 0.6 m.
    let mut criteria = robot_criteria(1.5, 1.2, 0.6, 0.008);
    // Hung from the still torso alone, the cape is stretched only by the arms' sweep and its
    // own weight (robot_cape.yaml's material).
    criteria.max_stretch = Some(impact_stretch_bound(1.2, 1500.0, 0.2, 0.6 * 0.6));
    case(
        name,
        "cape on drape_bot's torso while both arms swing through its sides (robot_cape.yaml), \
         self-collision on",
        &scene,
        pick(res, 2.0, 4.0),
        criteria,
    )
}

pub(super) fn sleeve_worn(res: Resolution) -> Result<Case, HardError> {
    let name = "self_sleeve_sewn_and_worn";
    let scene = bundled(name, "sleeve.yaml", None, Some(pick(res, 0.03, 0.015)))?;
    // sleeve.yaml: the arm drops 0.8 rad and swings 1.2 rad per second about the shoulder with the
    // sleeve ~0.4 m out: about 0.5 m/s. The sleeve is attached at the shoulder end.
    let criteria = robot_criteria(1.5, 0.5, 0.3, 0.005);
    case(
        name,
        "tube sleeve sewn round drape_bot's upper arm with self-collision on (seams exempt until \
         welded), then worn while the arm drops and swings (sleeve.yaml)",
        &scene,
        pick(res, 2.0, 4.0),
        criteria,
    )
}

pub(super) fn towel_picked(res: Resolution) -> Result<Case, HardError> {
    let name = "self_towel_picked_from_table";
    let scene = bundled(name, "robot_pick_towel.yaml", Some(pick(res, 16, 61)), None)?;
    // robot_pick_towel.yaml: the gripper moves at most ~0.5 m in 0.6 s (under 1 m/s) and lets
    // the towel go ~0.35 m above the table.
    let criteria = robot_criteria(1.5, 1.0, 0.5, 0.008);
    case(
        name,
        "towel lying on a table picked by one corner, lifted, carried and dropped onto itself \
         (robot_pick_towel.yaml), self-collision on",
        &scene,
        pick(res, 3.0, 4.0),
        criteria,
    )
}

pub(super) fn shirt_cut_long_worn(res: Resolution) -> Result<Case, HardError> {
    let name = "self_shirt_of_another_cut_worn";
    let mut scene = bundled(name, "shirt.yaml", None, Some(pick(res, 0.04, 0.025)))?;
    // The bundled shirt recut as a user would: narrow straps (5 cm) reaching 0.27 m above the
    // armholes' tops, past the shoulders, and a body 3 cm longer, down to the base.
    let outline = [
        [-0.40, -0.38],
        [0.40, -0.38],
        [0.40, 0.0],
        [0.16, 0.18],
        [0.16, 0.45],
        [0.11, 0.45],
        [0.11, 0.15],
        [-0.11, 0.15],
        [-0.11, 0.45],
        [-0.16, 0.45],
        [-0.16, 0.18],
        [-0.40, 0.0],
    ];
    for g in &mut scene.garments {
        g.panels
            .iter_mut()
            .for_each(|p| p.outline = outline.to_vec());
    }
    // The arms, held out sideways while it is sewn, come down through the armholes at the
    // shoulder roll's 2 rad/s limit, swing forward and back at 2 rad/s, and go back up.
    let names = [
        "left_shoulder_roll",
        "right_shoulder_roll",
        "left_shoulder_pitch",
        "right_shoulder_pitch",
    ];
    let points = [
        (0.0, [1.5, -1.5, 0.0, 0.0]),
        (0.5, [1.5, -1.5, 0.0, 0.0]),
        (1.1, [0.3, -0.3, 0.0, 0.0]),
        (1.6, [0.3, -0.3, 1.0, -1.0]),
        (2.6, [0.3, -0.3, -1.0, 1.0]),
        (3.1, [0.3, -0.3, 0.0, 0.0]),
        (3.7, [1.5, -1.5, 0.0, 0.0]),
        (5.0, [1.5, -1.5, 0.0, 0.0]),
    ];
    if let Some(robot) = scene.robot.as_mut() {
        robot.trajectory = Some(JointTrajectory {
            names: names.map(String::from).to_vec(),
            points: (points.iter())
                .map(|&(t, q)| TrajectoryPoint {
                    t,
                    positions: q.to_vec(),
                })
                .collect(),
        });
    }
    // The hands are ~0.75 m from the shoulders: 2 rad/s moves them at 1.5 m/s.
    let criteria = robot_criteria(1.5, 1.5, 0.3, 0.006);
    case(
        name,
        "sleeveless shirt recut with long narrow straps and a longer body, sewn on drape_bot \
         with self-collision on, then worn while the arms come down through the armholes and \
         swing at their joint-velocity limits",
        &scene,
        5.0,
        criteria,
    )
}
