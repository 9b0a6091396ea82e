//! Turns a validated [`Scene`] into a [`Simulation`] (and the driver of its robot): the cloth
//! pieces, pins and attachments, frames, grasps, obstacles, and the effects through the scene's
//! [`EffectPlan`] (only the effects the scene lists are built); garments are dressed here.

use super::{NameKind, RobotSpec, Scene, SceneError, Selection};
use crate::cloth::{Cloth, Panel, Piece};
use crate::collide::{CollisionStage, ShapeSpec};
use crate::effects::{EffectPlan, Lattice, WindPlan};
use crate::integrate::ImplicitSettings;
use crate::robot::driver::link_obstacles;
use crate::robot::{
    Grasp, Hysteresis, JointInputError, JointSource, JointTrajectory, PadBox, Robot, RobotDriver,
    TrajectoryError, UrdfOptions,
};
use crate::sim::{Frames, Simulation, StepSettings};
use crate::{Pose, Vec3};

/// Global vertex indices a (validated) selection picks in a piece.
pub fn select(piece: &Piece, s: &Selection) -> Vec<u32> {
    let mut local: Vec<u32> = Vec::new();
    if let Some(v) = s.vertex {
        local.push(v);
    }
    if let Some(v) = &s.vertices {
        local.extend(v);
    }
    if let Some(r) = s.region {
        local.extend(piece.panel.region(r));
    }
    if let Some(near) = &s.near {
        let p = Vec3::from(near.point);
        local.extend(
            (0..piece.vertex_count as u32)
                .filter(|&i| (piece.panel.positions[i as usize] - p).length() <= near.radius),
        );
    }
    local.into_iter().map(|i| piece.global(i)).collect()
}

pub fn build(scene: &Scene) -> Result<Simulation, SceneError> {
    build_with_robot(scene).map(|(sim, _)| sim)
}

/// Builds the simulation and the driver of the scene's robot (if any).
pub fn build_with_robot(scene: &Scene) -> Result<(Simulation, Option<RobotDriver>), SceneError> {
    let mut driver = match &scene.robot {
        Some(r) => Some(load_robot(scene, r)?),
        None => None,
    };
    let mut cloth = Cloth::new();
    for c in &scene.cloths {
        let panel = Panel::grid(
            &c.name,
            c.grid.size,
            c.grid.resolution,
            &c.grid.pose.to_pose(),
        );
        cloth.add_panel(panel, c.material);
    }

    let mut frames = Frames::default();
    for f in &scene.frames {
        let spec = f.clone();
        frames.add_scripted(&f.name, Box::new(move |t| spec.pose_at(t)));
    }

    for (ci, c) in scene.cloths.iter().enumerate() {
        let piece = cloth.pieces[ci].clone();
        for p in &c.pins {
            for v in select(&piece, p) {
                cloth.pin(v);
            }
        }
        for (k, a) in c.attach.iter().enumerate() {
            let frame = frames.index(&a.frame).ok_or_else(|| {
                unknown(
                    scene,
                    format!("cloths[{ci}].attach[{k}].frame"),
                    NameKind::Frame,
                    &a.frame,
                )
            })?;
            let pose = frames.pose(frame);
            for v in select(&piece, &a.selection()) {
                cloth.attach(v, frame, &pose);
            }
        }
        if let (Some(r), Some(d)) = (&scene.robot, driver.as_mut()) {
            attach_to_links(scene, r, d, ci, &piece, &mut cloth, &mut frames)?;
        }
        if c.pins
            .iter()
            .cloned()
            .chain(c.attach.iter().map(|a| a.selection()))
            .any(|s| select(&piece, &s).is_empty())
        {
            log::warn!("cloth '{}': a pin or attachment selects no vertex", c.name);
        }
    }

    let plan = scene.effect_plan();
    let effects = plan.build(&cloth, &Lattice(&cloth));
    let integrator = scene.solver.integrator.build_with(
        ImplicitSettings {
            cg_tolerance: scene.solver.cg_tolerance,
            cg_max_iterations: scene.solver.cg_max_iterations,
            linearisation_tolerance: scene.solver.linearisation_tolerance,
        },
        scene.solver.linear,
    );
    let settings = StepSettings {
        dt: scene.solver.dt,
        substeps: scene.solver.substeps,
        guard: scene.solver.guard,
    };
    let collision = if scene.needs_collision() {
        Some(build_collision(scene, &cloth, driver.as_mut())?)
    } else {
        None
    };
    let mut sim = Simulation::new(cloth, effects, integrator, frames, settings);
    if let Some(stage) = collision {
        for o in stage.overlaps(&sim.cloth.x) {
            log::warn!("{}: {o}", scene.origin());
        }
        sim.set_collision(stage);
    }
    if !scene.garments.is_empty() {
        crate::garment::dress(&mut sim, &scene.garments, &plan, driver.as_mut()).map_err(
            |source| SceneError::Garment {
                origin: scene.origin().to_string(),
                key: garment_key(&scene.garments, &source),
                source: Box::new(source),
            },
        )?;
    }
    // After dressing: a grasp's candidates are the vertices of the cloth as the run starts,
    // garments welded.
    if let (Some(r), Some(d)) = (&scene.robot, driver.as_mut()) {
        add_grasps(scene, r, d, &sim.cloth, &mut sim.frames)?;
    }
    Ok((sim, driver))
}

