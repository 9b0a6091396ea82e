//! The divergence guard: every substep checks the integrator's output for non-finite values,
//! runaway energy and impossible speeds, and names the likely culprit when it fails. It owns
//! its bookkeeping across substeps (the energy budget, the recent energy levels, the energy of
//! the current state) and the checks themselves.
//!
//! Runaway energy: over one substep the total energy may grow by the work of wind and driven
//! vertices, plus `energy_growth` times the recent peak dynamic energy, plus the first-order
//! error an explicit step makes under gravity (`h sum m |g| |v|`). An instability multiplies the
//! dynamic energy every step and trips this within a few steps; a stable step never comes
//! close. Over the run, the total energy may not exceed the budget: the initial energy plus all
//! the work done on the cloth from outside (wind, driven vertices, moving obstacles, released
//! vertices) and the allowances spent.

use super::energy::Energies;
use super::error::{Cause, DivergenceError, Symptom};
use super::scan::scan_vertices;
use super::strain::StrainModel;
use crate::cloth::Cloth;
use crate::collide::StageRollback;
use crate::effects::{EffectSet, State};
use crate::Vec3;
use serde::{Deserialize, Serialize};
use std::fmt;

/// What to do when a substep diverges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DivergencePolicy {
    /// Redo the substep as two half steps (recursively, up to `max_subdivisions` levels) and report it.
    Subdivide,
    /// Stop with a [`DivergenceError`].
    Stop,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GuardSettings {
    pub policy: DivergencePolicy,
    /// Levels of halving before giving up (2^levels substeps at most per substep).
    pub max_subdivisions: u32,
    /// Levels of halving fast contact may use (at most `max_subdivisions`; none: all of them).
    /// A link that outruns the cloth splits the substep until it moves a third of a spacing
    /// per piece: a 15 cm jump of drape_bot's arm at 64x64 took 77 splits and 1.4 s of one
    /// frame. A live node bounds that cost here; the substeps that would have split further
    /// are counted (`StepMetrics::contact_splits_refused`) and reported on `/diagnostics`.
    pub max_contact_split_levels: Option<u32>,
    /// Fastest plausible vertex speed (m/s); anything faster is treated as a blow-up.
    pub max_speed: f64,
    /// Allowed growth of kinetic + elastic energy in one substep beyond the work of gravity, wind
    /// and moving attachments, relative to the energy at the start of the substep.
    pub energy_growth: f64,
}

impl Default for GuardSettings {
    fn default() -> Self {
        Self {
            policy: DivergencePolicy::Subdivide,
            max_subdivisions: 8,
            max_contact_split_levels: None,
            max_speed: 500.0,
            energy_growth: 0.5,
        }
    }
}

impl fmt::Display for DivergencePolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DivergencePolicy::Subdivide => "subdivide",
            DivergencePolicy::Stop => "stop",
        })
    }
}

/// What the guard looks at after a solve: the end state (in the cloth) and the start state it
/// may roll back to.
pub(super) struct Sample<'a> {
    pub cloth: &'a Cloth,
    pub effects: &'a EffectSet,
    pub x0: &'a [Vec3],
    pub v0: &'a [Vec3],
}

/// A substep the guard accepted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Accepted {
    /// Energies of the end state.
    pub energies: Energies,
    /// Allowance spent: external work, gravity error bound and the rounding floor (J).
    pub spent: f64,
    /// Largest squared vertex speed of the end state.
    pub speed2: f64,
}

/// The guard's bookkeeping across substeps, and what a rollback after the collision pass needs.
#[derive(Debug, Default)]
pub(super) struct Guard {
    book: Book,
    /// The strain check of the current cloth (`None` until set up).
    pub strain: Option<StrainModel>,
    /// The collision stage's part of the substep's start state, when the strain check may reject
    /// the substep after the collision pass.
    pub stage_save: StageRollback,
    /// The solved positions before the collision pass (to tell whether the solve or the response
    /// stretched an edge).
    pub x_solved: Vec<Vec3>,
    /// Whether cloth was inside an obstacle when the strain check was set up and still is (`None`
    /// until known): pushing it out stretches the cloth as far as the scene put it in, so the
    /// check waits until it is out (the scene build reported it).
    pub inside: Option<bool>,
    /// Fast-contact splitting and the strain check switched off (for the cost comparison of
    /// `benches/fast_links.rs`).
    pub fast_off: bool,
}

