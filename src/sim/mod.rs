//! `Simulation::step`: the order of one step, the divergence guard and the metrics.
//!
//! One frame of `dt` is `substeps` substeps of `h = dt / substeps`. Each substep runs one way:
//! 1. kinematic vertices get their end-of-substep targets (frames interpolated across the frame);
//! 2. effects give forces and the integrator advances the state;
//! 3. kinematic vertices are put exactly on their end-of-substep targets;
//! 4. the guard checks the result (and subdivides or stops per policy);
//! 5. collisions fix the new state;
//! 6. metrics are recorded.
//!
//! The guard's energy pass at the new state also computes the position-only forces there, which
//! the next substep's first force evaluation reuses (see [`EffectSet::energy_split`]), so a
//! guarded explicit substep costs one pass over the effects. The same pass scans the vertices for
//! the guard (finiteness, speed, kinetic energy), on two threads for large cloths. The rollback
//! state costs no copy: the start state's buffers are swapped out and the integrator writes the
//! end state out of place ([`Integrator::step_into`]).

mod guard;

pub use guard::{DivergenceError, DivergencePolicy, GuardSettings, Symptom};

use crate::cloth::{Cloth, Kinematic};
use crate::collide::{CollisionStage, HeldNormals};
use crate::effects::{EffectSet, State};
use crate::integrate::{Capabilities, Constraints, Dynamics, Integrator, StepReport};
use crate::linalg::Filter;
use crate::{Pose, Vec3};
use std::time::Instant;

/// Time stepping settings of a simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSettings {
    /// Frame step (s): one call to [`Simulation::step`].
    pub dt: f64,
    pub substeps: u32,
    pub guard: GuardSettings,
}

/// What one frame step did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepMetrics {
    pub time: f64,
    pub substeps: u32,
    /// Substeps that were redone as smaller steps by the divergence guard.
    pub subdivisions: u32,
    pub force_evaluations: u32,
    pub cg_iterations: u32,
    pub cg_residual_max: f64,
    pub kinetic_energy: f64,
    pub potential_energy: f64,
    pub max_speed: f64,
    pub wall_time_s: f64,
    /// Obstacle contacts at the end of the step.
    pub contacts: usize,
    /// Deepest penetration into an obstacle's thickness layer over the step's substeps (m).
    pub deepest_penetration: f64,
    /// Intersecting non-adjacent triangle pairs at the end of the step, when counted.
    pub self_intersections: Option<usize>,
    /// Cloth-cloth pairs the collision fail-safe could not resolve.
    pub unresolved_contacts: usize,
    pub collision_time_s: f64,
    /// Obstacles skipped by the collision stage as far from the cloth (last substep).
    pub culled_obstacles: usize,
}

/// Energies of a state: kinetic (free vertices), elastic and gravitational potential.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Energies {
    kinetic: f64,
    elastic: f64,
    gravity: f64,
}

impl Energies {
    /// Kinetic plus every potential.
    fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravity
    }

    /// Kinetic plus elastic: the total without the gravity potential, so never negative.
    fn dynamic(&self) -> f64 {
        self.kinetic + self.elastic
    }
}

/// Moving frames that kinematic vertices attach to. A frame step moves each frame from `start`
/// to `end`; substeps see poses interpolated between the two, so fast motion is not a jump.
#[derive(Default)]
pub struct Frames {
    pub names: Vec<String>,
    start: Vec<Pose>,
    end: Vec<Pose>,
    /// Scripted frames know their pose at any time; the others are moved from outside
    /// (robot links) through [`Simulation::set_frame_target`].
    script: Vec<Option<FrameScript>>,
}

/// A frame's pose as a function of time.
pub type FrameScript = Box<dyn Fn(f64) -> Pose + Send + Sync>;

impl Frames {
    /// Adds a frame moved from outside.
    pub fn add(&mut self, name: &str, pose: Pose) -> usize {
        self.names.push(name.to_string());
        self.start.push(pose);
        self.end.push(pose);
        self.script.push(None);
        self.names.len() - 1
    }

    /// Adds a frame that follows a script.
    pub fn add_scripted(&mut self, name: &str, script: FrameScript) -> usize {
        let i = self.add(name, script(0.0));
        self.script[i] = Some(script);
        i
    }

    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Pose at fraction `s` of the current frame step.
    pub fn at(&self, frame: usize, s: f64) -> Pose {
        self.start[frame].lerp(&self.end[frame], s)
    }

    /// Current (end-of-step) pose.
    pub fn pose(&self, frame: usize) -> Pose {
        self.end[frame]
    }

    /// Pose at the simulation's current time, even after a target for the next step was set.
    pub fn pose_now(&self, frame: usize) -> Pose {
        self.start[frame]
    }
}