/// The key of a dressing error: `garments[i].` and the value at fault in garment `i` (garment
/// names are unique in a validated scene), or `garments` for the sewing of them all.
fn garment_key(
    garments: &[crate::garment::GarmentSpec],
    e: &crate::garment::GarmentError,
) -> String {
    let Some(i) = e
        .garment()
        .and_then(|name| garments.iter().position(|g| g.name == name))
    else {
        return "garments".into();
    };
    match e.key_in(&garments[i]) {
        k if k.is_empty() => format!("garments[{i}]"),
        k => format!("garments[{i}].{k}"),
    }
}

fn unknown(scene: &Scene, key: String, kind: NameKind, name: &str) -> SceneError {
    SceneError::UnknownName {
        origin: scene.origin().to_string(),
        key,
        kind,
        name: name.to_string(),
    }
}

fn grasp_error(scene: &Scene, key: String, source: crate::robot::GraspError) -> SceneError {
    SceneError::Grasp {
        origin: scene.origin().to_string(),
        key,
        source: Box::new(source),
    }
}

/// Loads the URDF (relative to the scene file) and checks the trajectory's joint names against it.
fn load_robot(scene: &Scene, r: &RobotSpec) -> Result<RobotDriver, SceneError> {
    let path = scene.base_dir.clone().unwrap_or_default().join(&r.urdf);
    let robot_error = |source| SceneError::Robot {
        origin: scene.origin().to_string(),
        source: Box::new(source),
    };
    let text = match &scene.robot_urdf_text {
        Some(text) => text.clone(),
        None => crate::input::read_text(&path, crate::input::InputKind::Urdf)
            .map_err(|e| robot_error(e.into()))?,
    };
    let options = UrdfOptions {
        visual_fallback: r.visual_fallback,
        mesh_roots: scene.mesh_roots(),
        search_paths: scene.package_paths.clone(),
        ..UrdfOptions::default()
    };
    let origin = path.display().to_string();
    let robot =
        Robot::from_urdf_named(&text, &origin, path.parent(), &options).map_err(robot_error)?;
    let source = match &r.trajectory {
        Some(tr) => {
            tr.validate(robot.kinematics())
                .map_err(|e| trajectory_error(scene, tr, e))?;
            if let Some(o) = tr.overspeed(robot.kinematics()) {
                // Not an error: a scene may script a motion faster than the robot's, but the
                // cloth then sees links faster than any real run of it.
                log::warn!("scene {}: robot.trajectory: {o}", scene.origin());
            }
            JointSource::Trajectory(tr.clone())
        }
        None => JointSource::Still,
    };
    Ok(RobotDriver::new(robot, text, source))
}

