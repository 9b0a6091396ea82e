//! The simulation: what it holds (model, state, work kept apart) and what the outside may do
//! to it between steps (move frames and obstacles, attach and release vertices, change the
//! wind, replace the cloth). The step itself is in `step.rs`.

use super::coupling::Coupling;
use super::energy::kinetic_energy;
use super::frames::Frames;
use super::guard::Guard;
use super::metrics::StepMetrics;
use super::model::{Model, StepSettings, Work};
use crate::cloth::Cloth;
use crate::collide::{CollisionStage, StageError};
use crate::effects::EffectSet;
use crate::integrate::{ImplicitSettings, Integrator};
use crate::{Pose, Vec3};

pub struct Simulation {
    // State: what evolves.
    /// The cloth's state (positions, velocities, kinematic vertices) with its fixed masses and
    /// topology.
    pub cloth: Cloth,
    pub frames: Frames,
    pub(super) time: f64,
    /// Start and end pose over the current frame of obstacles driven from outside (robot links).
    pub(super) obstacle_targets: Vec<Option<(Pose, Pose)>>,
    /// Obstacles (their poses evolve) and the stage's buffers; `None` without collisions.
    pub(super) collision: Option<CollisionStage>,
    /// The guard's state (energy bookkeeping, strain check, what it learned of the substep).
    pub(super) guard: Guard,
    /// Constraints, holds and lagged forces between solver and collision stage.
    pub(super) coupling: Coupling,
    pub(super) last: StepMetrics,
    // Model: what the scene fixes.
    pub settings: StepSettings,
    pub(super) model: Model,
    /// The time integrator (with its own warm-start state and buffers inside).
    pub(super) integrator: Box<dyn Integrator>,
    // Work: the substep's start state, the guard's saves, caches and scratch.
    pub(super) work: Work,
}

impl Simulation {
    pub fn new(
        cloth: Cloth,
        effects: EffectSet,
        mut integrator: Box<dyn Integrator>,
        frames: Frames,
        settings: StepSettings,
    ) -> Self {
        let n = cloth.len();
        integrator.prepare(&effects, n);
        let mut coupling = Coupling::default();
        coupling.replace_cloth(n);
        let model = Model::new(effects, integrator.capabilities(), &cloth);
        Self {
            cloth,
            frames,
            time: 0.0,
            obstacle_targets: Vec::new(),
            collision: None,
            guard: Guard::default(),
            coupling,
            last: StepMetrics::default(),
            settings,
            model,
            integrator,
            work: Work::default(),
        }
    }

    /// Adds the collision stage (scenes without obstacles or self-collision have none).
    /// Cloth that starts inside a solid obstacle is led out over the first steps, each patch
    /// the way it came in (see [`CollisionStage::plan_exits`]).
    pub fn set_collision(&mut self, mut stage: CollisionStage) {
        self.obstacle_targets = vec![None; stage.obstacles().len()];
        stage.plan_exits(&self.cloth.x, &self.kinematic_vertices());
        self.collision = Some(stage);
    }

    fn kinematic_vertices(&self) -> Vec<u32> {
        self.cloth.kinematic.iter().map(|(i, _)| *i).collect()
    }

    /// Starts a new phase with another cloth and effect set (a garment after welding): the
    /// integrator, constraints, energy bookkeeping and the collision stage's cloth topology are
    /// rebuilt, and the bound on the highest frequency recomputed for the new effects and
    /// masses; obstacles and frames keep their poses, the clock keeps running.
    pub fn replace_cloth(&mut self, cloth: Cloth, effects: EffectSet) -> Result<(), StageError> {
        if let Some(stage) = &self.collision {
            let new = CollisionStage::new(
                *stage.settings(),
                stage.obstacles().to_vec(),
                cloth.triangles.clone(),
                cloth.len(),
                cloth.thickness.clone(),
                cloth.friction.clone(),
            )?;
            self.collision = Some(new);
            let kinematic: Vec<u32> = cloth.kinematic.iter().map(|(i, _)| *i).collect();
            if let Some(stage) = self.collision.as_mut() {
                stage.plan_exits(&cloth.x, &kinematic);
            }
        }
        self.integrator.prepare(&effects, cloth.len());
        self.coupling.replace_cloth(cloth.len());
        self.cloth = cloth;
        // A new model (frequency bound, strain limit) and work (the tethers' cache) for the new
        // cloth.
        self.model = Model::new(effects, self.model.caps, &self.cloth);
        self.work.tethers = Default::default();
        self.guard.restart();
        Ok(())
    }

