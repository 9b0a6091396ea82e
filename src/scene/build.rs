//! Turns a validated [`Scene`] into a [`Simulation`]. Only the effects the scene lists are built.

use super::{EffectKind, Scene, SceneError, Selection};
use crate::cloth::topology::{bending_stencils, springs, twist_stencils, SpringKind};
use crate::cloth::{Cloth, Panel, Piece};
use crate::collide::CollisionStage;
use crate::effects::{
    AirDrag, Bending, EffectSet, Gravity, SpringDamping, Springs, Twist, VelocityDiffusion, Wind,
};
use crate::integrate::ImplicitSettings;
use crate::sim::{Frames, Simulation, StepSettings};
use crate::Vec3;

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
                origin: scene.name.clone(),
                key: format!("cloths[{ci}].attach[{k}].frame"),
                reason: format!("no frame named '{}'", a.frame),
            })?;
            let pose = frames.pose(frame);
            for v in select(&piece, &a.selection()) {
                cloth.attach(v, frame, &pose);
            }
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
        Some(build_collision(scene, &cloth)?)
    } else {
        None
    };
    let mut sim = Simulation::new(cloth, effects, integrator, frames, settings);
    if let Some(stage) = collision {
        sim.set_collision(stage);
    }
    Ok(sim)
}

fn build_collision(scene: &Scene, cloth: &Cloth) -> Result<CollisionStage, SceneError> {
    let origin = || scene.name.clone();
    let base = scene.base_dir.clone().unwrap_or_default();
    let mut obstacles = Vec::with_capacity(scene.obstacles.len());
    for (i, spec) in scene.obstacles.iter().enumerate() {
        let o = spec
            .build(|path: &str| {
                crate::mesh::load_mesh(&base.join(path), Vec3::ONE).map(|m| (m.vertices, m.indices))
            })
            .map_err(|e| SceneError::Invalid {
                origin: origin(),
                key: format!("obstacles[{i}]"),
                reason: e.to_string(),
            })?;
        obstacles.push(o);
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
                    set.push(Box::new(Wind::new(
                        w.velocity,
                        w.keys.clone(),
                        w.gusts.clone(),
                        w.air_density,
                        w.drag_coefficient,
                        cloth.triangles.clone(),
                    )));
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