/// Key path of a trajectory error: the name or the value at fault.
fn trajectory_error(scene: &Scene, tr: &JointTrajectory, e: TrajectoryError) -> SceneError {
    let base = "robot.trajectory";
    let name_key = |name: &str, nth: usize| {
        let k = tr
            .names
            .iter()
            .enumerate()
            .filter(|(_, n)| n.as_str() == name)
            .map(|(k, _)| k)
            .nth(nth)
            .unwrap_or(0);
        format!("{base}.names[{k}]")
    };
    let key = match &e {
        TrajectoryError::NoPoints => format!("{base}.points"),
        TrajectoryError::Length { index, .. } => format!("{base}.points[{index}].positions"),
        TrajectoryError::Time { index, .. } => format!("{base}.points[{index}].t"),
        TrajectoryError::Input { index, source } => match source {
            JointInputError::UnknownJoint(n) => name_key(n, 0),
            JointInputError::Duplicate(n) => name_key(n, 1),
            JointInputError::NotFinite { name, .. } => {
                let k = tr.names.iter().position(|x| x == name).unwrap_or(0);
                format!("{base}.points[{index}].positions[{k}]")
            }
            _ => format!("{base}.points[{index}]"),
        },
    };
    SceneError::Trajectory {
        origin: scene.origin().to_string(),
        key,
        source: Box::new(e),
    }
}

/// Attaches the cloth's selected vertices to their links (one frame per link), keeping offsets.
fn attach_to_links(
    scene: &Scene,
    r: &RobotSpec,
    driver: &mut RobotDriver,
    ci: usize,
    piece: &Piece,
    cloth: &mut Cloth,
    frames: &mut Frames,
) -> Result<(), SceneError> {
    let cloth_name = &scene.cloths[ci].name;
    for (k, a) in r.attach.iter().enumerate() {
        if &a.cloth != cloth_name {
            continue;
        }
        let link = driver.robot().link_index(&a.link).ok_or_else(|| {
            unknown(
                scene,
                format!("robot.attach[{k}].link"),
                NameKind::RobotLink,
                &a.link,
            )
        })?;
        let pose = driver.link_poses()[link];
        let frame = driver.link_frame(link, frames);
        let mut sel = a.selection();
        if let Some(near) = sel.near.as_mut() {
            near.point = pose.transform_point(Vec3::from(near.point)).into();
        }
        let picked = select(piece, &sel);
        if picked.is_empty() {
            return Err(SceneError::EmptySelection {
                origin: scene.origin().to_string(),
                key: format!("robot.attach[{k}]"),
                cloth: cloth_name.clone(),
            });
        }
        for v in picked {
            cloth.attach(v, frame, &pose);
        }
    }
    Ok(())
}

/// Builds the grasp rules (one frame per gripper link, shared with attachments).
fn add_grasps(
    scene: &Scene,
    r: &RobotSpec,
    driver: &mut RobotDriver,
    cloth: &Cloth,
    frames: &mut Frames,
) -> Result<(), SceneError> {
    for (k, g) in r.grasps.iter().enumerate() {
        let key = |field: &str| format!("robot.grasps[{k}].{field}");
        let link = driver
            .robot()
            .link_index(&g.link)
            .ok_or_else(|| unknown(scene, key("link"), NameKind::RobotLink, &g.link))?;
        let mut fingers = Vec::with_capacity(g.fingers.len());
        for (f, name) in g.fingers.iter().enumerate() {
            let j = driver.robot().joint_index(name).ok_or_else(|| {
                unknown(
                    scene,
                    key(&format!("fingers[{f}]")),
                    NameKind::RobotJoint,
                    name,
                )
            })?;
            fingers.push(j);
        }
        let candidates = match &g.cloth {
            Some(name) => cloth
                .pieces
                .iter()
                .find(|p| &p.name == name)
                .map(|p| p.vertices())
                .ok_or_else(|| unknown(scene, key("cloth"), NameKind::Cloth, name))?,
            None => 0..cloth.len(),
        };
        let state = Hysteresis::new(g.close_below, g.open_above)
            .map_err(|e| grasp_error(scene, key("close_below"), e))?;
        let pads = PadBox::new(
            Pose::from_xyz_rpy(g.pads.xyz, g.pads.rpy),
            Vec3::from(g.pads.half_extents),
        )
        .map_err(|e| grasp_error(scene, key("pads"), e))?;
        if !(g.pads.xyz.iter().chain(&g.pads.rpy).all(|v| v.is_finite())) {
            return Err(SceneError::NonFinitePose {
                origin: scene.origin().to_string(),
                key: key("pads"),
            });
        }
        let frame = driver.link_frame(link, frames);
        let grasp = Grasp::new(link, frame, fingers, state, pads, candidates)
            .map_err(|e| grasp_error(scene, key("fingers"), e))?;
        driver.add_grasp(grasp);
    }
    Ok(())
}

