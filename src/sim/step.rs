//! `Simulation::step`: the order of one frame step, as a table of contents.
//!
//! One frame of `dt` is `substeps` substeps of `h = dt / substeps`, each a [`Span`]. A substep
//! runs these stages in this order (each one named call in [`Simulation::attempt`]); the guard
//! answers its checks with a verdict that goes on, or splits the substep in two, or stops:
//! 0. the guard splits up front a substep over the integrator's stability limit, or one in
//!    which a moving obstacle would outrun the cloth near it (see [`super::fast`]);
//! 1. kinematic vertices get their end-of-substep targets (frames interpolated across the frame);
//! 2. coupling in: the last collision pass's contacts become the solver's constraints;
//! 3. the guard books the start (energies, forces from outside); effects give forces and the
//!    integrator advances the state (the start state is kept); the work moving contacts did
//!    inside the solve goes to the guard;
//! 4. kinematic vertices are put exactly on their end-of-substep targets;
//! 5. the guard checks the solved state (finite, speeds, energy: a rejected substep is rolled
//!    back, then split or stopped per policy); edges the solve left beyond their material's
//!    strain limit are shortened (see [`super::limit`]);
//! 6. the guard saves what a rollback after the collision pass needs, where its strain check
//!    applies; obstacles move over the substep;
//! 7. coupling out: what the solver did becomes the collision stage's feedback;
//! 8. collisions fix the new state; metrics are recorded;
//! 9. the guard checks the state the substep ends in: an edge the collision response stretched
//!    beyond the strain bound, a vertex it moved more than fast contact allows, or cloth-cloth
//!    pairs the self-contact fail-safe gave up on, rolls the whole substep back to be split (see
//!    [`super::guard`]).
//!
//! The guard's energy pass at the new state also computes the position-only forces there, which
//! the next substep's first force evaluation reuses (see [`EffectSet::energy_split`]), so a
//! guarded explicit substep costs one pass over the effects. The same pass scans the vertices for
//! the guard (finiteness, speed, kinetic energy), on two threads for large cloths. The rollback
//! state costs no copy: the start state's buffers are swapped out and the integrator writes the
//! end state out of place ([`Integrator::step_into`]).
//!
//! [`EffectSet::energy_split`]: crate::effects::EffectSet::energy_split
//! [`Integrator::step_into`]: crate::integrate::Integrator::step_into

use super::coupling::StartState;
use super::energy::Energies;
use super::error::{divergence_error, DivergenceError};
use super::guard::{self, Failure, Redo, Verdict};
use super::metrics::StepMetrics;
use super::simulation::Simulation;
use super::span::Span;
use crate::integrate::Dynamics;
use std::time::Instant;

impl Simulation {
    /// Switches fast-contact splitting and the guard's checks after the collision pass off or
    /// back on (on by default): what they cost is measured against this
    /// (`benches/fast_links.rs`).
    pub fn set_fast_contact(&mut self, on: bool) {
        self.guard.set_contact_checks(on);
    }

    /// Advances one frame (`settings.dt`) and says what it did.
    pub fn step(&mut self) -> Result<StepMetrics, Box<DivergenceError>> {
        let wall = Instant::now();
        let mut m = StepMetrics::default();
        let n_sub = self.settings.substeps.max(1);
        let h = self.settings.dt / f64::from(n_sub);
        let t0 = self.time;
        self.guard.start_frame();
        self.frames.script_targets(t0 + self.settings.dt);
        for k in 0..n_sub {
            self.substep(Span::of_frame(t0, h, k, n_sub), &mut m)?;
        }
        self.frames.finish_step();
        for t in self.obstacle_targets.iter_mut() {
            *t = None;
        }
        self.time = t0 + self.settings.dt;
        let (ke, pe) = match self.guard.energy() {
            Some(e) => (e.kinetic, e.elastic + e.gravity),
            None => self.energy(),
        };
        m.time = self.time;
        m.kinetic_energy = ke;
        m.potential_energy = pe;
        let speed2 = match self.guard.scanned_speed2() {
            Some(s2) => s2,
            None => (self.cloth.v.iter())
                .map(|v| v.length_squared())
                .fold(0.0, f64::max),
        };
        m.max_speed = speed2.sqrt();
        (m.held_inside, m.held_inside_depth) = self.held_inside();
        m.wall_time_s = wall.elapsed().as_secs_f64();
        self.last = m.clone();
        Ok(m)
    }