/// The energy bookkeeping (copied before a substep, put back when it is rejected after it was
/// booked).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Book {
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
    /// The fastest impact speed of the run so far (m/s): the fastest cloth vertex plus the
    /// fastest obstacle point of any substep. Strain a fast impact left can stay after it
    /// (friction and contact hold it), so the strain bound uses the run's peak.
    pub peak_speed: f64,
}

impl Guard {
    /// A new phase (another cloth): the energy bookkeeping starts over, the strain check is set
    /// up again.
    pub fn restart(&mut self) {
        self.book.energy_cache = None;
        self.book.recent_energy = [0.0; 16];
        self.book.energy_budget = None;
        self.book.budget_scale = 0.0;
        self.strain = None;
        self.inside = None;
    }

    /// The energy bookkeeping as it is now.
    pub fn book(&self) -> Book {
        self.book
    }

    /// Puts back the bookkeeping of a substep's start (the substep was rejected after booking).
    pub fn set_book(&mut self, b: Book) {
        self.book = b;
    }

    /// The run's fastest impact speed is now `v` (m/s).
    pub fn set_peak_speed(&mut self, v: f64) {
        self.book.peak_speed = v;
    }

    /// The strain check for `cloth`, set up on first use and again when the cloth changed.
    pub fn strain_model(&mut self, cloth: &Cloth, effects: &EffectSet) -> &StrainModel {
        if !self.strain.as_ref().is_some_and(|s| s.fits(cloth)) {
            self.strain = Some(StrainModel::of(cloth, effects));
        }
        self.strain
            .get_or_insert_with(|| StrainModel::of(cloth, effects))
    }

    /// The cloth changed outside a step (vertices attached or released): its energy is unknown.
    pub fn forget_energy(&mut self) {
        self.book.energy_cache = None;
    }

    /// The energy of the current state, if known.
    pub fn energy(&self) -> Option<Energies> {
        self.book.energy_cache
    }

    /// The largest squared speed of the current state, if the guard's scan measured it.
    pub fn scanned_speed2(&self) -> Option<f64> {
        self.book.scanned_speed2
    }

    /// A new frame step begins.
    pub fn start_frame(&mut self) {
        self.book.scanned_speed2 = None;
    }

    /// Energies at the start of a substep (the cached ones when known).
    pub fn start_energies(&self, cloth: &Cloth, effects: &EffectSet) -> Energies {
        match self.book.energy_cache {
            Some(e) => e,
            None => Energies::of(cloth, effects),
        }
    }

    /// Kinetic energy `gained` (J) was given to the cloth from outside (released vertices).
    pub fn widen(&mut self, gained: f64) {
        if let Some(b) = self.book.energy_budget.as_mut() {
            *b += gained;
        }
        self.book.budget_scale += gained;
        self.book.energy_cache = None;
    }

    /// Books an accepted substep that started at `e0`.
    pub fn accept(&mut self, e0: Energies, a: Accepted) {
        let (e0_total, e0_dynamic) = (e0.total(), e0.dynamic());
        self.book.scanned_speed2 = Some(a.speed2);
        if self.book.energy_budget.is_none() {
            self.book.budget_scale = e0_dynamic;
        }
        self.book.energy_budget = Some(self.book.energy_budget.unwrap_or(e0_total) + a.spent);
        self.book.budget_scale += a.spent;
        self.book.energy_cache = Some(a.energies);
        self.book.recent_energy[self.book.substep_count % 16] = a.energies.dynamic();
        self.book.substep_count += 1;
    }

    /// The substep was rolled back to its start state of energy `e0`.
    pub fn reject(&mut self, e0: Energies) {
        self.book.energy_cache = Some(e0);
    }