    /// Sets the clock back to zero, with scripted frames and obstacles at their t = 0 poses
    /// (after a preparation phase such as sewing, so that scripts and robot trajectories start
    /// with the run proper).
    pub fn restart_clock(&mut self) {
        self.time = 0.0;
        self.frames.restart();
        if let Some(stage) = self.collision.as_mut() {
            stage.advance_obstacles(0.0, 0.0);
        }
    }

    pub fn collision(&self) -> Option<&CollisionStage> {
        self.collision.as_ref()
    }

    /// The collision stage, to change its settings at runtime (e.g. culling).
    pub fn collision_mut(&mut self) -> Option<&mut CollisionStage> {
        self.collision.as_mut()
    }

    /// Sets where an externally driven obstacle will be at the end of the next frame step; the
    /// substeps see it move smoothly from its current pose. Returns false for a bad index or pose.
    pub fn set_obstacle_target(&mut self, obstacle: usize, pose: Pose) -> bool {
        let Some(stage) = &self.collision else {
            return false;
        };
        let (Some(slot), Some(o)) = (
            self.obstacle_targets.get_mut(obstacle),
            stage.obstacles().get(obstacle),
        ) else {
            return false;
        };
        if !pose.is_finite() {
            return false;
        }
        *slot = Some((o.pose, pose));
        true
    }

    /// Changes the step's quality from the next step on (the node's adaptive quality):
    /// `substeps` per frame and the implicit solver's CG tolerance and cap (an integrator
    /// without a linear solver ignores `solver`). The guard still subdivides any substep that
    /// needs it. Returns false, changing nothing, for 0 substeps or unusable solver settings.
    pub fn set_quality(&mut self, substeps: u32, solver: ImplicitSettings) -> bool {
        if substeps == 0 || !solver.is_usable() {
            return false;
        }
        self.settings.substeps = substeps;
        self.integrator.set_solver_settings(solver);
        true
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    /// Sets the scene's constant wind velocity from now on (m/s); false when the scene has no
    /// wind effect (it names none, so none was built).
    pub fn set_wind_velocity(&mut self, velocity: Vec3) -> bool {
        velocity.is_finite() && self.model.effects.set_wind_velocity(velocity)
    }

    pub fn effects(&self) -> &EffectSet {
        &self.model.effects
    }

    pub fn integrator_name(&self) -> &'static str {
        self.integrator.name()
    }

    pub fn last_metrics(&self) -> &StepMetrics {
        &self.last
    }

    /// Sets where a frame will be at the end of the next frame step.
    pub fn set_frame_target(&mut self, frame: usize, pose: Pose) {
        self.frames.set_target(frame, pose);
    }

    /// Attaches cloth vertices at runtime to `frame` at its current pose, keeping their offsets
    /// (a gripper closing on cloth). Vertices that are already kinematic, or out of range, are
    /// skipped; returns the ones attached. From the next substep on they are fixed in the
    /// solver's filter and have infinite mass in the collision stage; their kinetic energy
    /// leaves the guard's accounting (the budget stays an upper bound).
    pub fn attach_vertices(&mut self, vertices: &[u32], frame: usize) -> Vec<u32> {
        if frame >= self.frames.len() {
            return Vec::new();
        }
        let pose = self.frames.pose_now(frame);
        let mut done = Vec::with_capacity(vertices.len());
        for &v in vertices {
            if (v as usize) < self.cloth.len() && !self.cloth.is_kinematic(v) {
                self.cloth.attach(v, frame, &pose);
                done.push(v);
            }
        }
        if !done.is_empty() {
            self.guard.forget_energy();
        }
        done
    }

    /// Releases kinematic vertices at runtime with the given velocities (a gripper opening:
    /// the gripper's point velocity). Their kinetic energy is energy given to the cloth from
    /// outside, so it widens the guard's energy budget. Returns how many were released.
    pub fn release_vertices(&mut self, released: &[(u32, Vec3)]) -> usize {
        let mut count = 0;
        let mut gained = 0.0;
        for &(v, vel) in released {
            let i = v as usize;
            if i >= self.cloth.len() || !self.cloth.is_kinematic(v) || !vel.is_finite() {
                continue;
            }
            self.cloth.release(v);
            self.cloth.v[i] = vel;
            gained += 0.5 * self.cloth.mass[i] * vel.length_squared();
            count += 1;
        }
        if count > 0 {
            self.guard.widen(gained);
        }
        count
    }

    /// Kinetic energy of free vertices and potential energy of every conservative effect.
    pub fn energy(&self) -> (f64, f64) {
        let ke = kinetic_energy(&self.cloth);
        (ke, self.model.effects.energy(&self.cloth.x))
    }
}