    /// The kinematic vertices inside an obstacle's solid, and the deepest (m); nothing to test
    /// without a collision stage or kinematic vertices.
    fn held_inside(&mut self) -> (usize, f64) {
        let Some(stage) = self.collision.as_ref() else {
            return (0, 0.0);
        };
        if self.cloth.kinematic.is_empty() {
            return (0, 0.0);
        }
        let solids = match &mut self.work.solids {
            Some(s) if s.covers(stage) => s,
            cache => cache.insert(crate::collide::Solids::of(stage)),
        };
        (self.cloth.kinematic.iter())
            .map(|(i, _)| solids.depth(stage, self.cloth.x[*i as usize]))
            .filter(|d| *d > 0.0)
            .fold((0, 0.0), |(n, deepest), d| (n + 1, f64::max(deepest, d)))
    }

    /// One substep over `span`, redone as two halves where the guard's verdict says so.
    fn substep(&mut self, span: Span, m: &mut StepMetrics) -> Result<(), Box<DivergenceError>> {
        match self.attempt(span, m) {
            Ok(()) => {
                m.substeps += 1;
                Ok(())
            }
            Err(Redo::Split(why)) => {
                why.count(m);
                let [first, second] = span.halves();
                self.substep(first, m)?;
                self.substep(second, m)
            }
            Err(Redo::Fail(failure)) => Err(Box::new(self.divergence_error(span, failure))),
        }
    }

    /// The stages of one substep over `span`, in the module doc's order; a check the guard
    /// does not pass ends it, with the state back at the substep's start.
    fn attempt(&mut self, span: Span, m: &mut StepMetrics) -> Verdict {
        self.split_up_front(span, m)?; // 0
        self.kinematic_targets(span); // 1
        self.coupling_in(span); // 2
        let e0 = self.start(span); // 3
        self.integrate(span, m);
        self.snap_kinematic(span); // 4
        self.check_solve(span, e0)?; // 5
        self.limit_strain(span, m);
        self.watch_response(); // 6
        self.move_obstacles(span);
        self.coupling_out(span); // 7
        self.collide(span, m); // 8
        self.check_response(span, m) // 9
    }

    /// The error for a substep that failed.
    fn divergence_error(&self, span: Span, f: Failure) -> DivergenceError {
        divergence_error(
            (&self.cloth, &self.model.effects),
            self.integrator.name(),
            (self.model.caps.stability_limit, self.model.omega_bound),
            (span.t, span.h),
            f.vertex,
            f.symptom,
        )
    }

    /// Stage 0: the guard's split before trying (see [`guard::Guard::split_up_front`]).
    fn split_up_front(&mut self, span: Span, m: &mut StepMetrics) -> Verdict {
        self.guard.split_up_front(
            &self.settings.guard,
            span,
            self.model.stability(),
            self.collision.as_ref(),
            &self.obstacle_targets,
            (&self.cloth, &self.model.effects),
            &mut self.work.near,
            m,
        )
    }

    /// Stage 1: Kinematic vertices start on their target at `s0` and move at the constant velocity
    /// that reaches the one at `s1`; the solver's filter fixes them at that velocity.
    fn kinematic_targets(&mut self, span: Span) {
        self.coupling.begin(self.cloth.len());
        for (i, k) in &self.cloth.kinematic {
            let (a, b) = (
                self.frames.target(k, span.s0),
                self.frames.target(k, span.s1),
            );
            let i = *i as usize;
            self.cloth.x[i] = a;
            self.cloth.v[i] = (b - a) / span.h;
            self.coupling.fix(i, self.cloth.v[i]);
        }
    }

    /// Stage 2: Coupling in: the last collision pass's contacts become this substep's constraints
    /// (filter, friction, edge springs; the edges of obstacles moving in this substep aimed at
    /// where they will be at its end); see [`super::coupling`].
    fn coupling_in(&mut self, span: Span) {
        let mut poses = Vec::new();
        if let Some(stage) = self.collision.as_mut() {
            let targets = &self.obstacle_targets;
            poses.extend(
                (stage.obstacles().iter().enumerate())
                    .map(|(k, o)| span.poses(o, targets.get(k).and_then(Option::as_ref))),
            );
            let ends: Vec<Option<crate::Pose>> = (poses.iter())
                .map(|&(a, b)| (a != b).then_some(b))
                .collect();
            if ends.iter().any(Option::is_some) {
                stage.aim_feature_contacts(|k| ends.get(k).copied().flatten());
            }
        }
        let start = StartState {
            cloth: &self.cloth,
            effects: &self.model.effects,
            t: span.t,
            h_scene: self.settings.substep(),
            h: span.h,
            obstacle_poses: &poses,
        };
        let stage = self.collision.as_ref();
        let scratch = &mut self.work.scratch_f;
        let caps = &self.model.caps;
        self.coupling.contacts_in(stage, &start, caps, scratch);
    }