fn build_collision(
    scene: &Scene,
    cloth: &Cloth,
    driver: Option<&mut RobotDriver>,
) -> Result<CollisionStage, SceneError> {
    let origin = || scene.origin().to_string();
    let base = scene.base_dir.clone().unwrap_or_default();
    let roots = scene.mesh_roots();
    let mut obstacles = Vec::with_capacity(scene.obstacles.len());
    for (i, spec) in scene.obstacles.iter().enumerate() {
        // A mesh is scaled by its loader, which bounds the scale and the scaled vertices.
        let mut spec = spec.clone();
        let scale = match &mut spec.shape {
            ShapeSpec::Mesh { scale, .. } => Vec3::from(std::mem::replace(scale, [1.0; 3])),
            _ => Vec3::ONE,
        };
        let o = spec
            .build(|path: &str| {
                crate::mesh::load_mesh_within(&base.join(path), scale, &roots)
                    .map(|m| (m.vertices, m.indices))
            })
            .map_err(|source| SceneError::Obstacle {
                origin: origin(),
                key: format!("obstacles[{i}]"),
                source: Box::new(source),
            })?;
        obstacles.push(o);
    }
    if let Some(d) = driver {
        let poses = d.link_poses().to_vec();
        let names = d.robot().link_names().to_vec();
        let shapes = d.robot().collision_shapes().to_vec();
        for (link, link_shapes) in shapes.iter().enumerate() {
            let built =
                link_obstacles(&names[link], link_shapes, &poses[link]).map_err(|source| {
                    SceneError::LinkObstacle {
                        origin: origin(),
                        link: names[link].clone(),
                        source: Box::new(source),
                    }
                })?;
            for (o, local) in built {
                d.bind_obstacle(link, obstacles.len(), local);
                obstacles.push(o);
            }
        }
    }
    CollisionStage::new(
        scene.collision.settings(),
        obstacles,
        cloth.triangles.clone(),
        cloth.len(),
        cloth.thickness.clone(),
        cloth.friction.clone(),
    )
    .map_err(|source| SceneError::Collision {
        origin: origin(),
        source: Box::new(source),
    })
}

impl Scene {
    /// Builds the simulation this scene describes. A robot stays in its t = 0 pose: use
    /// [`Scene::build_with_robot`] to get the driver that moves it.
    pub fn build(&self) -> Result<Simulation, SceneError> {
        build(self)
    }

    /// Builds the simulation and, when the scene has a `robot:` section, the driver that moves
    /// the robot's obstacles and attachment frames (call `driver.advance` before each step).
    pub fn build_with_robot(&self) -> Result<(Simulation, Option<RobotDriver>), SceneError> {
        build_with_robot(self)
    }

    /// The effects this scene names, in its order, with its gravity and wind: what both a grid
    /// cloth and dressed garments are built from.
    pub fn effect_plan(&self) -> EffectPlan {
        EffectPlan {
            terms: self.effects.clone(),
            gravity: Vec3::from(self.gravity),
            wind: self.wind.as_ref().map(|w| WindPlan {
                velocity: w.velocity,
                keys: w.keys.clone(),
                gusts: w.gusts.clone(),
                air_density: w.air_density,
                drag_coefficient: w.drag_coefficient,
            }),
        }
    }
}
