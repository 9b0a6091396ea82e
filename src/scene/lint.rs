//! Likely mistakes in a valid scene: things `drape check` warns about but that are not errors,
//! because a scene may mean them. Each [`Warning`] names the key path it is about.
//!
//! - an angle over 2π in magnitude (`rpy`, or any key naming an angle): radians were meant,
//!   degrees were probably written;
//! - an attachment whose vertices are all far from what holds them at t = 0 (a scene frame's
//!   origin, a robot link's origin and collision shapes): the towel would be dragged across
//!   the scene on the first step;
//! - a pin or attachment whose `near` point selects no vertex;
//! - a grid cloth with no obstacle or robot link anywhere near it at t = 0 (only in a scene
//!   that has obstacles): it probably sits in the wrong place;
//! - cloth that starts inside a mesh obstacle (a mesh link, a scene `mesh`), by the mesh's
//!   winding number: the contact stage treats a mesh as a two-sided surface, finds no inside,
//!   and cannot lead the cloth out as it does from a solid primitive;
//! - cloth attached to a robot link that the robot's motion carries inside another of its links
//!   (a wrist folded onto the shoulder, a hand swept through the base): held vertices go where
//!   the link takes them whatever is there, so the cloth around them is pulled out of the other
//!   link and stretched. drape does not check a robot against itself; this check does, for what
//!   the robot holds, by sampling the scene's trajectory.

use super::build::select;
use super::{Scene, Selection};
use crate::collide::Obstacle;
use crate::robot::driver::link_obstacles;
use crate::robot::RobotDriver;
use crate::sim::Simulation;
use crate::Vec3;
use serde_yaml_ng::Value;

/// Farthest (m) the nearest held vertex may be from what holds it (a frame's origin, or a link's
/// origin or collision shapes) at t = 0. A gripper holds cloth a few centimetres to a hand's
/// length from its link frame; a quarter metre leaves room for long fingers and tool links.
pub const FAR_FROM_HOLDER: f64 = 0.25;

/// A cloth whose nearest obstacle (or robot link) at t = 0 is farther than this (m), and
/// farther than [`ALONE_CLOTH_SIZES`] times its larger side, is reported as alone.
pub const ALONE_DISTANCE: f64 = 1.0;

/// See [`ALONE_DISTANCE`]: a large cloth may hang well above what it lands on.
pub const ALONE_CLOTH_SIZES: f64 = 2.0;

/// Time between the trajectory samples at which held cloth is checked against the robot's
/// other links (s): at the 2-3 m/s of an arm at its joint-velocity limits a held point moves
/// about a centimetre between samples, less than a link is thick.
pub const HELD_SAMPLE: f64 = 1.0 / 200.0;

/// One likely mistake, with the scene key it is about (`cloths[0].grid.pose.rpy[0]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    pub key: String,
    pub kind: WarningKind,
}