    /// Stage 3, first: the guard books the substep's start; its energies are returned.
    fn start(&mut self, span: Span) -> Energies {
        let w = &mut self.work;
        let cloth = (&self.cloth, &self.model.effects);
        (self.guard).start(
            &mut w.saved,
            cloth,
            span.t,
            &mut w.outside,
            &mut w.scratch_f,
        )
    }

    /// Stage 3: Integrate: the start state moves to the work's start buffers (a swap, not a copy)
    /// and the integrator writes the end state into the cloth's buffers; its contact forces go to
    /// the coupling, its counts to the metrics, the work moving contacts did in it to the guard's
    /// outside forces.
    fn integrate(&mut self, span: Span, m: &mut StepMetrics) {
        let n = self.cloth.len();
        std::mem::swap(&mut self.work.x_start, &mut self.cloth.x);
        std::mem::swap(&mut self.work.v_start, &mut self.cloth.v);
        crate::linalg::scratch(&mut self.cloth.x, n);
        crate::linalg::scratch(&mut self.cloth.v, n);
        let d = Dynamics {
            effects: &self.model.effects,
            mass: &self.cloth.mass,
            constraints: &self.coupling.constraints,
            nominal_step: self.settings.substep(),
        };
        let w = &mut self.work;
        let start = (w.x_start.as_slice(), w.v_start.as_slice());
        let (x, v) = (&mut self.cloth.x, &mut self.cloth.v);
        (self.integrator).step_into(&d, span.t, span.h, start, x, v, &mut w.report);
        let solves_contacts = self.model.caps.solves_contacts;
        let forces = w.report.contact_forces.as_slice();
        self.coupling
            .solved(solves_contacts.then_some(forces), &self.cloth.v);
        m.add_solve(&w.report);
        m.add_pinch(self.coupling.pinch_grip);
        m.slipping_vertices = self.coupling.layer_slipping;
        let c = &self.coupling;
        guard::moving_contact_work(
            &c.constraints,
            &c.moving_springs,
            &w.report,
            solves_contacts,
            (n, span.h),
            &mut w.outside,
        );
    }

    /// Stage 4: Kinematic vertices end exactly on target (no drift from round-off).
    fn snap_kinematic(&mut self, span: Span) {
        for (i, k) in &self.cloth.kinematic {
            self.cloth.x[*i as usize] = self.frames.target(k, span.s1);
        }
    }

    /// Stage 5: The guard's verdict on the solved substep started at energies `e0` (see
    /// [`guard::Guard::check_solve`]).
    fn check_solve(&mut self, span: Span, e0: Energies) -> Verdict {
        let w = &mut self.work;
        self.guard.check_solve(
            &self.settings.guard,
            span,
            (&mut self.cloth, &self.model.effects),
            (&mut w.x_start, &mut w.v_start),
            e0,
            self.model.caps.stability_limit.is_some(),
            &w.outside,
            &mut w.scratch_f,
        )
    }

    /// Stage 5, after the guard's check: edges the solve left longer than their material's
    /// strain limit are shortened (see [`super::limit`]). Nothing when no material sets a limit.
    fn limit_strain(&mut self, span: Span, m: &mut StepMetrics) {
        let Some(limit) = self.model.limit.as_ref() else {
            return;
        };
        let w = &mut self.work;
        self.cloth.inverse_masses_into(&mut w.inv_mass);
        let c = &mut self.cloth;
        let r = limit.apply(
            &mut w.tethers,
            &mut c.x,
            &mut c.v,
            &w.inv_mass,
            &c.kinematic,
            span.h,
        );
        m.add_limit(&r);
    }

    /// Stage 6, first: the guard decides whether it checks the collision pass's answer and saves
    /// what a rollback after it needs (see [`guard::Guard::watch_response`]).
    fn watch_response(&mut self) {
        let cloth = (&self.cloth, &self.model.effects);
        (self.guard).watch_response(self.collision.as_ref(), cloth, &mut self.work.saved);
    }

