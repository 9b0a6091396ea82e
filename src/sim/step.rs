//! `Simulation::step`: the order of one frame step, as a table of contents.
//!
//! One frame of `dt` is `substeps` substeps of `h = dt / substeps`. Each substep runs one way
//! (each stage below is one named call, with its inputs and outputs in its doc):
//! 0. a moving obstacle that would outrun the cloth near it splits the substep in two (see
//!    [`super::fast`]);
//! 1. kinematic vertices get their end-of-substep targets (frames interpolated across the frame);
//! 2. coupling in: the last collision pass's contacts become the solver's constraints;
//! 3. effects give forces and the integrator advances the state (the start state is kept);
//! 4. kinematic vertices are put exactly on their end-of-substep targets;
//! 5. the guard checks the result (and subdivides or stops per policy); then edges the solve
//!    left beyond their material's strain limit are shortened (see [`super::limit`]);
//! 6. obstacles move over the substep;
//! 7. coupling out: what the solver did becomes the collision stage's feedback;
//! 8. collisions fix the new state; metrics are recorded;
//! 9. the guard checks the state the substep ends in for edges the collision response stretched
//!    beyond the strain bound (and rolls the whole substep back per policy), and for vertices
//!    the obstacle response moved more than fast contact allows (then the substep is rolled back
//!    and split as in 0; see [`super::fast`]).
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
use super::error::{DivergenceError, Symptom};
use super::fast;
use super::guard::{self, Book, DivergencePolicy, Sample};
use super::metrics::StepMetrics;
use super::simulation::Simulation;
use crate::integrate::Dynamics;
use crate::Vec3;
use std::time::Instant;

impl Simulation {
    /// Switches the fast-contact splitting and the guard's strain check off or back on (on by
    /// default): what they cost is measured against this (`benches/fast_links.rs`).
    pub fn set_fast_contact(&mut self, on: bool) {
        self.guard.fast_off = !on;
    }