    /// The collision stage changed the state to energy `after`: a moving obstacle can push
    /// energy into the cloth, so the budget widens by any gain.
    pub fn collided(&mut self, after: Energies) {
        if let (Some(b), Some(budget)) = (self.book.energy_cache, self.book.energy_budget.as_mut())
        {
            *budget += (after.total() - b.total()).max(0.0);
        }
        self.book.energy_cache = Some(after);
        self.book.scanned_speed2 = None;
    }

    /// Checks the integrator's output; returns the new energies or the first bad vertex.
    /// `fext`: the forces from outside the cloth whose work over the substep is allowed (see
    /// [`external_forces`]).
    pub fn check(
        &self,
        g: &GuardSettings,
        s: &Sample,
        h: f64,
        e0: Energies,
        fext: Option<&[Vec3]>,
    ) -> Result<Accepted, (usize, Symptom)> {
        let c = s.cloth;
        // One pass over the vertices: finiteness, the fastest speed, the kinetic energy, the
        // speed sum of the gravity error bound and the total mass.
        // The energy pass at the new state (whose position-only forces serve the next substep)
        // runs on two threads for large cloths; each also scans its half of the vertices.
        let v_save = s.v0;
        let ((elastic, gravity_energy), scan, second) =
            s.effects
                .energy_split_with(&c.x, |r: std::ops::Range<usize>| {
                    let (x, v, v0, m) = (
                        &c.x[r.clone()],
                        &c.v[r.clone()],
                        &v_save[r.clone()],
                        &c.mass[r],
                    );
                    scan_vertices(x, v, v0, m)
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
            Some(f) => (0..c.len()).map(|i| f[i].dot(c.x[i] - s.x0[i]).abs()).sum(),
            None => 0.0,
        };
        let gravity = s.effects.gravity().length();
        let gravity_error = h * gravity * mass_speed;
        let floor = 1e-12 * (1.0 + scan.mass);
        let reference = self
            .book
            .recent_energy
            .iter()
            .fold(e0_dynamic, |a, &b| a.max(b));
        let allowed = work + g.energy_growth * reference + gravity_error + floor;
        let gained = e1_total - e0_total;
        if gained > allowed {
            return Err((fastest(), Symptom::EnergyGain { gained, allowed }));
        }
        let spent = work + gravity_error + floor;
        let budget = self.book.energy_budget.unwrap_or(e0_total) + spent;
        let scale = if self.book.energy_budget.is_some() {
            self.book.budget_scale
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
        Ok(Accepted {
            energies: e1,
            spent,
            speed2: scan.speed2,
        })
    }

    /// The guard's second opinion on a substep rejected for energy gain while attachments move:
    /// the start-of-substep force underestimates the work of a driven vertex that stretches the
    /// cloth within the substep (a robot link jumping to a new joint state), so each driven
    /// vertex's work is bounded with the larger of its start and end forces (a bound for a force
    /// that grows monotonically along the path; the trapezoid rule still fell ~20% short on the
    /// robot towel). Wind forces stay start-of-substep. Only for unconditionally stable
    /// integrators: there a large end force is the input's doing, while in an explicit blow-up
    /// it would be the instability's and must not widen the allowance. `scratch` holds the end
    /// forces.
    #[allow(clippy::too_many_arguments)]
    pub fn check_with_end_forces(
        &self,
        g: &GuardSettings,
        s: &Sample,
        t1: f64,
        h: f64,
        e0: Energies,
        fext: &[Vec3],
        scratch: &mut Vec<Vec3>,
    ) -> Result<Accepted, (usize, Symptom)> {
        let c = s.cloth;
        let n = c.len();
        crate::linalg::scratch(scratch, n);
        let st = State {
            t: t1,
            x: &c.x,
            v: &c.v,
        };
        s.effects.forces(&st, scratch);
        let mut f = fext.to_vec();
        for (i, _) in &c.kinematic {
            let i = *i as usize;
            let dx = c.x[i] - s.x0[i];
            let end = -scratch[i];
            if end.dot(dx).abs() > f[i].dot(dx).abs() {
                f[i] = end;
            }
        }
        self.check(g, s, h, e0, Some(&f))
    }
}

/// Work done on the cloth during the substep by forces from outside it (wind and moving
/// attachments), evaluated at the start state `(t, cloth.x, cloth.v)`, per unit displacement:
/// writes the forces to `fext` and returns whether there are any (`scratch`: internal forces).
pub(super) fn external_forces(
    cloth: &Cloth,
    effects: &EffectSet,
    t: f64,
    fext: &mut Vec<Vec3>,
    scratch: &mut Vec<Vec3>,
) -> bool {
    let has_wind = effects.iter().any(|e| e.injects_energy());
    let moving_attachments = cloth
        .kinematic
        .iter()
        .any(|(i, _)| cloth.v[*i as usize] != Vec3::ZERO);
    if !has_wind && !moving_attachments {
        return false;
    }
    let s = State {
        t,
        x: &cloth.x,
        v: &cloth.v,
    };
    let n = cloth.len();
    crate::linalg::scratch(fext, n);
    effects.injecting_forces(&s, fext);
    if moving_attachments {
        // Power a driven vertex puts into the cloth: minus the internal force on it times its
        // velocity (gravity on the driven vertex itself does no work on the cloth).
        crate::linalg::scratch(scratch, n);
        effects.forces(&s, scratch);
        for (i, _) in &cloth.kinematic {
            let i = *i as usize;
            fext[i] = -scratch[i];
        }
    }
    true
}

/// Whether a substep of `h` exceeds the integrator's stability limit `h omega <= limit` for the
/// bound `omega` (`omega^2 <=` the sum over elastic effects of their Gershgorin bounds), and the
/// guard's policy allows halving it. Integrators without a limit (implicit) or with none at all
/// (forward Euler, limit 0) are left to the reactive guard.
pub(super) fn over_stability_limit(
    g: &GuardSettings,
    limit: Option<f64>,
    h: f64,
    depth: u32,
    omega: impl FnOnce() -> f64,
) -> bool {
    if g.policy != DivergencePolicy::Subdivide || depth >= g.max_subdivisions {
        return false;
    }
    let Some(limit) = limit.filter(|l| *l > 0.0) else {
        return false;
    };
    h * omega() > limit
}

/// The error for a substep of `h` at `t` that failed at `vertex` (flat index) with `symptom`.
/// An effect is blamed only when the step is over the integrator's stability bound
/// `h omega > limit` (`omega_bound` the bound on the cloth's highest angular frequency): the
/// one contributing the largest `omega^2`.
/// Otherwise (within the bound, or an integrator without one) the error reports what the guard
/// measured and suggests no step size.
#[allow(clippy::too_many_arguments)]
pub(super) fn divergence_error(
    cloth: &Cloth,
    effects: &EffectSet,
    integrator: &'static str,
    stability_limit: Option<f64>,
    omega_bound: f64,
    (t, h): (f64, f64),
    vertex: usize,
    symptom: Symptom,
) -> DivergenceError {
    let (name, local) = match cloth.piece_of(vertex) {
        Some(p) => (p.name.clone(), vertex - p.first_vertex),
        None => (String::from("?"), vertex),
    };
    let cause = match stability_limit {
        None => Cause::Unknown,
        Some(limit) if limit <= 0.0 => Cause::NoStableStep,
        Some(limit) => {
            let h_omega = h * omega_bound;
            let stiffest = effects
                .stiffness(&cloth.mass)
                .into_iter()
                .max_by(|a, b| a.omega_sq.total_cmp(&b.omega_sq));
            match stiffest {
                Some(b) if h_omega > limit => Cause::Unstable {
                    parameter: b.parameter,
                    h_omega,
                    limit,
                },
                _ => Cause::Unknown,
            }
        }
    };
    DivergenceError {
        time: t,
        step: h,
        cloth: name,
        vertex: local,
        symptom,
        integrator,
        cause,
    }
}