    /// Stage 6: Obstacles move over the span: scripted ones by their motion, driven ones to
    /// fraction `s1` of their frame targets.
    fn move_obstacles(&mut self, span: Span) {
        let Some(stage) = self.collision.as_mut() else {
            return;
        };
        stage.advance_obstacles(span.t, span.t + span.h);
        for (idx, target) in self.obstacle_targets.iter().enumerate() {
            if let Some((a, b)) = target {
                stage.set_obstacle_pose(idx, a.lerp(b, span.s1));
            }
        }
    }

    /// Stage 7: Coupling out: the solver's impulses on held vertices become the stage's feedback
    /// (and in-solve friction's next limits); see [`super::coupling`]. Nothing without a stage.
    fn coupling_out(&mut self, span: Span) {
        if self.collision.is_none() {
            return;
        }
        let solves_friction = self.model.caps.solves_friction;
        let impulses = self.work.report.impulses();
        let (v0, scratch) = (&self.work.v_start, &mut self.work.scratch_f);
        let (cloth, effects) = (&self.cloth, &self.model.effects);
        self.coupling.feedback_out(
            cloth,
            effects,
            v0,
            (span.t, span.h),
            solves_friction,
            impulses,
            scratch,
        );
    }

    /// Stage 8: Collisions fix the end state (kinematic vertices have infinite mass), with the
    /// solver's feedback; the report goes to the metrics and the energy change to the guard.
    fn collide(&mut self, span: Span, m: &mut StepMetrics) {
        let Some(stage) = self.collision.as_mut() else {
            return;
        };
        let inv_mass = &mut self.work.inv_mass;
        self.cloth.inverse_masses_into(inv_mass);
        let (x, v) = (&mut self.cloth.x, &mut self.cloth.v);
        let bound = self.model.response_bound.as_ref();
        if bound.is_some() {
            self.work.pre_collision.clone_from(x);
        }
        let feedback = &self.coupling.feedback;
        let before = &self.work.pre_collision;
        let inv_mass = &*inv_mass;
        // Between the obstacles' passes and cloth-cloth contact, which then sees every move: an
        // obstacle's answer past the bound goes to the next solve, or where it cannot, is spread
        // over the cloth around it (see `super::limit`).
        let hold = |stage: &crate::collide::CollisionStage, x: &mut [crate::Vec3]| {
            let Some(bound) = bound else {
                return;
            };
            // Only the vertex pass's answers go back: a feature answer keeps an obstacle's edge
            // or rod from passing between vertices, which no vertex's own way back would see.
            let by_obstacle = |i: usize| {
                stage.contact_kind(i, false) == Some(crate::collide::ContactKind::ObstacleVertex)
            };
            let clear = |a, b| super::limit::clear_of_obstacles(stage, a, b);
            bound.hold_response(before, x, by_obstacle, clear);
            let clear = |k, a, b| super::limit::clear_of_layers(stage, k, a, b);
            let edge_clear = |a, b| super::limit::clear_of_obstacles(stage, a, b);
            let thickness = |k| stage.thickness_of(k);
            bound.spread_response(before, x, inv_mass, clear, edge_clear, thickness);
        };
        // Cloth-cloth repulsion's answers likewise go back to the next solve, whose layer
        // springs hold the layers apart, where they stretch an edge past the bound; the CCD
        // passes and impact zones after it keep the layers from crossing.
        let mut repelled = |before: &[crate::Vec3], x: &mut [crate::Vec3]| {
            if let Some(bound) = bound {
                bound.hold_response(before, x, |_| true, |_, _| true);
            }
        };
        let x0 = &self.work.x_start;
        let r = stage.resolve_with(x0, x, v, inv_mass, span.h, feedback, hold, &mut repelled);
        m.add_collision(&r);
        let after = Energies::of(&self.cloth, &self.model.effects);
        self.guard.collided(after, r.unresolved);
    }

    /// Stage 9: the guard's verdict on the state the substep ends in (see
    /// [`guard::Guard::check_response`]).
    fn check_response(&mut self, span: Span, m: &mut StepMetrics) -> Verdict {
        let w = &mut self.work;
        self.guard.check_response(
            &self.settings.guard,
            span,
            self.collision.as_mut(),
            &mut self.cloth,
            (&mut w.x_start, &mut w.v_start),
            &w.saved,
            m,
        )
    }
}
