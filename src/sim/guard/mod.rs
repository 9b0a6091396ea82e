//! The divergence guard: every substep's checks and every decision to redo one.
//!
//! The guard answers each check with a [`Verdict`]: go on, split the substep in two (and why),
//! or stop the run. It decides, in the order the step asks:
//! - before the solve ([`Guard::split_up_front`]): an explicit step over its stability limit,
//!   and a moving obstacle that would outrun the cloth near it ([`contact`], with the pure
//!   geometry in [`super::fast`]), are split before trying;
//! - after the solve ([`Guard::check_solve`]): non-finite values, impossible speeds and runaway
//!   energy ([`energy`]) roll the substep back, then split it or stop per policy;
//! - after the collision pass ([`Guard::check_response`]): an edge the response stretched beyond
//!   what the material and the speeds allow ([`super::strain`]), and a vertex the response
//!   moved more than fast contact allows, roll the whole substep back (stage included) and
//!   split it.
//!
//! Rollbacks cost no copy before the solve: the start state's buffers are swapped out of the
//! cloth and the integrator writes the end state out of place. What a rollback after the
//! collision pass needs (the stage's part, the solved positions, the energy bookkeeping) is
//! saved into [`Saved`] only where the strain check applies.

mod contact;
mod energy;
mod outside;
mod settings;
mod verdict;

pub(super) use energy::{Book, Sample};
pub(super) use outside::{moving_contact_work, OutsideForces};
pub use settings::{DivergencePolicy, GuardSettings};
use verdict::rejected;
pub(super) use verdict::{Failure, Redo, Verdict, Why};

use super::error::Symptom;
use super::metrics::StepMetrics;
use super::span::Span;
use super::strain::StrainModel;
use crate::cloth::Cloth;
use crate::collide::{CollisionStage, StageRollback};
use crate::effects::EffectSet;
use crate::Vec3;

/// Whether cloth the scene started inside an obstacle is still on its way out: pushing it out
/// stretches the cloth as far as the scene put it in, so the checks after the collision pass
/// wait until it is out (the scene build reported it).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
enum Inside {
    /// Not looked at yet.
    #[default]
    Unknown,
    /// Some cloth is inside an obstacle.
    Leaving,
    /// None is, and the checks apply from now on.
    Out,
}

/// What a rollback after the collision pass needs, saved before the pass (kept in the step's
/// `Work`, overwritten by every substep the strain check applies to).
#[derive(Debug, Default)]
pub(super) struct Saved {
    /// The energy bookkeeping as the substep started.
    book: Book,
    /// The collision stage's part of the substep's start state.
    stage: StageRollback,
    /// The solved positions before the collision pass (to tell whether the solve or the response
    /// stretched an edge, and how far the response moved a vertex).
    x_solved: Vec<Vec3>,
}

/// The guard's state across substeps: its energy bookkeeping, its strain check of the cloth
/// and what it learned of the substep under way.
#[derive(Debug, Default)]
pub(super) struct Guard {
    book: Book,
    /// The strain check of the current cloth (`None` until set up).
    strain: Option<StrainModel>,
    inside: Inside,
    /// The fastest obstacle point of the substep under way (m/s), for the strain bound.
    obstacle_speed: f64,
    /// Whether the substep under way is checked after its collision pass.
    watching: bool,
    /// Cloth-cloth pairs the last collision pass left unresolved.
    unresolved: usize,
    /// The last kept substep ended tangled: halving cannot undo a tangle the substep starts in,
    /// so only a new one is redone in halves.
    tangled: bool,
    /// Fast-contact splitting and the strain check switched off (for the cost comparison of
    /// `benches/fast_links.rs`).
    contact_checks_off: bool,
}

impl Guard {
    /// Switches fast-contact splitting and the checks after the collision pass off or back on.
    pub fn set_contact_checks(&mut self, on: bool) {
        self.contact_checks_off = !on;
    }

    /// A new phase (another cloth): the energy bookkeeping starts over, the strain check is set
    /// up again.
    pub fn restart(&mut self) {
        self.book.restart();
        self.strain = None;
        self.inside = Inside::Unknown;
    }