#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum WarningKind {
    /// An angle (radians) over 2π in magnitude.
    LargeAngle { value: f64 },
    /// The attached vertices' nearest is `distance` m from `holder` (a link or frame) at t = 0.
    FarFromHolder {
        holder: String,
        distance: f64,
        limit: f64,
    },
    /// A `near` selection that picks no vertex; the cloth's vertex nearest its point is
    /// `nearest` m away.
    SelectsNothing { nearest: f64, radius: f64 },
    /// No obstacle or robot link within `limit` m of the cloth at t = 0; the nearest is
    /// `nearest` m away.
    ClothAlone { nearest: f64, limit: f64 },
    /// The robot's motion carries vertices attached to `holder` up to `deepest` m inside its
    /// link `link` (deeper than the cloth is thick): first at `first` s, deepest at `at` s.
    HeldThroughLink {
        holder: String,
        link: String,
        first: f64,
        at: f64,
        deepest: f64,
    },
    /// `vertices` of the cloth start inside the mesh obstacle `obstacle`, up to `deepest` m.
    InsideMesh {
        obstacle: String,
        vertices: usize,
        deepest: f64,
    },
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: ", self.key)?;
        match &self.kind {
            WarningKind::LargeAngle { value } => write!(
                f,
                "{value} rad is more than a full turn; angles are in radians (degrees? \
                 {value} deg is {:.4} rad)",
                value.to_radians()
            ),
            WarningKind::FarFromHolder {
                holder,
                distance,
                limit,
            } => write!(
                f,
                "the attached vertices are {distance:.3} m from {holder} at t = 0 (more than \
                 {limit} m): the cloth will be dragged to it; place the cloth at the holder \
                 (`drape check --links` prints the links' poses)"
            ),
            WarningKind::SelectsNothing { nearest, radius } => write!(
                f,
                "selects no vertex: the nearest cloth vertex is {nearest:.3} m from `near.point` \
                 (radius {radius} m)"
            ),
            WarningKind::InsideMesh {
                obstacle,
                vertices,
                deepest,
            } => write!(
                f,
                "{vertices} vertices start inside the mesh `{obstacle}` at t = 0 (up to \
                 {deepest:.3} m, by its winding number): drape treats a mesh as a surface and \
                 cannot lead them out; move the cloth out of it (`drape check --links` prints \
                 the links' poses)"
            ),
            WarningKind::HeldThroughLink {
                holder,
                link,
                first,
                at,
                deepest,
            } => write!(
                f,
                "the robot's trajectory carries the cloth held by `{holder}` {deepest:.3} m inside \
                 its link `{link}` (from t = {first:.2} s, deepest at t = {at:.2} s): held \
                 vertices follow their link whatever is there, so the cloth around them is \
                 pulled out of `{link}` and stretched; keep what the robot holds clear of its \
                 other links (drape does not check a robot against itself)"
            ),
            WarningKind::ClothAlone { nearest, limit } => write!(
                f,
                "no obstacle or robot link within {limit:.2} m at t = 0 (the nearest is \
                 {nearest:.2} m away): is the cloth's pose right?"
            ),
        }
    }
}

/// The likely mistakes of `scene`, built as `sim` (and `driver`, its robot) by
/// [`super::build_with_robot`], at t = 0.
pub fn lint(scene: &Scene, sim: &Simulation, driver: Option<&RobotDriver>) -> Vec<Warning> {
    let mut out = Vec::new();
    large_angles(scene, &mut out);
    held_far(scene, sim, driver, &mut out);
    alone(scene, sim, &mut out);
    inside_meshes(scene, sim, &mut out);
    held_through_links(scene, sim, driver, &mut out);
    out
}

/// Robot attachments that the scene's trajectory carries inside another link of the robot (see
/// [`WarningKind::HeldThroughLink`]), sampled every [`HELD_SAMPLE`] over the scene's duration.
/// Links that already hold an attached vertex inside them at t = 0 (the gripper's own fingers)
/// are not judged.
fn held_through_links(
    scene: &Scene,
    sim: &Simulation,
    driver: Option<&RobotDriver>,
    out: &mut Vec<Warning>,
) {
    let (Some(r), Some(driver), Some(stage)) = (&scene.robot, driver, sim.collision()) else {
        return;
    };
    if r.attach.is_empty() {
        return;
    }
    let robot = driver.robot();
    let solids = crate::collide::Solids::of(stage);
    let samples = (scene.duration / HELD_SAMPLE).ceil().clamp(1.0, 1e6) as usize;
    let poses: Vec<Vec<crate::Pose>> = (0..=samples)
        .map(|s| robot.link_poses(&driver.positions_at(s as f64 * HELD_SAMPLE)))
        .collect();
    let depth = |link: usize, at: &[crate::Pose], p: Vec3| {
        (driver.obstacles_of(link).iter())
            .map(|(k, local)| solids.depth_at(stage, *k, &at[link].mul(local), p))
            .fold(0.0, f64::max)
    };
    for (k, a) in r.attach.iter().enumerate() {
        let (Some(ci), Some(holder)) = (
            scene.cloths.iter().position(|c| c.name == a.cloth),
            robot.link_index(&a.link),
        ) else {
            continue;
        };
        let (Some(piece), Some(start)) = (sim.cloth.pieces.get(ci), poses.first()) else {
            continue;
        };
        let mut sel = a.selection();
        if let Some(near) = sel.near.as_mut() {
            near.point = start[holder].transform_point(Vec3::from(near.point)).into();
        }
        let local: Vec<Vec3> = (select(piece, &sel).iter())
            .filter_map(|&v| sim.cloth.x.get(v as usize))
            .map(|&p| start[holder].inverse_transform_point(p))
            .collect();
        let thickness = scene.cloths[ci].material.thickness;
        for link in (0..poses[0].len()).filter(|&l| l != holder) {
            let held_at = |at: &Vec<crate::Pose>| {
                (local.iter())
                    .map(|&p| depth(link, at, at[holder].transform_point(p)))
                    .fold(0.0, f64::max)
            };
            if held_at(start) > 0.0 {
                continue;
            }
            let (mut first, mut deepest) = (None, (0.0, 0.0));
            for (s, at) in poses.iter().enumerate() {
                let d = held_at(at);
                if d > thickness {
                    let t = s as f64 * HELD_SAMPLE;
                    first.get_or_insert(t);
                    if d > deepest.0 {
                        deepest = (d, t);
                    }
                }
            }
            if let Some(first) = first {
                out.push(Warning {
                    key: format!("robot.attach[{k}]"),
                    kind: WarningKind::HeldThroughLink {
                        holder: a.link.clone(),
                        link: robot.link_names()[link].clone(),
                        first,
                        at: deepest.1,
                        deepest: deepest.0,
                    },
                });
            }
        }
    }
}