pub struct Simulation {
    pub cloth: Cloth,
    effects: EffectSet,
    integrator: Box<dyn Integrator>,
    /// What the integrator is (asked once, at construction).
    caps: Capabilities,
    /// The integrator's report of the last step (its buffers reused across steps).
    report: StepReport,
    pub frames: Frames,
    pub settings: StepSettings,
    constraints: Constraints,
    time: f64,
    /// Energy of the current state, if known (saves one evaluation per substep).
    energy_cache: Option<Energies>,
    /// Largest squared vertex speed of the current state when the guard's scan measured it
    /// (cleared by anything that changes velocities after the scan, e.g. collisions).
    scanned_speed2: Option<f64>,
    /// Dynamic energy of the last substeps: the guard's reference level, so that the bounded
    /// energy oscillation of a stable symplectic step is not mistaken for a blow-up.
    recent_energy: [f64; 16],
    /// Upper bound of the total energy the cloth may have by now: its initial energy plus all the
    /// work done on it from outside (and the allowed integration error). `None` until first set.
    energy_budget: Option<f64>,
    /// Scale of the budget's slack: initial dynamic energy plus the allowances spent.
    budget_scale: f64,
    substep_count: usize,
    // Scratch buffers.
    x_save: Vec<Vec3>,
    v_save: Vec<Vec3>,
    scratch_f: Vec<Vec3>,
    /// Forces from outside the cloth (wind, driven vertices) at the start of the substep.
    fext: Vec<Vec3>,
    inv_mass: Vec<f64>,
    last: StepMetrics,
    collision: Option<CollisionStage>,
    /// Start and end pose over the current frame of obstacles driven from outside (robot links).
    obstacle_targets: Vec<Option<(Pose, Pose)>>,
    /// Upper bound of the cloth's highest angular frequency (rad/s), computed on first use.
    omega_bound: Option<f64>,
    /// Per vertex, the normals the last substep's solve held it against with their Coulomb
    /// limits `mu N` (N; 0: unused): the lagged normal forces of in-solve friction.
    friction_limit: Vec<[(Vec3, f64); 3]>,
    /// The last substep's edge springs (cloth face or edge) and their end forces (N), sorted.
    spring_forces: Vec<([u32; 3], f64)>,
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
        Self {
            cloth,
            effects,
            caps: integrator.capabilities(),
            report: StepReport::default(),
            integrator,
            frames,
            settings,
            constraints: Constraints::free(n),
            time: 0.0,
            energy_cache: None,
            scanned_speed2: None,
            recent_energy: [0.0; 16],
            energy_budget: None,
            budget_scale: 0.0,
            substep_count: 0,
            x_save: Vec::new(),
            v_save: Vec::new(),
            scratch_f: Vec::new(),
            fext: Vec::new(),
            inv_mass: Vec::new(),
            last: StepMetrics::default(),
            collision: None,
            obstacle_targets: Vec::new(),
            omega_bound: None,
            friction_limit: Vec::new(),
            spring_forces: Vec::new(),
        }
    }

    /// Adds the collision stage (scenes without obstacles or self-collision have none).
    pub fn set_collision(&mut self, stage: CollisionStage) {
        self.obstacle_targets = vec![None; stage.obstacles().len()];
        self.collision = Some(stage);
    }

    /// Starts a new phase with another cloth and effect set (a garment after welding): the
    /// integrator, constraints, energy bookkeeping and the collision stage's cloth topology are
    /// rebuilt; obstacles and frames keep their poses, the clock keeps running.
    pub fn replace_cloth(
        &mut self,
        cloth: Cloth,
        effects: EffectSet,
    ) -> Result<(), crate::collide::StageError> {
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
        }
        self.integrator.prepare(&effects, cloth.len());
        self.constraints = Constraints::free(cloth.len());
        self.cloth = cloth;
        self.effects = effects;
        self.energy_cache = None;
        self.recent_energy = [0.0; 16];
        self.energy_budget = None;
        self.budget_scale = 0.0;
        Ok(())
    }

    /// Sets the clock back to zero, with scripted frames and obstacles at their t = 0 poses
    /// (after a preparation phase such as sewing, so that scripts and robot trajectories start
    /// with the run proper).
    pub fn restart_clock(&mut self) {
        self.time = 0.0;
        for f in 0..self.frames.len() {
            if let Some(script) = &self.frames.script[f] {
                let p = script(0.0);
                self.frames.start[f] = p;
                self.frames.end[f] = p;
            }
        }
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

    pub fn time(&self) -> f64 {
        self.time
    }

    /// Sets the scene's constant wind velocity from now on (m/s); false when the scene has no
    /// wind effect (it names none, so none was built).
    pub fn set_wind_velocity(&mut self, velocity: Vec3) -> bool {
        velocity.is_finite() && self.effects.set_wind_velocity(velocity)
    }

    pub fn effects(&self) -> &EffectSet {
        &self.effects
    }

    pub fn integrator_name(&self) -> &'static str {
        self.integrator.name()
    }

    pub fn last_metrics(&self) -> &StepMetrics {
        &self.last
    }

    /// Sets where a frame will be at the end of the next frame step.
    pub fn set_frame_target(&mut self, frame: usize, pose: Pose) {
        self.frames.end[frame] = pose;
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
            self.energy_cache = None;
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
            if let Some(b) = self.energy_budget.as_mut() {
                *b += gained;
            }
            self.budget_scale += gained;
            self.energy_cache = None;
        }
        count
    }

    /// Kinetic energy of free vertices and potential energy of every conservative effect.
    pub fn energy(&self) -> (f64, f64) {
        let ke = self.kinetic_energy();
        (ke, self.effects.energy(&self.cloth.x))
    }

    fn kinetic_energy(&self) -> f64 {
        let c = &self.cloth;
        let mut ke: f64 =
            c.v.iter()
                .zip(&c.mass)
                .map(|(v, m)| 0.5 * m * v.length_squared())
                .sum();
        for (i, _) in &c.kinematic {
            ke -= 0.5 * c.mass[*i as usize] * c.v[*i as usize].length_squared();
        }
        ke
    }

    /// Advances one frame (`settings.dt`).
    pub fn step(&mut self) -> Result<&StepMetrics, Box<DivergenceError>> {
        let wall = Instant::now();
        let mut m = StepMetrics::default();
        let n_sub = self.settings.substeps.max(1);
        let h = self.settings.dt / n_sub as f64;
        let t0 = self.time;
        self.scanned_speed2 = None;
        for f in 0..self.frames.len() {
            if let Some(script) = &self.frames.script[f] {
                self.frames.end[f] = script(t0 + self.settings.dt);
            }
        }
        for k in 0..n_sub {
            let s0 = k as f64 / n_sub as f64;
            let s1 = (k + 1) as f64 / n_sub as f64;
            self.substep(t0 + k as f64 * h, h, s0, s1, 0, &mut m)?;
        }
        for f in 0..self.frames.len() {
            self.frames.start[f] = self.frames.end[f];
        }
        for t in self.obstacle_targets.iter_mut() {
            *t = None;
        }
        self.time = t0 + self.settings.dt;
        let (ke, pe) = match self.energy_cache {
            Some(e) => (e.kinetic, e.elastic + e.gravity),
            None => self.energy(),
        };
        m.time = self.time;
        m.kinetic_energy = ke;
        m.potential_energy = pe;
        let speed2 = match self.scanned_speed2 {
            Some(s2) => s2,
            None => (self.cloth.v.iter())
                .map(|v| v.length_squared())
                .fold(0.0, f64::max),
        };
        m.max_speed = speed2.sqrt();
        m.wall_time_s = wall.elapsed().as_secs_f64();
        self.last = m;
        Ok(&self.last)
    }

    /// World position of a kinematic vertex at fraction `s` of the frame step.
    fn target(&self, k: &Kinematic, s: f64) -> Vec3 {
        match *k {
            Kinematic::Pinned(p) => p,
            Kinematic::Attached { frame, local } => self.frames.at(frame, s).transform_point(local),
        }
    }

    /// One substep from fraction `s0` to `s1` of the frame, redone as halves on divergence.
    fn substep(
        &mut self,
        t: f64,
        h: f64,
        s0: f64,
        s1: f64,
        depth: u32,
        m: &mut StepMetrics,
    ) -> Result<(), Box<DivergenceError>> {
        if self.over_stability_limit(h, depth) {
            // Known to be unstable before trying: an explicit step over its limit is only caught
            // by the energy check once the unstable mode carries a visible share of the energy,
            // and that energy would stay in the cloth. Halve it up front instead.
            m.subdivisions += 1;
            let sm = 0.5 * (s0 + s1);
            self.substep(t, 0.5 * h, s0, sm, depth + 1, m)?;
            return self.substep(t + 0.5 * h, 0.5 * h, sm, s1, depth + 1, m);
        }
        let n = self.cloth.len();
        // 1. Kinematic vertices: start on target, move at the constant velocity that reaches the end target.
        if self.constraints.filter.len() != n {
            self.constraints = Constraints::free(n);
        } else {
            self.constraints.filter.fill(Filter::Free);
        }
        self.constraints.friction.clear();
        for (i, k) in &self.cloth.kinematic {
            let (a, b) = (self.target(k, s0), self.target(k, s1));
            let i = *i as usize;
            self.cloth.x[i] = a;
            self.cloth.v[i] = (b - a) / h;
            self.constraints.filter[i] = Filter::Fixed;
            self.constraints.target_velocity[i] = self.cloth.v[i];
        }
        self.edge_springs();
        let held = self.contact_constraints(t);
        let e0 = match self.energy_cache {
            Some(e) => e,
            None => self.energies(),
        };
        let (e0_total, e0_dynamic) = (e0.total(), e0.dynamic());
        let external = self.external_work_rate(t);
        // The start state moves to the save buffers (a swap, not a copy) and the integrator
        // writes the end state into the cloth's buffers.
        std::mem::swap(&mut self.x_save, &mut self.cloth.x);
        std::mem::swap(&mut self.v_save, &mut self.cloth.v);
        crate::linalg::scratch(&mut self.cloth.x, n);
        crate::linalg::scratch(&mut self.cloth.v, n);

        // 2. Integrate.
        {
            let d = Dynamics {
                effects: &self.effects,
                mass: &self.cloth.mass,
                constraints: &self.constraints,
            };
            let start = (self.x_save.as_slice(), self.v_save.as_slice());
            self.integrator.step_into(
                &d,
                t,
                h,
                start,
                &mut self.cloth.x,
                &mut self.cloth.v,
                &mut self.report,
            );
        }
        let stats = &self.report;
        // Edge springs' end forces, the normal forces of their friction next substep.
        self.spring_forces.clear();
        if self.caps.solves_contacts {
            self.spring_forces.extend(
                self.constraints
                    .contacts
                    .iter()
                    .zip(&stats.contact_forces)
                    .map(|(c, f)| (c.verts, *f)),
            );
            self.spring_forces.sort_by_key(|a| a.0);
        }
        m.force_evaluations += stats.force_evaluations;
        m.cg_iterations += stats.cg_iterations;
        m.cg_residual_max = m.cg_residual_max.max(stats.cg_residual);

        // 3. Constraints: kinematic vertices end exactly on target (no drift from round-off).
        for (i, k) in &self.cloth.kinematic {
            self.cloth.x[*i as usize] = self.target(k, s1);
        }

        // 4. Guard.
        let mut verdict = self.check(h, e0, external.then_some(self.fext.as_slice()));
        if external
            && self.caps.stability_limit.is_none()
            && matches!(verdict, Err((_, Symptom::EnergyGain { .. })))
        {
            verdict = self.check_with_end_forces(t + h, h, e0);
        }
        match verdict {
            Ok((e1, spent, speed2)) => {
                self.scanned_speed2 = Some(speed2);
                if self.energy_budget.is_none() {
                    self.budget_scale = e0_dynamic;
                }
                self.energy_budget = Some(self.energy_budget.unwrap_or(e0_total) + spent);
                self.budget_scale += spent;
                self.energy_cache = Some(e1);
                self.recent_energy[self.substep_count % 16] = e1.dynamic();
                self.substep_count += 1;
            }
            Err((vertex, symptom)) => {
                std::mem::swap(&mut self.cloth.x, &mut self.x_save);
                std::mem::swap(&mut self.cloth.v, &mut self.v_save);
                self.energy_cache = Some(e0);
                let g = self.settings.guard;
                if g.policy == DivergencePolicy::Subdivide && depth < g.max_subdivisions {
                    m.subdivisions += 1;
                    let sm = 0.5 * (s0 + s1);
                    self.substep(t, 0.5 * h, s0, sm, depth + 1, m)?;
                    return self.substep(t + 0.5 * h, 0.5 * h, sm, s1, depth + 1, m);
                }
                return Err(Box::new(self.divergence_error(t, h, vertex, symptom)));
            }
        }

        // 5. Collisions: obstacles move over the substep, then contacts are resolved.
        if let Some(stage) = self.collision.as_mut() {
            stage.advance_obstacles(t, t + h);
            for (idx, target) in self.obstacle_targets.iter().enumerate() {
                if let Some((a, b)) = target {
                    stage.set_obstacle_pose(idx, a.lerp(b, s1));
                }
            }
            self.inv_mass.clone_from(&self.cloth.mass);
            self.inv_mass.iter_mut().for_each(|m| *m = 1.0 / *m);
            for (i, _) in &self.cloth.kinematic {
                self.inv_mass[*i as usize] = 0.0;
            }
            // Normal impulse per unit mass the filter gave each held vertex, for friction:
            // implicit Euler is `m (v1 - v0) = h f(x1, v1) + impulse`. (Start-of-step forces,
            // `f0 h / m`, overstate it up to 1e3 times for a vertex pressed by springs that the
            // implicit step relaxes: every held vertex then stuck, and friction's projection
            // back stretched the springs every step.)
            // In-solve friction's Coulomb limits for the next substep: `mu N` of this solve's
            // normal impulses (zero for vertices not held now).
            self.friction_limit.clear();
            self.friction_limit.resize(n, [(Vec3::ZERO, 0.0); 3]);
            let solves_friction = self.caps.solves_friction;
            if !held.is_empty() {
                let impulses = self.report.impulses();
                if impulses.is_none() {
                    crate::linalg::scratch(&mut self.scratch_f, n);
                    let s = State {
                        t: t + h,
                        x: &self.cloth.x,
                        v: &self.cloth.v,
                    };
                    self.effects.forces(&s, &mut self.scratch_f);
                }
                for (i, normals, mu) in &held {
                    let i = *i;
                    let m = self.cloth.mass[i];
                    // The solver's own constraint impulse when it reports one: the estimate
                    // below also holds the linearisation error of a stretched cloth's end-state
                    // forces (up to 1e4 times the real normal force), and as friction's normal
                    // force it made stretched cloth stick harder the more it was stretched.
                    let dv = match impulses.and_then(|r| r.get(i)) {
                        Some(r) => *r / m,
                        None => self.cloth.v[i] - self.v_save[i] - self.scratch_f[i] * (h / m),
                    };
                    let split = normals.split(dv);
                    for (normal, dvn) in normals.normals().iter().zip(split) {
                        stage.set_held(i, *normal, dvn);
                    }
                    if solves_friction {
                        for (normal, surface) in normals.normals().iter().zip(normals.surfaces()) {
                            if *surface == Vec3::ZERO {
                                stage.set_friction_solved(i, *normal);
                            }
                        }
                        for (slot, (normal, l)) in self.friction_limit[i]
                            .iter_mut()
                            .zip(normals.normals().iter().zip(split))
                        {
                            *slot = (*normal, mu * l.max(0.0) * m / h);
                        }
                    }
                }
            }
            let before = self.energy_cache;
            let r = stage.resolve(
                &self.x_save,
                &mut self.cloth.x,
                &mut self.cloth.v,
                &self.inv_mass,
                h,
            );
            m.contacts = r.contacts;
            m.deepest_penetration = m.deepest_penetration.max(r.deepest_penetration);
            m.self_intersections = match (m.self_intersections, r.self_intersections) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            m.unresolved_contacts += r.unresolved;
            m.collision_time_s += r.time_s;
            m.culled_obstacles = r.culled;
            // A moving obstacle can push energy into the cloth: widen the guard's budget by it.
            let after = self.energies();
            if let (Some(b), Some(budget)) = (before, self.energy_budget.as_mut()) {
                *budget += (after.total() - b.total()).max(0.0);
            }
            self.energy_cache = Some(after);
            self.scanned_speed2 = None;
        }
        m.substeps += 1;
        Ok(())
    }

    /// Whether a substep of `h` exceeds the integrator's stability limit `h omega <= limit` for the
    /// bound `omega^2 <= sum over elastic effects of their Gershgorin bounds`, and the guard's
    /// policy allows halving it. Integrators without a limit (implicit) or with none at all
    /// (forward Euler, limit 0) are left to the reactive guard.
    fn over_stability_limit(&mut self, h: f64, depth: u32) -> bool {
        let g = self.settings.guard;
        if g.policy != DivergencePolicy::Subdivide || depth >= g.max_subdivisions {
            return false;
        }
        let Some(limit) = self.caps.stability_limit.filter(|l| *l > 0.0) else {
            return false;
        };
        h * self.omega_bound() > limit
    }

    /// In-solve friction of vertex `i` held against `normals` (force `f` on it), one per surface:
    /// each surface rubs with its own velocity (a cloth wedged between a moving hand and a
    /// static torso is dragged by one and held by the other; one drag towards their mean
    /// velocity with both limits summed dragged it at half the hand's speed with twice the
    /// grip). The Coulomb limit is the last substep's `mu N` for that surface when the solve
    /// held the vertex against it, else `mu` times the force pressing it into it now.
    fn held_friction(
        &self,
        i: usize,
        normals: &HeldNormals,
        mu: f64,
        f: Vec3,
        out: &mut Vec<crate::integrate::Friction>,
    ) {
        let lagged = self.friction_limit.get(i).copied().unwrap_or_default();
        for (n, surface) in normals.normals().iter().zip(normals.surfaces()) {
            if *surface != Vec3::ZERO {
                // A moving surface does work through friction, and under a kinematic squeeze
                // its normal force is unbounded: its friction stays with the collision stage,
                // bounded by the normal impulses there.
                continue;
            }
            let limit = match lagged.iter().find(|l| l.1 > 0.0 && l.0.dot(*n) > 0.9) {
                Some(l) => l.1,
                None => mu * (-f.dot(*n)).max(0.0),
            };
            if limit > 0.0 {
                out.push(crate::integrate::Friction {
                    vertex: i as u32,
                    limit,
                    reference: *surface,
                });
            }
        }
    }

    /// Static obstacle edges and corners the cloth touched in the last collision pass become
    /// one-sided springs of this substep when the integrator solves them (see
    /// [`crate::integrate::ContactSpring`]), with in-solve Coulomb friction whose limit is `mu`
    /// times the force the same contact's spring ended the last substep with, shared by
    /// weight. The stage then leaves those contacts to the solver unless they end deep.
    fn edge_springs(&mut self) {
        /// `k h^2 / m` of an edge spring at the contact point's mass `m`: the spring stops the
        /// point within a step, and a load of the cloth's own weight per vertex deflects it by
        /// `g h^2 / 1e3` (a micrometre at 120 Hz). Springs as stiff as the cloth's stiffest
        /// mode (`m omega^2`, 40 times stiffer in tests/table_edge.rs) made the re-detection's
        /// drift of micrometres into newtons and slowed a frictionless strip sliding over the
        /// edge (0.39 m instead of 0.57 m in 2 s).
        const CONTACT_STIFFNESS: f64 = 1e3;
        self.constraints.contacts.clear();
        if !self.caps.solves_contacts {
            return;
        }
        // The scene's substep, not a subdivided one: a spring stiffened by `1 / h^2` as the guard
        // halves the step would only store more energy in a contact that is already deep.
        let h = self.settings.dt / f64::from(self.settings.substeps.max(1));
        let n = self.cloth.len();
        let solves_friction = self.caps.solves_friction;
        let Some(stage) = self.collision.as_mut() else {
            return;
        };
        let (mass, filter) = (&self.cloth.mass, &self.constraints.filter);
        let lagged = &self.spring_forces;
        let mut sprung = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for c in stage.feature_contacts() {
            // A face or edge answered in two passes is one contact: keep the first.
            if c.verts.iter().any(|&v| v as usize >= n) || !seen.insert(c.verts) {
                continue;
            }
            let mut spring = crate::integrate::ContactSpring {
                verts: c.verts,
                weights: c.weights,
                normal: c.normal,
                point: c.point,
                gap: c.gap,
                stiffness: 0.0,
                friction: 0.0,
            };
            // `k h^2 / m` at the contact point's mass.
            let m: f64 = spring.slots().map(|(i, w)| w * mass[i]).sum();
            spring.stiffness = CONTACT_STIFFNESS * m / (h * h);
            let movable = spring.slots().any(|(i, _)| filter[i] != Filter::Fixed);
            // A contact already deep (cloth pinched below its thickness under a press that
            // stopped) stays with the collision stage's pinch and push: as a spring it would
            // start with a large stored force (17 J released in one step, measured).
            let deep = spring.depth(&self.cloth.x) > (1.0 - crate::collide::FEATURE_DEEP) * c.gap;
            if !spring.is_valid(n) || !movable || deep {
                continue;
            }
            // The normal force of the last solve's spring on this face or edge (none for a new
            // contact: the collision stage gave it friction): the start depth holds the
            // re-detection's drift, micrometres that the stiff spring turns into newtons.
            let normal_force = lagged
                .binary_search_by(|l| l.0.cmp(&c.verts))
                .map_or(0.0, |k| lagged[k].1);
            if solves_friction {
                spring.friction = c.mu * normal_force;
            }
            sprung.push(c.verts);
            self.constraints.contacts.push(spring);
        }
        stage.set_sprung(sprung);
    }

    /// Bound on the cloth's highest angular frequency (rad/s): the square root of the sum over
    /// elastic effects of their Gershgorin bounds on `omega^2`.
    fn omega_bound(&mut self) -> f64 {
        *self.omega_bound.get_or_insert_with(|| {
            let sum: f64 = self
                .effects
                .stiffness(&self.cloth.mass)
                .iter()
                .map(|b| b.omega_sq)
                .sum();
            sum.sqrt()
        })
    }

    /// Contacts of the last collision pass become constraints of this substep (the survey's mass
    /// modification, `S = I - n n^T`) when the scene's response asks for the filter. A contact whose
    /// vertex is pulled away from the surface by the other forces is released instead of held.
    /// A vertex held by two or three surfaces keeps its velocity along all their normals (see
    /// [`HeldNormals`]). Returns the held vertices with their normals.
    fn contact_constraints(&mut self, t: f64) -> Vec<(usize, HeldNormals, f64)> {
        let mut held = Vec::new();
        let Some(stage) = self.collision.as_ref() else {
            return held;
        };
        if !stage.settings().response.uses_filter() || stage.contacts().is_empty() {
            return held;
        }
        let n = self.cloth.len();
        crate::linalg::scratch(&mut self.scratch_f, n);
        let s = State {
            t,
            x: &self.cloth.x,
            v: &self.cloth.v,
        };
        self.effects.forces(&s, &mut self.scratch_f);
        // The contacts grouped by vertex (in contact order within a vertex).
        let mut contacts: Vec<(usize, Vec3, Vec3, usize)> = stage
            .contacts()
            .iter()
            .map(|c| (c.vertex as usize, c.normal, c.surface_velocity, c.obstacle))
            .filter(|&(i, _, _, _)| i < n && self.constraints.filter[i] != Filter::Fixed)
            .collect();
        contacts.sort_by_key(|c| c.0);
        let solves_friction = self.caps.solves_friction;
        self.friction_limit.resize(n, [(Vec3::ZERO, 0.0); 3]);
        let mut friction = Vec::new();
        for group in contacts.chunk_by(|a, b| a.0 == b.0) {
            let i = group[0].0;
            let f = self.scratch_f[i];
            let Some(normals) = pressing_normals(group, f) else {
                continue;
            };
            let (filter, target) = normals.filter();
            self.constraints.filter[i] = filter;
            self.constraints.target_velocity[i] = target;
            let mu = group
                .iter()
                .map(|c| stage.friction_coefficient(i, c.3))
                .fold(0.0, f64::max);
            held.push((i, normals, mu));
            if solves_friction {
                self.held_friction(i, &normals, mu, f, &mut friction);
            }
        }
        self.constraints.friction.extend(friction);
        held
    }

    /// Work done on the cloth during the substep by forces from outside it (wind and moving
    /// attachments), evaluated at the start state, per unit displacement: returns the forces.
    fn external_work_rate(&mut self, t: f64) -> bool {
        let has_wind = self.effects.iter().any(|e| e.injects_energy());
        let moving_attachments = self
            .cloth
            .kinematic
            .iter()
            .any(|(i, _)| self.cloth.v[*i as usize] != Vec3::ZERO);
        if !has_wind && !moving_attachments {
            return false;
        }
        let s = State {
            t,
            x: &self.cloth.x,
            v: &self.cloth.v,
        };
        let n = self.cloth.len();
        crate::linalg::scratch(&mut self.fext, n);
        self.effects.injecting_forces(&s, &mut self.fext);
        if moving_attachments {
            // Power a driven vertex puts into the cloth: minus the internal force on it times its
            // velocity (gravity on the driven vertex itself does no work on the cloth).
            crate::linalg::scratch(&mut self.scratch_f, n);
            self.effects.forces(&s, &mut self.scratch_f);
            for (i, _) in &self.cloth.kinematic {
                let i = *i as usize;
                self.fext[i] = -self.scratch_f[i];
            }
        }
        true
    }

    /// The guard's second opinion on a substep rejected for energy gain while attachments move:
    /// the start-of-substep force underestimates the work of a driven vertex that stretches the
    /// cloth within the substep (a robot link jumping to a new joint state), so each driven
    /// vertex's work is bounded with the larger of its start and end forces (a bound for a force
    /// that grows monotonically along the path; the trapezoid rule still fell ~20% short on the
    /// robot towel). Wind forces stay start-of-substep. Only for unconditionally stable
    /// integrators: there a large end force is the input's doing, while in an explicit blow-up
    /// it would be the instability's and must not widen the allowance.
    fn check_with_end_forces(
        &mut self,
        t1: f64,
        h: f64,
        e0: Energies,
    ) -> Result<(Energies, f64, f64), (usize, Symptom)> {
        let n = self.cloth.len();
        crate::linalg::scratch(&mut self.scratch_f, n);
        let s = State {
            t: t1,
            x: &self.cloth.x,
            v: &self.cloth.v,
        };
        self.effects.forces(&s, &mut self.scratch_f);
        let mut f = self.fext.clone();
        for (i, _) in &self.cloth.kinematic {
            let i = *i as usize;
            let dx = self.cloth.x[i] - self.x_save[i];
            let end = -self.scratch_f[i];
            if end.dot(dx).abs() > f[i].dot(dx).abs() {
                f[i] = end;
            }
        }
        self.check(h, e0, Some(&f))
    }

    /// Energies of the current state (and the position-only forces there, for the next substep).
    fn energies(&self) -> Energies {
        let (elastic, gravity) = self.effects.energy_split(&self.cloth.x);
        Energies {
            kinetic: self.kinetic_energy(),
            elastic,
            gravity,
        }
    }

    /// Checks the integrator's output; returns the new energies or the first bad vertex.
    ///
    /// Runaway energy: over one substep the total energy may grow by the work of wind and driven
    /// vertices, plus `energy_growth` times the recent peak dynamic energy, plus the first-order
    /// error an explicit step makes under gravity (`h sum m |g| |v|`). An instability multiplies the
    /// dynamic energy every step and trips this within a few steps; a stable step never comes close.
    fn check(
        &self,
        h: f64,
        e0: Energies,
        fext: Option<&[Vec3]>,
    ) -> Result<(Energies, f64, f64), (usize, Symptom)> {
        let c = &self.cloth;
        let g = &self.settings.guard;
        // One pass over the vertices: finiteness, the fastest speed, the kinetic energy, the
        // speed sum of the gravity error bound and the total mass.
        // The energy pass at the new state (whose position-only forces serve the next substep)
        // runs on two threads for large cloths; each also scans its half of the vertices.
        let v_save = &self.v_save;
        let ((elastic, gravity_energy), scan, second) =
            self.effects
                .energy_split_with(&c.x, |r: std::ops::Range<usize>| {
                    let (x, v, v0, m) = (
                        &c.x[r.clone()],
                        &c.v[r.clone()],
                        &v_save[r.clone()],
                        &c.mass[r],
                    );
                    guard::scan_vertices(x, v, v0, m)
                });
        let scan = match second {
            Some(b) => scan.merge(&b),
            None => scan,
        };
        if !scan.finite {
            let bad = (0..c.len()).find(|&i| !c.x[i].is_finite() || !c.v[i].is_finite());
            if let Some(i) = bad {
                return Err((i, Symptom::NonFinite));
            }
        }
        // The first vertex at the top speed: only looked up when a check fails.
        let fastest = || {
            (0..c.len())
                .find(|&i| c.v[i].length_squared() == scan.speed2)
                .unwrap_or(0)
        };
        let (mut kinetic, mass_speed) = (scan.kinetic, scan.mass_speed);
        let speed = scan.speed2.sqrt();
        if speed > g.max_speed {
            return Err((fastest(), Symptom::Speed(speed)));
        }
        for (i, _) in &c.kinematic {
            kinetic -= 0.5 * c.mass[*i as usize] * c.v[*i as usize].length_squared();
        }
        let e1 = Energies {
            kinetic,
            elastic,
            gravity: gravity_energy,
        };
        let (e0_total, e0_dynamic, e1_total) = (e0.total(), e0.dynamic(), e1.total());
        if !e1_total.is_finite() {
            return Err((fastest(), Symptom::NonFinite));
        }
        let work: f64 = match fext {
            Some(f) => (0..c.len())
                .map(|i| f[i].dot(c.x[i] - self.x_save[i]).abs())
                .sum(),
            None => 0.0,
        };
        let gravity = self.effects.gravity().length();
        let gravity_error = h * gravity * mass_speed;
        let floor = 1e-12 * (1.0 + scan.mass);
        let reference = self.recent_energy.iter().fold(e0_dynamic, |a, &b| a.max(b));
        let allowed = work + g.energy_growth * reference + gravity_error + floor;
        let gained = e1_total - e0_total;
        if gained > allowed {
            return Err((fastest(), Symptom::EnergyGain { gained, allowed }));
        }
        let spent = work + gravity_error + floor;
        let budget = self.energy_budget.unwrap_or(e0_total) + spent;
        let scale = if self.energy_budget.is_some() {
            self.budget_scale
        } else {
            e0_dynamic
        } + spent;
        let over = e1_total - budget;
        if over > g.energy_growth * scale + floor {
            return Err((
                fastest(),
                Symptom::EnergyGain {
                    gained: over,
                    allowed: g.energy_growth * scale,
                },
            ));
        }
        Ok((e1, spent, scan.speed2))
    }

    fn divergence_error(&self, t: f64, h: f64, vertex: usize, symptom: Symptom) -> DivergenceError {
        let (cloth, local) = match self.cloth.piece_of(vertex) {
            Some(p) => (p.name.clone(), vertex - p.first_vertex),
            None => (String::from("?"), vertex),
        };
        let suspect = self
            .effects
            .stiffness(&self.cloth.mass)
            .into_iter()
            .next()
            .map(|b| {
                let ho = h * b.omega_sq.sqrt();
                (b, ho)
            });
        DivergenceError {
            time: t,
            step: h,
            cloth,
            vertex: local,
            symptom,
            integrator: self.integrator.name(),
            suspect,
            stability_limit: self.caps.stability_limit,
        }
    }
}