    /// The cloth changed outside a step (vertices attached or released): its energy is unknown.
    pub fn forget_energy(&mut self) {
        self.book.forget_energy();
    }

    /// Kinetic energy `gained` (J) was given to the cloth from outside (released vertices).
    pub fn widen(&mut self, gained: f64) {
        self.book.widen(gained);
    }

    /// A new frame step begins.
    pub fn start_frame(&mut self) {
        self.book.start_frame();
    }

    /// The energy of the current state, if known.
    pub fn energy(&self) -> Option<super::energy::Energies> {
        self.book.energy()
    }

    /// The largest squared speed of the current state, if the guard's scan measured it.
    pub fn scanned_speed2(&self) -> Option<f64> {
        self.book.scanned_speed2()
    }

    /// The strain check for `cloth`, set up on first use and again when the cloth changed.
    fn strain_model(&mut self, cloth: &Cloth, effects: &EffectSet) -> &StrainModel {
        if !self.strain.as_ref().is_some_and(|s| s.fits(cloth)) {
            self.strain = Some(StrainModel::of(cloth, effects));
        }
        self.strain
            .get_or_insert_with(|| StrainModel::of(cloth, effects))
    }

    /// Stage 0: splits the substep before trying when it is over the integrator's stability
    /// limit `h omega <= limit` (`omega`: the bound on the cloth's highest angular frequency;
    /// integrators without a limit, or stable for no step, are left to the checks after the
    /// solve), or when a moving obstacle would outrun the cloth near it (see [`contact`]).
    #[allow(clippy::too_many_arguments)]
    pub fn split_up_front(
        &mut self,
        g: &GuardSettings,
        span: Span,
        stability: Option<(f64, f64)>,
        stage: Option<&CollisionStage>,
        targets: &[Option<(crate::Pose, crate::Pose)>],
        (cloth, effects): (&Cloth, &EffectSet),
        near: &mut Vec<(usize, f64, f64)>,
        m: &mut StepMetrics,
    ) -> Verdict {
        let subdivides = g.policy == DivergencePolicy::Subdivide && span.depth < g.max_subdivisions;
        if let Some((limit, omega)) = stability.filter(|_| subdivides) {
            if limit > 0.0 && span.h * omega > limit {
                return Err(Redo::Split(Why::Stability));
            }
        }
        self.obstacle_speed = 0.0;
        match stage.filter(|_| !self.contact_checks_off) {
            Some(stage) => self.fast_contact(g, span, stage, targets, (cloth, effects), near, m),
            None => Ok(()),
        }
    }

    /// The collision pass changed the state to energy `after`: a moving obstacle can push
    /// energy into the cloth, so the budget widens by any gain.
    /// After the collision pass: its energies, and whether the self-contact fail-safe gave up
    /// on any pair (`unresolved`).
    pub fn collided(&mut self, after: super::energy::Energies, unresolved: usize) {
        self.book.collided(after);
        self.unresolved = unresolved;
    }

    /// Stage 3, before the solve: books the substep's start and returns its energies (the
    /// cached ones when known); the forces from outside the cloth at the start state go to
    /// `outside` (see [`outside::external_forces`]). `scratch`: internal forces.
    pub fn start(
        &mut self,
        saved: &mut Saved,
        (cloth, effects): (&Cloth, &EffectSet),
        t: f64,
        outside: &mut OutsideForces,
        scratch: &mut Vec<Vec3>,
    ) -> super::energy::Energies {
        saved.book = self.book;
        let e0 = self.book.start_energies(cloth, effects);
        outside::external_forces(cloth, effects, t, outside, scratch);
        e0
    }