/// Per cloth and mesh obstacle, the cloth's vertices inside the mesh at t = 0 (see
/// [`WarningKind::InsideMesh`]), keyed by the cloth (`cloths[i]`, then `garments[j]`).
fn inside_meshes(scene: &Scene, sim: &Simulation, out: &mut Vec<Warning>) {
    let Some(stage) = sim.collision() else { return };
    let solids = crate::collide::Solids::of(stage);
    let meshes: Vec<usize> = (0..stage.obstacles().len())
        .filter(|&k| solids.is_mesh(k))
        .collect();
    if meshes.is_empty() {
        return;
    }
    for (pi, piece) in sim.cloth.pieces.iter().enumerate() {
        let key = match pi.checked_sub(scene.cloths.len()) {
            None => format!("cloths[{pi}]"),
            Some(gi) => format!("garments[{gi}]"),
        };
        let range = piece.first_vertex..piece.first_vertex + piece.vertex_count;
        let Some(xs) = sim.cloth.x.get(range) else {
            continue;
        };
        for &k in &meshes {
            let (vertices, deepest) = (xs.iter())
                .map(|&p| solids.depth_in(stage, k, p))
                .filter(|d| *d > 0.0)
                .fold((0, 0.0), |(n, deepest), d| (n + 1, f64::max(deepest, d)));
            if vertices > 0 {
                out.push(Warning {
                    key: key.clone(),
                    kind: WarningKind::InsideMesh {
                        obstacle: stage.obstacles()[k].name.clone(),
                        vertices,
                        deepest,
                    },
                });
            }
        }
    }
}

/// Every `rpy` entry, and every number under a key naming an angle, over 2π in magnitude. The
/// scene is walked as its serialised form, so a key added to the format is covered by its name.
fn large_angles(scene: &Scene, out: &mut Vec<Warning>) {
    let Ok(v) = serde_yaml_ng::to_value(scene) else {
        return;
    };
    walk(&v, String::new(), false, out);
}

/// A key whose numbers are angles in radians (`angular_velocity` is not one: rad/s).
fn is_angle_key(key: &str) -> bool {
    key == "rpy" || key.split('_').any(|w| w == "angle" || w == "angles")
}

fn walk(v: &Value, key: String, angle: bool, out: &mut Vec<Warning>) {
    match v {
        Value::Mapping(m) => {
            for (k, v) in m {
                let Some(k) = k.as_str() else { continue };
                let path = if key.is_empty() {
                    k.to_string()
                } else {
                    format!("{key}.{k}")
                };
                walk(v, path, is_angle_key(k), out);
            }
        }
        Value::Sequence(s) => {
            for (i, v) in s.iter().enumerate() {
                walk(v, format!("{key}[{i}]"), angle, out);
            }
        }
        Value::Tagged(t) => walk(&t.value, key, angle, out),
        _ => {
            if let Some(x) = v
                .as_f64()
                .filter(|x| angle && x.abs() > std::f64::consts::TAU)
            {
                out.push(Warning {
                    key,
                    kind: WarningKind::LargeAngle { value: x },
                });
            }
        }
    }
}

