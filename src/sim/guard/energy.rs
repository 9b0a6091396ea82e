//! The guard's energy check: non-finite values, impossible speeds and runaway energy in the
//! solved state, with the bookkeeping it needs across substeps.
//!
//! Runaway energy: over one substep the total energy may grow by the work of wind and driven
//! vertices, plus `energy_growth` times the recent peak dynamic energy, plus the first-order
//! error an explicit step makes under gravity (`h sum m |g| |v|`). An instability multiplies the
//! dynamic energy every step and trips this within a few steps; a stable step never comes
//! close. Over the run, the total energy may not exceed the budget: the initial energy plus all
//! the work done on the cloth from outside (wind, driven vertices, moving obstacles, released
//! vertices) and the allowances spent.

use super::settings::GuardSettings;
use crate::cloth::Cloth;
use crate::effects::{EffectSet, State};
use crate::sim::energy::Energies;
use crate::sim::error::Symptom;
use crate::sim::scan::scan_vertices;
use crate::Vec3;

/// What the guard looks at after a solve: the end state (in the cloth) and the start state it
/// may roll back to.
pub(in crate::sim) struct Sample<'a> {
    pub cloth: &'a Cloth,
    pub effects: &'a EffectSet,
    pub x0: &'a [Vec3],
    pub v0: &'a [Vec3],
}

/// A substep the guard accepted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::sim) struct Accepted {
    /// Energies of the end state.
    pub energies: Energies,
    /// Allowance spent: external work, gravity error bound and the rounding floor (J).
    pub spent: f64,
    /// Largest squared vertex speed of the end state.
    pub speed2: f64,
}

/// The energy bookkeeping (copied before a substep, put back when it is rejected after it was
/// booked).
#[derive(Debug, Clone, Copy, Default)]
pub(in crate::sim) struct Book {
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

impl Book {
    /// A new phase (another cloth): the bookkeeping starts over (the run's peak speed stays).
    pub fn restart(&mut self) {
        self.energy_cache = None;
        self.recent_energy = [0.0; 16];
        self.energy_budget = None;
        self.budget_scale = 0.0;
    }

    /// The cloth changed outside a step (vertices attached or released): its energy is unknown.
    pub fn forget_energy(&mut self) {
        self.energy_cache = None;
    }

    /// The energy of the current state, if known.
    pub fn energy(&self) -> Option<Energies> {
        self.energy_cache
    }

    /// The largest squared speed of the current state, if the guard's scan measured it.
    pub fn scanned_speed2(&self) -> Option<f64> {
        self.scanned_speed2
    }

    /// A new frame step begins.
    pub fn start_frame(&mut self) {
        self.scanned_speed2 = None;
    }

    /// Energies at the start of a substep (the cached ones when known).
    pub fn start_energies(&self, cloth: &Cloth, effects: &EffectSet) -> Energies {
        match self.energy_cache {
            Some(e) => e,
            None => Energies::of(cloth, effects),
        }
    }

    /// Kinetic energy `gained` (J) was given to the cloth from outside (released vertices).
    pub fn widen(&mut self, gained: f64) {
        if let Some(b) = self.energy_budget.as_mut() {
            *b += gained;
        }
        self.budget_scale += gained;
        self.energy_cache = None;
    }

    /// Books an accepted substep that started at `e0`.
    pub fn accept(&mut self, e0: Energies, a: Accepted) {
        let (e0_total, e0_dynamic) = (e0.total(), e0.dynamic());
        self.scanned_speed2 = Some(a.speed2);
        if self.energy_budget.is_none() {
            self.budget_scale = e0_dynamic;
        }
        self.energy_budget = Some(self.energy_budget.unwrap_or(e0_total) + a.spent);
        self.budget_scale += a.spent;
        self.energy_cache = Some(a.energies);
        self.recent_energy[self.substep_count % 16] = a.energies.dynamic();
        self.substep_count += 1;
    }

    /// The substep was rolled back to its start state of energy `e0`.
    pub fn reject(&mut self, e0: Energies) {
        self.energy_cache = Some(e0);
    }

    /// The collision stage changed the state to energy `after`: a moving obstacle can push
    /// energy into the cloth, so the budget widens by any gain.
    pub fn collided(&mut self, after: Energies) {
        if let (Some(b), Some(budget)) = (self.energy_cache, self.energy_budget.as_mut()) {
            *budget += (after.total() - b.total()).max(0.0);
        }
        self.energy_cache = Some(after);
        self.scanned_speed2 = None;
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
    /// that grows monotonically along the path, where the trapezoid rule is not). Wind forces stay start-of-substep. Only for unconditionally stable
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