    /// Advances one frame (`settings.dt`).
    pub fn step(&mut self) -> Result<&StepMetrics, Box<DivergenceError>> {
        let wall = Instant::now();
        let mut m = StepMetrics::default();
        let n_sub = self.settings.substeps.max(1);
        let h = self.settings.dt / n_sub as f64;
        let t0 = self.time;
        self.guard.start_frame();
        self.frames.script_targets(t0 + self.settings.dt);
        for k in 0..n_sub {
            let s0 = k as f64 / n_sub as f64;
            let s1 = (k + 1) as f64 / n_sub as f64;
            self.substep(t0 + k as f64 * h, h, s0, s1, 0, &mut m)?;
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
        m.wall_time_s = wall.elapsed().as_secs_f64();
        self.last = m;
        Ok(&self.last)
    }

    /// One substep from fraction `s0` to `s1` of the frame, redone as halves on divergence, or
    /// split up front where an obstacle outruns cloth within its reach.
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
            return self.halves(t, h, (s0, s1), depth, m);
        }
        let obstacle_speed = match self.fast_contact(t, h, (s0, s1), depth) {
            Err(()) => {
                m.contact_splits += 1;
                return self.halves(t, h, (s0, s1), depth, m);
            }
            Ok((speed, refused)) => {
                m.contact_splits_refused += u32::from(refused);
                speed
            }
        };
        let book = self.guard.book();
        self.kinematic_targets(h, s0, s1);
        self.coupling_in(t, h, (s0, s1));
        let e0 = self.guard.start_energies(&self.cloth, &self.model.effects);
        let external = self.external_forces(t);
        self.integrate(t, h, m);
        self.snap_kinematic(s1);
        let external = self.moving_contact_work(external, h);
        if let Err(failure) = self.check(t, h, e0, external) {
            self.roll_back(e0);
            return self.rejected(t, h, (s0, s1), depth, m, failure);
        }
        self.limit_strain(h, m);
        let strained = self.guard_strain();
        if self.collision.is_some() {
            if strained {
                self.save_stage();
            }
            self.move_obstacles(t, h, s1);
            self.coupling_out(t, h);
            self.collide(h, m);
        }
        if strained {
            if let Err(failure) = self.check_strain(obstacle_speed) {
                // Subdivide: halved while the guard may; at its deepest level the response cannot
                // do better and the state is kept (its stretch is on /diagnostics). Stop: stop.
                let g = self.settings.guard;
                if g.policy == DivergencePolicy::Stop || depth < g.max_subdivisions {
                    self.roll_back_collided(book);
                    return self.rejected(t, h, (s0, s1), depth, m, failure);
                }
            }
            if self.response_jumped() {
                if depth < self.split_levels() {
                    self.roll_back_collided(book);
                    m.contact_splits += 1;
                    return self.halves(t, h, (s0, s1), depth, m);
                }
                m.contact_splits_refused += 1;
            }
        }
        m.substeps += 1;
        Ok(())
    }

    /// A rejected substep (already rolled back): redone as halves when the policy allows, else
    /// the error.
    fn rejected(
        &mut self,
        t: f64,
        h: f64,
        (s0, s1): (f64, f64),
        depth: u32,
        m: &mut StepMetrics,
        (vertex, symptom): (usize, Symptom),
    ) -> Result<(), Box<DivergenceError>> {
        let g = self.settings.guard;
        if g.policy == DivergencePolicy::Subdivide && depth < g.max_subdivisions {
            m.subdivisions += 1;
            return self.halves(t, h, (s0, s1), depth, m);
        }
        Err(Box::new(self.divergence_error(t, h, vertex, symptom)))
    }

    /// The substep `(t, h)` over frame fractions `s0..s1` as two halves, one level deeper.
    fn halves(
        &mut self,
        t: f64,
        h: f64,
        (s0, s1): (f64, f64),
        depth: u32,
        m: &mut StepMetrics,
    ) -> Result<(), Box<DivergenceError>> {
        let sm = 0.5 * (s0 + s1);
        self.substep(t, 0.5 * h, s0, sm, depth + 1, m)?;
        self.substep(t + 0.5 * h, 0.5 * h, sm, s1, depth + 1, m)
    }

    /// Stage 0: whether a moving obstacle outruns cloth within its reach over this substep (see
    /// [`fast`]): `Err` asks for a split (within the guard's levels of halving and of fast
    /// contact), `Ok` gives the fastest obstacle point's speed (m/s) for the strain bound, and
    /// whether a split was wanted that `max_contact_split_levels` refused. Static obstacles
    /// cost nothing.
    fn fast_contact(
        &mut self,
        t: f64,
        h: f64,
        (s0, s1): (f64, f64),
        depth: u32,
    ) -> Result<(f64, bool), ()> {
        let Some(stage) = self.collision.as_ref().filter(|_| !self.guard.fast_off) else {
            return Ok((0.0, false));
        };
        let may_split = depth < self.split_levels();
        // At the budget's depth (not the guard's) the test still runs, to count the refusal.
        let test = may_split || depth < self.settings.guard.max_subdivisions;
        let (cloth, targets) = (&self.cloth, &self.obstacle_targets);
        let near = &mut self.work.near;
        let (mut top, mut refused) = (0.0f64, false);
        let mut thickness = None;
        for (k, o) in stage.obstacles().iter().enumerate() {
            let target = targets.get(k).and_then(Option::as_ref);
            let poses = fast::substep_poses(o, target, (t, h), (s0, s1));
            if poses.0 == poses.1 {
                continue;
            }
            top = top.max(fast::top_speed(o, poses, h));
            if !test || refused {
                continue;
            }
            let strain = self.guard.strain_model(cloth, &self.model.effects);
            let reach = fast::Reach {
                thickness: *thickness
                    .get_or_insert_with(|| cloth.thickness.iter().copied().fold(0.0, f64::max)),
                spacing: strain.max_spacing(),
            };
            if fast::outruns(o, poses, cloth, h, reach, |i| strain.spacing(i), near) {
                if !may_split {
                    refused = true;
                    continue;
                }
                return Err(());
            }
        }
        Ok((top, refused))
    }

    /// How many levels of halving fast contact may split a scene substep into: the guard's, or
    /// fewer when `max_contact_split_levels` bounds what a live node spends on it.
    fn split_levels(&self) -> u32 {
        let g = self.settings.guard;
        g.max_contact_split_levels
            .map_or(g.max_subdivisions, |l| l.min(g.max_subdivisions))
    }

    /// Stage 9, after the strain check: whether the collision pass moved a vertex it answered
    /// for an obstacle by more than a third of its spacing from where the solve left it (see
    /// [`fast::jumped`]); such a substep is rolled back and split like one fast contact predicts.
    /// Only where the strain check applies (it keeps the solved positions), and not while the
    /// cloth is still leaving an obstacle the scene started it in (the lead-out moves a vertex a
    /// sixth of its shortest edge per pass at most; the strain check waits too).
    fn response_jumped(&self) -> bool {
        let (Some(stage), Some(strain)) = (self.collision.as_ref(), self.guard.strain.as_ref())
        else {
            return false;
        };
        if self.guard.inside != Some(false) {
            return false;
        }
        fast::jumped(
            &self.guard.x_solved,
            &self.cloth.x,
            |i| strain.spacing(i),
            |i| stage.contact_kind(i, false).is_some(),
        )
    }

    /// Whether the substep is over the integrator's stability limit (see
    /// [`guard::over_stability_limit`]).
    fn over_stability_limit(&mut self, h: f64, depth: u32) -> bool {
        let limit = self.model.caps.stability_limit;
        let (model, mass) = (&mut self.model, &self.cloth.mass);
        guard::over_stability_limit(&self.settings.guard, limit, h, depth, || {
            model.omega_bound(mass)
        })
    }

    /// Stage 1: Kinematic vertices start on their target at `s0` and move at the constant velocity
    /// that reaches the one at `s1`; the solver's filter fixes them at that velocity.
    fn kinematic_targets(&mut self, h: f64, s0: f64, s1: f64) {
        self.coupling.begin(self.cloth.len());
        for (i, k) in &self.cloth.kinematic {
            let (a, b) = (self.frames.target(k, s0), self.frames.target(k, s1));
            let i = *i as usize;
            self.cloth.x[i] = a;
            self.cloth.v[i] = (b - a) / h;
            self.coupling.fix(i, self.cloth.v[i]);
        }
    }

    /// Stage 2: Coupling in: the last collision pass's contacts become this substep's constraints
    /// (filter, friction, edge springs; the edges of obstacles moving in this substep aimed at
    /// where they will be at its end); see [`super::coupling`].
    fn coupling_in(&mut self, t: f64, h: f64, (s0, s1): (f64, f64)) {
        if let Some(stage) = self.collision.as_mut() {
            let targets = &self.obstacle_targets;
            let ends: Vec<Option<crate::Pose>> = (stage.obstacles().iter().enumerate())
                .map(|(k, o)| {
                    let target = targets.get(k).and_then(Option::as_ref);
                    let (a, b) = fast::substep_poses(o, target, (t, h), (s0, s1));
                    (a != b).then_some(b)
                })
                .collect();
            if ends.iter().any(Option::is_some) {
                stage.aim_feature_contacts(|k| ends.get(k).copied().flatten());
            }
        }
        let start = StartState {
            cloth: &self.cloth,
            effects: &self.model.effects,
            t,
            h_scene: self.settings.substep(),
            h,
        };
        let stage = self.collision.as_ref();
        let scratch = &mut self.work.scratch_f;
        let caps = &self.model.caps;
        self.coupling.contacts_in(stage, &start, caps, scratch);
    }

    /// The forces from outside the cloth at the start of the substep, for the guard (into
    /// `work.fext`); false when there are none.
    fn external_forces(&mut self, t: f64) -> bool {
        let (fext, scratch) = (&mut self.work.fext, &mut self.work.scratch_f);
        guard::external_forces(&self.cloth, &self.model.effects, t, fext, scratch)
    }

    /// Moving obstacles do work on the cloth inside the solve: through the springs on their
    /// features (a link carrying the cloth), through the filter holding a vertex at a moving
    /// surface's velocity (a ball pushing it) and through that surface's friction (a forearm
    /// dragging a hem). All are work from outside: the springs' end forces, the held vertices'
    /// constraint impulses over `h` and the friction drags' end forces join `work.fext` (zeroed
    /// first when `external` says it holds nothing). Returns whether `work.fext` now holds external
    /// forces. Nothing is added where nothing moves (bit for bit what the guard did before).
    fn moving_contact_work(&mut self, external: bool, h: f64) -> bool {
        let c = &self.coupling.constraints;
        let springs = &self.coupling.moving_springs;
        let report = &self.work.report;
        let impulses = report.impulses();
        let held_moving = |i: usize| {
            !matches!(
                c.filter[i],
                crate::linalg::Filter::Free | crate::linalg::Filter::Fixed
            ) && c.target_velocity[i] != Vec3::ZERO
        };
        let n = self.cloth.len();
        let any_held = impulses.is_some() && (0..n).any(held_moving);
        let rubbed = &report.moving_friction;
        if !any_held
            && rubbed.is_empty()
            && (springs.is_empty() || !self.model.caps.solves_contacts)
        {
            return external;
        }
        let fext = &mut self.work.fext;
        if !external {
            crate::linalg::scratch(fext, n);
        }
        if self.model.caps.solves_contacts {
            for &k in springs {
                if let (Some(spring), Some(f)) = (c.contacts.get(k), report.contact_forces.get(k)) {
                    spring.add_point_force(spring.normal * *f, 1.0, fext);
                }
            }
        }
        if let Some(r) = impulses.filter(|_| any_held) {
            for i in (0..n).filter(|&i| held_moving(i)) {
                fext[i] += r[i] / h;
            }
        }
        for &(i, f) in rubbed.iter().filter(|r| (r.0 as usize) < n) {
            fext[i as usize] += f;
        }
        true
    }

    /// Stage 3: Integrate: the start state moves to the save buffers (a swap, not a copy) and the
    /// integrator writes the end state into the cloth's buffers; its contact forces go to the
    /// coupling, its counts to the metrics.
    fn integrate(&mut self, t: f64, h: f64, m: &mut StepMetrics) {
        let n = self.cloth.len();
        std::mem::swap(&mut self.work.x_save, &mut self.cloth.x);
        std::mem::swap(&mut self.work.v_save, &mut self.cloth.v);
        crate::linalg::scratch(&mut self.cloth.x, n);
        crate::linalg::scratch(&mut self.cloth.v, n);
        let d = Dynamics {
            effects: &self.model.effects,
            mass: &self.cloth.mass,
            constraints: &self.coupling.constraints,
            nominal_step: self.settings.substep(),
        };
        let w = &mut self.work;
        let start = (w.x_save.as_slice(), w.v_save.as_slice());
        let (x, v) = (&mut self.cloth.x, &mut self.cloth.v);
        self.integrator
            .step_into(&d, t, h, start, x, v, &mut w.report);
        let forces = w.report.contact_forces.as_slice();
        self.coupling
            .solved(self.model.caps.solves_contacts.then_some(forces));
        m.add_solve(&w.report);
    }

    /// Stage 4: Kinematic vertices end exactly on target (no drift from round-off).
    fn snap_kinematic(&mut self, s1: f64) {
        for (i, k) in &self.cloth.kinematic {
            self.cloth.x[*i as usize] = self.frames.target(k, s1);
        }
    }

    /// Stage 5: The guard's verdict on the solved substep started at energies `e0`; an accepted one
    /// is booked. `external`: whether `work.fext` holds external forces.
    fn check(
        &mut self,
        t: f64,
        h: f64,
        e0: Energies,
        external: bool,
    ) -> Result<(), (usize, Symptom)> {
        let g = self.settings.guard;
        let w = &mut self.work;
        let s = Sample {
            cloth: &self.cloth,
            effects: &self.model.effects,
            x0: &w.x_save,
            v0: &w.v_save,
        };
        let mut verdict = self
            .guard
            .check(&g, &s, h, e0, external.then_some(w.fext.as_slice()));
        if external
            && self.model.caps.stability_limit.is_none()
            && matches!(verdict, Err((_, Symptom::EnergyGain { .. })))
        {
            let scratch = &mut w.scratch_f;
            verdict = self
                .guard
                .check_with_end_forces(&g, &s, t + h, h, e0, &w.fext, scratch);
        }
        let accepted = verdict?;
        self.guard.accept(e0, accepted);
        Ok(())
    }

    /// The substep failed: the start state comes back from the save buffers.
    fn roll_back(&mut self, e0: Energies) {
        std::mem::swap(&mut self.cloth.x, &mut self.work.x_save);
        std::mem::swap(&mut self.cloth.v, &mut self.work.v_save);
        self.guard.reject(e0);
    }

    /// The error for the failed substep, with the cause only where the stability bound says so.
    fn divergence_error(
        &mut self,
        t: f64,
        h: f64,
        vertex: usize,
        symptom: Symptom,
    ) -> DivergenceError {
        let omega = self.model.omega_bound(&self.cloth.mass);
        guard::divergence_error(
            &self.cloth,
            &self.model.effects,
            self.integrator.name(),
            self.model.caps.stability_limit,
            omega,
            (t, h),
            vertex,
            symptom,
        )
    }

    /// Stage 6: Obstacles move over `[t, t + h]`: scripted ones by their motion, driven ones to
    /// fraction `s1` of their frame targets.
    fn move_obstacles(&mut self, t: f64, h: f64, s1: f64) {
        let Some(stage) = self.collision.as_mut() else {
            return;
        };
        stage.advance_obstacles(t, t + h);
        for (idx, target) in self.obstacle_targets.iter().enumerate() {
            if let Some((a, b)) = target {
                stage.set_obstacle_pose(idx, a.lerp(b, s1));
            }
        }
    }

    /// Stage 7: Coupling out: the solver's impulses on held vertices become the stage's feedback
    /// (and in-solve friction's next limits); see [`super::coupling`].
    fn coupling_out(&mut self, t: f64, h: f64) {
        let solves_friction = self.model.caps.solves_friction;
        let impulses = self.work.report.impulses();
        let (v0, scratch) = (&self.work.v_save, &mut self.work.scratch_f);
        let (cloth, effects) = (&self.cloth, &self.model.effects);
        self.coupling.feedback_out(
            cloth,
            effects,
            v0,
            (t, h),
            solves_friction,
            impulses,
            scratch,
        );
    }

    /// Stage 8: Collisions fix the end state (kinematic vertices have infinite mass), with the
    /// solver's feedback; the report goes to the metrics and the energy change to the guard.
    fn collide(&mut self, h: f64, m: &mut StepMetrics) {
        let Some(stage) = self.collision.as_mut() else {
            return;
        };
        let inv_mass = &mut self.work.inv_mass;
        self.cloth.inverse_masses_into(inv_mass);
        let (x, v) = (&mut self.cloth.x, &mut self.cloth.v);
        let feedback = &self.coupling.feedback;
        let r = stage.resolve(&self.work.x_save, x, v, inv_mass, h, feedback);
        m.add_collision(&r);
        self.guard
            .collided(Energies::of(&self.cloth, &self.model.effects));
    }

    /// Stage 5, after the guard's check: edges the solve left longer than their material's
    /// strain limit are shortened (see [`super::limit`]). Nothing when no material sets a limit.
    fn limit_strain(&mut self, h: f64, m: &mut StepMetrics) {
        let Some(limit) = self.model.limit.as_mut() else {
            return;
        };
        let w = &mut self.work.inv_mass;
        self.cloth.inverse_masses_into(w);
        let c = &mut self.cloth;
        let r = limit.apply(&mut c.x, &mut c.v, w, &c.kinematic, h);
        m.add_limit(&r);
    }

    /// Whether the guard's strain check applies to this cloth (one with a collision stage; see
    /// [`super::strain`]).
    fn guard_strain(&mut self) -> bool {
        !self.guard.fast_off
            && self.collision.is_some()
            && (self.guard)
                .strain_model(&self.cloth, &self.model.effects)
                .applies()
    }

    /// Before the collision pass, for a rejection after it: the stage's part of the start state
    /// and the solved positions.
    fn save_stage(&mut self) {
        if let Some(stage) = &self.collision {
            stage.save_into(&mut self.guard.stage_save);
        }
        self.guard.x_solved.clone_from(&self.cloth.x);
    }

    /// Stage 9: the guard's strain check of the state the substep ends in: an edge the collision
    /// pass stretched beyond the bound of the material and the fastest impact of the run so far
    /// (this substep's: the fastest start speed of the cloth plus `obstacle_speed`), from within
    /// it after the solve (see [`super::strain`]). An edge the solve itself left beyond the bound
    /// is the scene's doing (a kinematic link dragging pinned cloth stretches it without limit)
    /// and the energy check's business; so is cloth the scene started inside an obstacle, until
    /// it is out.
    fn check_strain(&mut self, obstacle_speed: f64) -> Result<(), (usize, Symptom)> {
        let v_cloth = (self.work.v_save.iter())
            .map(|v| v.length_squared())
            .fold(0.0, f64::max)
            .sqrt();
        let speed = self.guard.book().peak_speed.max(v_cloth + obstacle_speed);
        self.guard.set_peak_speed(speed);
        let Some(stage) = self.collision.as_ref() else {
            return Ok(());
        };
        let x_start = &self.work.x_save;
        if *(self.guard.inside).get_or_insert_with(|| !stage.overlaps(x_start).is_empty()) {
            if !stage.overlaps(&self.cloth.x).is_empty() {
                return Ok(());
            }
            self.guard.inside = Some(false);
        }
        let Some(strain) = self.guard.strain.as_ref() else {
            return Ok(());
        };
        let bound = strain.bound(speed);
        let solved = &self.guard.x_solved;
        // Only edges an obstacle's pass moved an end of: halving bounds how far an obstacle
        // moves per substep, not how far self-contact pushes a layer squeezed against kinematic
        // cloth (at most its contact distance). robot_cape's former torso and shoulder
        // attachments: self-contact pushed an edge the solve left at 1.32 to 1.35 (bound 1.34),
        // eight levels of halving could not undo it, and the solve answered the same stretch over
        // ever shorter substeps with speeds growing as 1 / h (0.15 to 5.4 m/s in one 0.5 ms
        // substep, 16 m/s by t = 1.8 s; 1.6 m/s without the halving).
        let by_obstacle = |i: usize| stage.contact_kind(i, false).is_some();
        let judged = |a: usize, b: usize| by_obstacle(a) || by_obstacle(b);
        let Some(worst) = strain.grown_beyond(solved, &self.cloth.x, bound, judged) else {
            return Ok(());
        };
        let (a, b) = worst.vertices;
        let moved = |i: usize| solved[i] != self.cloth.x[i];
        let contact = (stage.contact_kind(a, moved(a))).or_else(|| stage.contact_kind(b, moved(b)));
        let other = match self.cloth.piece_of(b) {
            Some(p) => b - p.first_vertex,
            None => b,
        };
        Err((
            a,
            Symptom::Stretch {
                other,
                ratio: worst.ratio,
                bound,
                contact,
            },
        ))
    }

    /// A substep rejected after its collision pass: the cloth, the guard's bookkeeping (`book`,
    /// as the substep started) and the stage's poses and contacts go back to its start.
    fn roll_back_collided(&mut self, book: Book) {
        std::mem::swap(&mut self.cloth.x, &mut self.work.x_save);
        std::mem::swap(&mut self.cloth.v, &mut self.work.v_save);
        self.guard.set_book(book);
        if let Some(stage) = self.collision.as_mut() {
            stage.restore(&self.guard.stage_save);
        }
    }
}