/// Attachments far from their frame or link, and `near` selections that pick nothing.
fn held_far(scene: &Scene, sim: &Simulation, driver: Option<&RobotDriver>, out: &mut Vec<Warning>) {
    let x = &sim.cloth.x;
    for (ci, c) in scene.cloths.iter().enumerate() {
        let Some(piece) = sim.cloth.pieces.get(ci) else {
            continue;
        };
        for (k, p) in c.pins.iter().enumerate() {
            nothing_near(piece, p, format!("cloths[{ci}].pins[{k}]"), x, out);
        }
        for (k, a) in c.attach.iter().enumerate() {
            let key = format!("cloths[{ci}].attach[{k}]");
            let sel = a.selection();
            let picked = select(piece, &sel);
            if picked.is_empty() {
                nothing_near(piece, &sel, key, x, out);
                continue;
            }
            let Some(f) = scene.frames.iter().find(|f| f.name == a.frame) else {
                continue;
            };
            let origin = f.pose_at(0.0).translation;
            let d = nearest(&picked, x, |p| (p - origin).length());
            far(out, key, format!("frame `{}`'s origin", f.name), d);
        }
    }
    let (Some(r), Some(driver)) = (&scene.robot, driver) else {
        return;
    };
    let robot = driver.robot();
    for (k, a) in r.attach.iter().enumerate() {
        let key = format!("robot.attach[{k}]");
        let (Some(ci), Some(link)) = (
            scene.cloths.iter().position(|c| c.name == a.cloth),
            robot.link_index(&a.link),
        ) else {
            continue;
        };
        let (Some(piece), Some(pose)) = (sim.cloth.pieces.get(ci), driver.link_poses().get(link))
        else {
            continue;
        };
        let mut sel = a.selection();
        if let Some(near) = sel.near.as_mut() {
            near.point = pose.transform_point(Vec3::from(near.point)).into();
        }
        let picked = select(piece, &sel);
        let shapes = robot
            .collision_shapes()
            .get(link)
            .and_then(|s| link_obstacles(&a.link, s, pose).ok())
            .unwrap_or_default();
        let d = nearest(&picked, x, |p| {
            shapes
                .iter()
                .map(|(o, _)| distance(o, p))
                .fold((p - pose.translation).length(), f64::min)
        });
        far(out, key, format!("link `{}`", a.link), d);
    }
}

fn far(out: &mut Vec<Warning>, key: String, holder: String, distance: f64) {
    if distance > FAR_FROM_HOLDER {
        out.push(Warning {
            key,
            kind: WarningKind::FarFromHolder {
                holder,
                distance,
                limit: FAR_FROM_HOLDER,
            },
        });
    }
}

/// A `near` selection (world frame) that picks no vertex of `piece`.
fn nothing_near(
    piece: &crate::cloth::Piece,
    s: &Selection,
    key: String,
    x: &[Vec3],
    out: &mut Vec<Warning>,
) {
    let Some(near) = s.near else { return };
    let only_near = Selection {
        near: Some(near),
        ..Selection::default()
    };
    if !select(piece, &only_near).is_empty() {
        return;
    }
    let all: Vec<u32> = (0..piece.vertex_count as u32)
        .map(|i| piece.global(i))
        .collect();
    let p = Vec3::from(near.point);
    out.push(Warning {
        key,
        kind: WarningKind::SelectsNothing {
            nearest: nearest(&all, x, |v| (v - p).length()),
            radius: near.radius,
        },
    });
}

/// The smallest `dist` over the vertices `picked` (infinite for none).
fn nearest(picked: &[u32], x: &[Vec3], dist: impl Fn(Vec3) -> f64) -> f64 {
    picked
        .iter()
        .filter_map(|&v| x.get(v as usize))
        .map(|&p| dist(p))
        .fold(f64::INFINITY, f64::min)
}

/// Distance (m) from world point `p` to an obstacle's surface, 0 inside it.
fn distance(o: &Obstacle, p: Vec3) -> f64 {
    let local = o.pose.inverse_transform_point(p);
    o.closest_local(local, local).signed_distance.max(0.0)
}