/// The surfaces a vertex with the contacts `group` (vertex, normal, surface velocity, obstacle) is held
/// against this substep, given the force `f` on it, or `None` when it is released from all.
///
/// A contact whose surface the force pulls the vertex off is released, but not alone: the
/// surfaces still held steer the vertex. In a wedge (cloth pressed by a moving slanted face
/// against a table) the springs lift an edge vertex a little off the table while the face
/// pushes it along its normal, which points into the table; released from the table, the
/// solver drove it 9 mm through it in one substep and the collision stage's push back stored
/// 0.7 J in the springs. So a released contact is taken back while the held ones' filtered
/// force, or their surfaces' velocities, drive the vertex into its surface.
fn pressing_normals(group: &[(usize, Vec3, Vec3, usize)], f: Vec3) -> Option<HeldNormals> {
    let mut held: Vec<bool> = group.iter().map(|c| f.dot(c.1) <= 0.0).collect();
    let build = |held: &[bool]| {
        HeldNormals::from_contacts(
            group
                .iter()
                .zip(held)
                .filter(|(_, h)| **h)
                .map(|(c, _)| (c.1, c.2)),
        )
    };
    let mut normals = build(&held);
    if normals.is_empty() {
        return None;
    }
    // Each pass can only add contacts, so at most one pass per contact.
    for _ in 0..group.len() {
        let (filter, target) = normals.filter();
        let f_free = filter.apply(f);
        let driven = target - filter.apply(target);
        let mut added = false;
        for (c, h) in group.iter().zip(held.iter_mut()) {
            if !*h && (f_free.dot(c.1) < 0.0 || (driven - c.2).dot(c.1) < 0.0) {
                *h = true;
                added = true;
            }
        }
        if !added {
            break;
        }
        normals = build(&held);
    }
    Some(normals)
}