    /// Stage 5: the verdict on the solved substep started at energies `e0` (see [`energy`]);
    /// an accepted one is booked, a rejected one rolled back to its start (`x0`, `v0`, swapped
    /// back into the cloth).
    #[allow(clippy::too_many_arguments)]
    pub fn check_solve(
        &mut self,
        g: &GuardSettings,
        span: Span,
        (cloth, effects): (&mut Cloth, &EffectSet),
        (x0, v0): (&mut Vec<Vec3>, &mut Vec<Vec3>),
        e0: super::energy::Energies,
        has_stability_limit: bool,
        outside: &OutsideForces,
        scratch: &mut Vec<Vec3>,
    ) -> Verdict {
        let s = Sample {
            cloth,
            effects,
            x0,
            v0,
        };
        let mut verdict = self.book.check(g, &s, span.h, e0, outside.forces());
        if let Some(f) = outside.forces() {
            if !has_stability_limit && matches!(verdict, Err((_, Symptom::EnergyGain { .. }))) {
                let t1 = span.t + span.h;
                verdict = (self.book).check_with_end_forces(g, &s, t1, span.h, e0, f, scratch);
            }
        }
        match verdict {
            Ok(accepted) => {
                self.book.accept(e0, accepted);
                Ok(())
            }
            Err((vertex, symptom)) => {
                std::mem::swap(&mut cloth.x, x0);
                std::mem::swap(&mut cloth.v, v0);
                self.book.reject(e0);
                Err(rejected(g, span, Failure { vertex, symptom }))
            }
        }
    }

    /// Stage 6, before the collision pass: whether the checks after it apply to this substep
    /// (a cloth with a collision stage whose strain bound applies; see [`super::strain`]), and
    /// if so, what a rollback after the pass needs is saved.
    pub fn watch_response(
        &mut self,
        stage: Option<&CollisionStage>,
        (cloth, effects): (&Cloth, &EffectSet),
        saved: &mut Saved,
    ) {
        self.watching = !self.contact_checks_off
            && stage.is_some()
            && self.strain_model(cloth, effects).applies();
        if let Some(stage) = stage.filter(|_| self.watching) {
            stage.save_into(&mut saved.stage);
            saved.x_solved.clone_from(&cloth.x);
        }
    }

    /// Stage 9: the verdict on the state the substep ends in, where [`Guard::watch_response`]
    /// watched it: an edge the collision response stretched beyond the strain bound rejects the
    /// substep (at the guard's deepest level, with the subdivide policy, the response cannot do
    /// better and the state is kept: its stretch is on `/diagnostics`); a vertex the response
    /// moved more than fast contact allows splits it, and so do cloth-cloth pairs the
    /// self-contact fail-safe gave up on in a substep that started untangled, while the guard
    /// may split. Each rolls the whole
    /// substep back to its start (`x0`, `v0`, the saved stage and bookkeeping).
    #[allow(clippy::too_many_arguments)]
    pub fn check_response(
        &mut self,
        g: &GuardSettings,
        span: Span,
        stage: Option<&mut CollisionStage>,
        cloth: &mut Cloth,
        (x0, v0): (&mut Vec<Vec3>, &mut Vec<Vec3>),
        saved: &Saved,
        m: &mut StepMetrics,
    ) -> Verdict {
        let Some(stage) = stage.filter(|_| self.watching) else {
            self.tangled = self.unresolved > 0;
            return Ok(());
        };
        let mut redo = None;
        if let Err(failure) = self.check_strain(stage, cloth, (x0, v0), &saved.x_solved) {
            if g.policy == DivergencePolicy::Stop || span.depth < g.max_subdivisions {
                redo = Some(rejected(g, span, failure));
            }
        }
        if redo.is_none() && self.response_jumped(stage, cloth, &saved.x_solved) {
            if span.depth < g.split_levels() {
                redo = Some(Redo::Split(Why::ResponseJump));
            } else {
                m.contact_splits_refused += 1;
            }
        }
        // A tangle the fail-safe gave up on is redone in halves while the guard may split; past
        // that it stands, counted in `unresolved_contacts` (a WARN on `/diagnostics`).
        if redo.is_none() && self.unresolved > 0 && !self.tangled && span.depth < g.split_levels() {
            redo = Some(Redo::Split(Why::Tangle));
        }
        let Some(redo) = redo else {
            self.tangled = self.unresolved > 0;
            return Ok(());
        };
        // The rolled-back pass's tangle is not the state the step keeps.
        m.unresolved_contacts -= self.unresolved;
        std::mem::swap(&mut cloth.x, x0);
        std::mem::swap(&mut cloth.v, v0);
        self.book = saved.book;
        stage.restore(&saved.stage);
        Err(redo)
    }
}