/// Grid cloths with nothing to touch near them, in a scene that has obstacles.
fn alone(scene: &Scene, sim: &Simulation, out: &mut Vec<Warning>) {
    let Some(stage) = sim.collision() else { return };
    let obstacles = stage.obstacles();
    if obstacles.is_empty() {
        return;
    }
    for (ci, c) in scene.cloths.iter().enumerate() {
        let Some(piece) = sim.cloth.pieces.get(ci) else {
            continue;
        };
        let size = c.grid.size[0].max(c.grid.size[1]);
        let limit = ALONE_DISTANCE.max(ALONE_CLOTH_SIZES * size);
        let xs = &sim.cloth.x[piece.first_vertex..piece.first_vertex + piece.vertex_count];
        // Any vertex with an obstacle within the limit settles it; meshes prune with the bound.
        let near = xs.iter().any(|&p| {
            obstacles.iter().any(|o| {
                let local = o.pose.inverse_transform_point(p);
                o.closest_local_within(local, local, limit).is_some()
            })
        });
        if near {
            continue;
        }
        let nearest = xs
            .iter()
            .flat_map(|&p| obstacles.iter().map(move |o| distance(o, p)))
            .fold(f64::INFINITY, f64::min);
        out.push(Warning {
            key: format!("cloths[{ci}].grid.pose"),
            kind: WarningKind::ClothAlone { nearest, limit },
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warnings(yaml: &str) -> Vec<Warning> {
        let scene = Scene::from_yaml(yaml, "t.yaml").unwrap();
        let (sim, driver) = scene.build_with_robot().unwrap();
        lint(&scene, &sim, driver.as_ref())
    }

    const CLOTH: &str = "effects: [gravity, stretch]\ncloths:\n  - name: c\n    grid: { size: [0.5, 0.5], resolution: [5, 5], pose: { xyz: [0, 0, 1], rpy: RPY } }\n";

    #[test]
    fn degrees_in_rpy_are_named_with_their_key() {
        let w = warnings(&CLOTH.replace("RPY", "[90, 0, 1.5]"));
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].key, "cloths[0].grid.pose.rpy[0]");
        assert_eq!(w[0].kind, WarningKind::LargeAngle { value: 90.0 });
        assert!(warnings(&CLOTH.replace("RPY", "[-6.2, 3.14, 6.28]")).is_empty());
    }

    #[test]
    fn angle_keys_are_told_from_rates() {
        assert!(is_angle_key("rpy"));
        assert!(is_angle_key("max_angle"));
        assert!(!is_angle_key("angular_velocity"));
        assert!(!is_angle_key("angular"));
    }

    #[test]
    fn a_far_frame_attachment_and_an_empty_near_pin_are_reported() {
        let yaml = format!(
            "{}    pins: [ {{ near: {{ point: [3, 0, 1], radius: 0.01 }} }} ]\n    attach: [ {{ frame: h, region: top_left }} ]\nframes: [ {{ name: h, pose: {{ xyz: [0, 2, 1] }} }} ]\n",
            CLOTH.replace("RPY", "[0, 0, 0]")
        );
        let w = warnings(&yaml);
        let keys: Vec<&str> = w.iter().map(|w| w.key.as_str()).collect();
        assert_eq!(keys, ["cloths[0].pins[0]", "cloths[0].attach[0]"], "{w:?}");
        assert!(
            matches!(w[0].kind, WarningKind::SelectsNothing { nearest, .. } if (nearest - 2.75).abs() < 1e-9),
            "{w:?}"
        );
        assert!(
            matches!(&w[1].kind, WarningKind::FarFromHolder { distance, .. } if *distance > 1.5),
            "{w:?}"
        );
        let near = yaml.replace("xyz: [0, 2, 1]", "xyz: [-0.25, 0.25, 1]");
        assert_eq!(warnings(&near).len(), 1);
    }

    #[test]
    fn a_cloth_far_above_the_ground_is_alone() {
        let base = CLOTH.replace("RPY", "[0, 0, 0]");
        let ground = "obstacles: [ { name: floor, shape: { type: plane, normal: [0, 0, 1] } } ]\n";
        let high = format!(
            "{}{ground}",
            base.replace("xyz: [0, 0, 1]", "xyz: [0, 0, 5]")
        );
        let w = warnings(&high);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].key, "cloths[0].grid.pose");
        assert!(
            matches!(w[0].kind, WarningKind::ClothAlone { nearest, limit } if (nearest - 5.0).abs() < 1e-6 && limit == 1.0),
            "{w:?}"
        );
        assert!(warnings(&format!("{base}{ground}")).is_empty());
        // Nothing to be near: a flag in the wind is not alone.
        assert!(warnings(&high.replace(ground, "")).is_empty());
    }
}
