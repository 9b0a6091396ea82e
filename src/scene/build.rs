//! Turns a validated [`Scene`] into a [`Simulation`]. Only the effects the scene lists are built.

use super::{EffectKind, RobotSpec, Scene, SceneError, Selection};
use crate::cloth::topology::{bending_stencils, springs, twist_stencils, SpringKind};
use crate::cloth::{Cloth, Panel, Piece};
use crate::collide::CollisionStage;
use crate::effects::{
    AirDrag, Bending, EffectSet, Gravity, SpringDamping, Springs, Twist, VelocityDiffusion,
};
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
            let frame = frames.index(&a.frame).ok_or_else(|| SceneError::Invalid {
                origin: scene.origin().to_string(),
                key: format!("cloths[{ci}].attach[{k}].frame"),
                reason: format!("no frame named '{}'", a.frame),
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

    if let (Some(r), Some(d)) = (&scene.robot, driver.as_mut()) {
        add_grasps(scene, r, d, &cloth, &mut frames)?;
    }

    let effects = build_effects(scene, &cloth);
    let integrator = scene.solver.integrator.build(ImplicitSettings {
        cg_tolerance: scene.solver.cg_tolerance,
        cg_max_iterations: scene.solver.cg_max_iterations,
    });
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
        sim.set_collision(stage);
    }
    if !scene.garments.is_empty() {
        crate::garment::dress(&mut sim, scene, driver.as_mut())
            .map_err(|e| invalid(scene, "garments".into(), e.to_string()))?;
    }
    Ok((sim, driver))
}

fn invalid(scene: &Scene, key: String, reason: String) -> SceneError {
    SceneError::Invalid {
        origin: scene.origin().to_string(),
        key,
        reason,
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
        ..UrdfOptions::default()
    };
    let origin = path.display().to_string();
    let robot =
        Robot::from_urdf_named(&text, &origin, path.parent(), &options).map_err(robot_error)?;
    let source = match &r.trajectory {
        Some(tr) => {
            tr.validate(robot.kinematics())
                .map_err(|e| trajectory_error(scene, tr, e))?;
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
    let reason = match e {
        TrajectoryError::Input { source, .. } => source.to_string(),
        other => other.to_string(),
    };
    invalid(scene, key, reason)
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
            invalid(
                scene,
                format!("robot.attach[{k}].link"),
                format!("the robot has no link named '{}'", a.link),
            )
        })?;
        let pose = driver.link_poses()[link];
        let frame = match driver.frame_of(link) {
            Some(f) => f,
            None => {
                let f = frames.add(&format!("robot:{}", a.link), pose);
                driver.bind_frame(link, f);
                f
            }
        };
        let mut sel = a.selection();
        if let Some(near) = sel.near.as_mut() {
            near.point = pose.transform_point(Vec3::from(near.point)).into();
        }
        let picked = select(piece, &sel);
        if picked.is_empty() {
            return Err(invalid(
                scene,
                format!("robot.attach[{k}]"),
                format!("selects no vertex of cloth '{cloth_name}'"),
            ));
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
        let link = driver.robot().link_index(&g.link).ok_or_else(|| {
            invalid(
                scene,
                key("link"),
                format!("the robot has no link named '{}'", g.link),
            )
        })?;
        let mut fingers = Vec::with_capacity(g.fingers.len());
        for (f, name) in g.fingers.iter().enumerate() {
            let j = driver.robot().joint_index(name).ok_or_else(|| {
                invalid(
                    scene,
                    key(&format!("fingers[{f}]")),
                    format!("the robot has no joint named '{name}'"),
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
                .ok_or_else(|| invalid(scene, key("cloth"), format!("no cloth named '{name}'")))?,
            None => 0..cloth.len(),
        };
        let state = Hysteresis::new(g.close_below, g.open_above)
            .map_err(|e| invalid(scene, key("close_below"), e.to_string()))?;
        let pads = PadBox::new(
            Pose::from_xyz_rpy(g.pads.xyz, g.pads.rpy),
            Vec3::from(g.pads.half_extents),
        )
        .map_err(|e| invalid(scene, key("pads"), e.to_string()))?;
        if !(g.pads.xyz.iter().chain(&g.pads.rpy).all(|v| v.is_finite())) {
            return Err(invalid(scene, key("pads"), "pose must be finite".into()));
        }
        let frame = match driver.frame_of(link) {
            Some(f) => f,
            None => {
                let f = frames.add(&format!("robot:{}", g.link), driver.link_poses()[link]);
                driver.bind_frame(link, f);
                f
            }
        };
        let grasp = Grasp::new(link, frame, fingers, state, pads, candidates)
            .map_err(|e| invalid(scene, key("fingers"), e.to_string()))?;
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
        let o = spec
            .build(|path: &str| {
                crate::mesh::load_mesh_within(&base.join(path), Vec3::ONE, &roots)
                    .map(|m| (m.vertices, m.indices))
            })
            .map_err(|e| SceneError::Invalid {
                origin: origin(),
                key: format!("obstacles[{i}]"),
                reason: e.to_string(),
            })?;
        obstacles.push(o);
    }
    if let Some(d) = driver {
        let poses = d.link_poses().to_vec();
        let names = d.robot().link_names().to_vec();
        let shapes = d.robot().collision_shapes().to_vec();
        for (link, link_shapes) in shapes.iter().enumerate() {
            let built = link_obstacles(&names[link], link_shapes, &poses[link]).map_err(|e| {
                invalid(
                    scene,
                    "robot.urdf".into(),
                    format!("link `{}`: {e}", names[link]),
                )
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
    .map_err(|e| SceneError::Invalid {
        origin: origin(),
        key: "collision".into(),
        reason: e.to_string(),
    })
}

fn build_effects(scene: &Scene, cloth: &Cloth) -> EffectSet {
    let mut set = EffectSet::new();
    let param = |i: usize, name: &str| format!("cloths[{i}].material.{name}");
    for kind in &scene.effects {
        match kind {
            EffectKind::Gravity => {
                set.push_gravity(Gravity::new(Vec3::from(scene.gravity), &cloth.mass))
            }
            EffectKind::Stretch | EffectKind::Shear | EffectKind::SkipOne => {
                let (name, sk) = match kind {
                    EffectKind::Stretch => ("stretch", SpringKind::Structural),
                    EffectKind::Shear => ("shear", SpringKind::Shear),
                    _ => ("skip_one", SpringKind::SkipOne),
                };
                for (i, p) in cloth.pieces.iter().enumerate() {
                    let k = match kind {
                        EffectKind::Stretch => p.material.stretch,
                        EffectKind::Shear => p.material.shear,
                        _ => p.material.skip_one,
                    };
                    let s = springs(p, sk);
                    if k > 0.0 && !s.is_empty() {
                        let ks = vec![k; s.len()];
                        set.push(Box::new(Springs::new(name, s, ks, param(i, name))));
                    }
                }
            }
            EffectKind::Bending => {
                for (i, p) in cloth.pieces.iter().enumerate() {
                    let mut st = Vec::new();
                    let mut c = Vec::new();
                    for (along_u, b) in
                        [(true, p.material.bend_warp), (false, p.material.bend_weft)]
                    {
                        if b > 0.0 {
                            let s = bending_stencils(p, along_u);
                            c.extend(std::iter::repeat_n(b, s.len()));
                            st.extend(s);
                        }
                    }
                    if !st.is_empty() {
                        let which = if p.material.bend_warp >= p.material.bend_weft {
                            "bend_warp"
                        } else {
                            "bend_weft"
                        };
                        set.push(Box::new(Bending::new(st, c, param(i, which))));
                    }
                }
            }
            EffectKind::Twist => {
                for (i, p) in cloth.pieces.iter().enumerate() {
                    let s = twist_stencils(p);
                    if p.material.twist > 0.0 && !s.is_empty() {
                        let c = vec![p.material.twist; s.len()];
                        set.push(Box::new(Twist::new(s, c, param(i, "twist"))));
                    }
                }
            }
            EffectKind::Wind => {
                if let Some(w) = &scene.wind {
                    set.push(Box::new(w.effect(cloth.triangles.clone())));
                }
            }
            EffectKind::Damping => build_damping(&mut set, cloth),
        }
    }
    set
}

fn build_damping(set: &mut EffectSet, cloth: &Cloth) {
    let mut spring_pairs = Vec::new();
    let mut spring_kd = Vec::new();
    let mut diff_pairs = Vec::new();
    let mut diff_k = Vec::new();
    for p in &cloth.pieces {
        let d = p.material.damping;
        if d.spring > 0.0 {
            for kind in [SpringKind::Structural, SpringKind::Shear] {
                for s in springs(p, kind) {
                    spring_pairs.push((s.i, s.j));
                    spring_kd.push(d.spring);
                }
            }
        }
        if d.diffusion > 0.0 {
            for s in springs(p, SpringKind::Structural) {
                diff_pairs.push((s.i, s.j));
                diff_k.push(d.diffusion);
            }
        }
    }
    if !spring_pairs.is_empty() {
        set.push(Box::new(SpringDamping::new(spring_pairs, spring_kd)));
    }
    let air: Vec<f64> = cloth
        .pieces
        .iter()
        .flat_map(|p| std::iter::repeat_n(p.material.damping.air, p.vertex_count))
        .collect();
    if air.iter().any(|&a| a > 0.0) {
        set.push(Box::new(AirDrag::new(&air, &cloth.mass)));
    }
    if !diff_pairs.is_empty() {
        set.push(Box::new(VelocityDiffusion::new(diff_pairs, diff_k)));
    }
}
