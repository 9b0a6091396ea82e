//! One implicit step as a table of contents: assemble the linearised system, solve it from the
//! last steps' velocity changes, refit friction drags, contact springs and holds (at most
//! `MAX_REFITS` solves to a loose tolerance, then the same at the scene's), then Newton
//! iterations while the step creates energy or stretches springs its linearisation did not see.

use super::newton::{potential, unseen_stretch};
use super::solve::SolveKind;
use super::solver::Implicit;
use crate::effects::State;
use crate::integrate::cg::SolveStats;
use crate::integrate::integrator::{Integrator, StepReport};
use crate::integrate::Dynamics;
use crate::linalg::{scratch, Filter};
use crate::Vec3;
use std::time::Instant;

/// Solves at most with friction drags refitted to the sliding speed (see [`crate::integrate::friction`]).
const MAX_REFITS: u32 = 2;

/// Relative residual to which the solves that decide a step's active sets (friction modes,
/// contact springs, holds) are taken; the answer is then solved to the scene's own tolerance
/// (`cg_tolerance`) from there and gets the same rounds again (at most `MAX_REFITS` more
/// solves), so it ends as settled as when every round was tight, from active sets that mostly
/// settled already. Each change of an active set moves the answer by more than the last
/// decades of a tight solve, which the next round would throw away: a cloth resting on a
/// sphere with friction (S1 64x64, `cargo bench --bench contact`) would be solved to the
/// scene's tolerance three times a step. The rounds after the tight solve stay: with only one,
/// or none, a round decided on a loose answer could be final, and a hem led out of an
/// obstacle (`tests/start_inside.rs`) or the frictionless towel of `tests/fast_robot.rs`
/// stretches past its bound.
const ACTIVE_SET_TOLERANCE: f64 = 1e-2;

/// A step shorter than this share of the scene's substep is a split or subdivided one (halves,
/// quarters, ...; see `Implicit::solve`).
const SHORT_STEP: f64 = 0.75;

/// Newton iterations at most beyond Baraff and Witkin's one linearised solve.
const MAX_NEWTON: u32 = 8;

/// The share of the energy the last Newton iterate created above which an iteration is slow
/// (see `out_of_reach`).
const SLOW_NEWTON: f64 = 0.7;

impl Implicit {
    pub(super) fn step_in_pool(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    ) {
        let n = x.len();
        self.short_step = h < SHORT_STEP * d.nominal_step;
        if self.a.as_ref().is_none_or(|a| a.rows() != n) {
            self.prepare(d.effects, n);
        }
        for buf in [
            &mut self.f0,
            &mut self.b,
            &mut self.dv,
            &mut self.z,
            &mut self.xk,
            &mut self.vk,
        ] {
            scratch(buf, n);
        }
        // The step's own copy of the filter: contacts whose constraint would pull the vertex
        // into the surface are released during the step.
        let mut filter = std::mem::take(&mut self.filter);
        filter.clone_from(&d.constraints.filter);
        self.released.clear();
        self.released.extend(
            (d.constraints.standby.iter().copied())
                .filter(|&(i, _)| i < n && filter[i] == Filter::Free),
        );
        let filt = &mut filter;
        let clock = Instant::now();
        self.assemble(d, &State { t, x, v }, h);
        report.assembly_time_s = clock.elapsed().as_secs_f64();
        self.choose_path();
        report.linear_path = Some(self.path);
        // Constrained components of dv are fixed: z = (I - S)(v_target - v).
        for i in 0..n {
            self.z[i] = filt[i].constrained(d.constraints.target_velocity[i] - v[i]);
        }
        // The start directions: the last two steps' velocity changes.
        self.last.clone_from(&self.dv);
        (report.cg_time_s, report.cg_flops, report.cg_bytes) = (0.0, 0.0, 0.0);
        (report.setup_time_s, report.factorisations, report.analyses) = (0.0, 0, 0);
        // Active sets to settle: their rounds solve to `ACTIVE_SET_TOLERANCE`, then the answer is
        // polished to the scene's tolerance and gets the rounds again (see `ACTIVE_SET_TOLERANCE`).
        let tight = self.settings.cg_tolerance;
        let holds =
            !self.released.is_empty() || filt.iter().any(|f| matches!(f, Filter::Direction(_)));
        let active = holds
            || !self.drags.is_empty()
            || !self.edge_drags.is_empty()
            || !d.constraints.contacts.is_empty();
        let mut tol = if active {
            ACTIVE_SET_TOLERANCE.max(tight)
        } else {
            tight
        };
        let mut stats = self.solve(filt, SolveKind::First, tol);
        tally(report, &stats);
        std::mem::swap(&mut self.older, &mut self.last);
        let mut cg_iterations = stats.iterations;
        let mut impulses_current = false;
        let mut rounds = 0;
        loop {
            let mut changed = false;
            if rounds < MAX_REFITS {
                let state = State { t, x, v };
                let (c, impulses) =
                    self.refit_active_sets(filt, d, &state, h, (holds, tol <= tight));
                (changed, impulses_current) = (c, impulses_current || impulses);
            }
            if changed {
                rounds += 1;
            } else if tol > tight {
                // The polish, then the rounds again on its answer.
                (tol, rounds) = (tight, 0);
            } else {
                break;
            }
            stats = self.solve(filt, SolveKind::Round, tol);
            tally(report, &stats);
            cg_iterations += stats.iterations;
            impulses_current = false;
        }
        if !impulses_current {
            self.linear_impulses(filt);
        }

        // Newton iterations on the nonlinear backward-Euler system, only while the step creates
        // energy (see `EnergyCheck`) or a spring stretches beyond what the linearisation it was
        // solved on predicts (`unseen_stretch`), and while they converge fast enough to end
        // within the cap (`out_of_reach`).
        // The potential at `x` is known when `x` is exactly where the last step ended (nothing
        // moved it since: no collision response, no kinematic reset off it).
        let u0 = match self.end_potential {
            Some(u) if self.xk.as_slice() == &x[..] => u,
            _ => potential(d, x),
        };
        self.end_potential = None;
        let mut newton = 0;
        let mut best: Option<f64> = None;
        // The energy the last three iterates created, oldest first.
        let mut history = [f64::NAN; 3];
        loop {
            for i in 0..n {
                self.vk[i] = v[i] + self.dv[i];
                self.xk[i] = x[i] + self.vk[i] * h;
            }
            let check = self.energy_check(d, t + h, h, v, u0);
            let lin: &[Vec3] = if newton == 0 { x } else { &self.x_lin };
            let unseen = unseen_stretch(d, lin, &self.xk);
            // A non-finite iterate is the divergence guard's case, not Newton's.
            if (check.accepted() && unseen <= self.settings.linearisation_tolerance)
                || !check.created.is_finite()
            {
                self.end_potential = check.accepted().then_some(check.u1);
                break;
            }
            // Keep the iterate that created the least energy in case none is accepted.
            if best.is_none_or(|b| check.created < b) {
                best = Some(check.created);
                self.best.clone_from(&self.dv);
            }
            history = [history[1], history[2], check.created];
            let stalled = newton > 1
                && unseen <= self.settings.linearisation_tolerance
                && out_of_reach(history, check.allowed, MAX_NEWTON - newton);
            if newton == MAX_NEWTON || stalled {
                log::debug!(
                    "implicit step still creates energy or stretches springs unseen after \
                     {newton} Newton iterations ({check:?}, unseen stretch {unseen:.3}); keeping \
                     the best iterate"
                );
                std::mem::swap(&mut self.dv, &mut self.best);
                break;
            }
            newton += 1;
            let (xk, vk) = (std::mem::take(&mut self.xk), std::mem::take(&mut self.vk));
            let clock = Instant::now();
            self.assemble_matrix(
                d,
                &State {
                    t: t + h,
                    x: &xk,
                    v: &vk,
                },
                h,
            );
            report.assembly_time_s += clock.elapsed().as_secs_f64();
            self.x_lin.clone_from(&xk);
            (self.xk, self.vk) = (xk, vk);
            // Solve for the correction: `b` holds `-g`, and the constrained part is met already.
            // `dv` moves to `delta` while the correction is solved for in `dv` (from zero).
            std::mem::swap(&mut self.dv, &mut self.delta);
            scratch(&mut self.dv, n);
            self.dv.fill(Vec3::ZERO);
            self.z.fill(Vec3::ZERO);
            stats = self.solve(filt, SolveKind::Newton, tight);
            tally(report, &stats);
            cg_iterations += stats.iterations;
            for (total, c) in self.delta.iter_mut().zip(&self.dv) {
                *total += *c;
            }
            std::mem::swap(&mut self.dv, &mut self.delta);
        }

        if newton > 0 {
            // Newton's last residual `g = M dv - h f(x1, v1)` (in `b` as `-g`): converged, its
            // constrained part is the reaction of the nonlinear system.
            for i in 0..n {
                self.impulses[i] = filt[i].constrained(-self.b[i]);
            }
        }
        self.record_loads(d, v, h);
        for i in 0..n {
            v[i] += self.dv[i];
            x[i] += v[i] * h;
        }
        report.moving_friction.clear();
        report.moving_friction.extend(
            (self.drags.iter())
                .filter(|g| g.reference != Vec3::ZERO)
                .map(|g| (g.vertex as u32, g.force(v[g.vertex]))),
        );
        report.contact_forces.clear();
        report
            .contact_forces
            .extend(d.constraints.contacts.iter().map(|c| {
                if c.is_valid(n) {
                    c.force(x)
                } else {
                    0.0
                }
            }));
        self.filter = filter;
        report.force_evaluations = 2 + newton;
        report.cg_iterations = cg_iterations;
        report.cg_residual = stats.residual;
    }
}

/// Whether Newton iterations are converging too slowly to bring the energy they create under
/// `allowed` in the `left` iterations they have: `created` is the energy of the last three
/// iterates, oldest first. Where the Jacobian leaves out what the step needs (the transverse
/// stiffness of compressed springs is clamped to zero, friction and contact are lagged), Newton
/// converges only linearly: in the node's towel crumpled by drape_bot's arm jumping at its
/// velocity limits each iteration kept 0.8-0.9 of the energy the last created, so the cap's
/// eight iterations, each a linear solve, tripled a frame's cost and still ended over the
/// allowance. Linear convergence is read from two iterations in a row that each keep more than
/// [`SLOW_NEWTON`] of the energy; one slow iteration is no verdict, a first correction can
/// overshoot before the quadratic phase (the stiff cloth of `tests/implicit_newton.rs` goes
/// from 0.01 J to 0.1, 0.04, 0.003 and 0.0006 J, accepted at the fifth iterate). The best
/// iterate is then kept at once, and the divergence guard's own energy check decides whether
/// the step stands.
fn out_of_reach(created: [f64; 3], allowed: f64, left: u32) -> bool {
    let [a, b, c] = created;
    let (r1, r2) = (b / a, c / b);
    let slow = |r: f64| r > SLOW_NEWTON && r < 1.0;
    c > allowed
        && allowed > 0.0
        && slow(r1)
        && slow(r2)
        && (allowed / c).ln() / r2.ln() > f64::from(left)
}

impl Implicit {
    /// One round of the step's active sets on the current answer: friction drags, contact
    /// springs, edge springs' drags and (`holds`) the held vertices, whose impulses it computes.
    /// Returns whether any changed (the system then needs a new solve) and whether the
    /// impulses are those of the current answer. `tight`: the answer is solved to the scene's
    /// tolerance (pinch patches are refitted only then, see `refit_drags`).
    fn refit_active_sets(
        &mut self,
        filt: &mut [Filter],
        d: &Dynamics,
        s: &State,
        h: f64,
        (holds, tight): (bool, bool),
    ) -> (bool, bool) {
        let v = s.v;
        let drags = self.refit_drags(v, d.mass, h, tight);
        let springs = self.refit_springs(d, s, h);
        let edge_drags = self.refit_edge_drags(d, v, h);
        let mut released = false;
        if holds {
            self.linear_impulses(filt);
            released = self.settle_holds(filt, d, v);
        }
        (drags || springs || edge_drags || released, holds)
    }

    /// Records each held vertex's tangential load of this step, `m dv / h - f_friction(v1)`
    /// (see [`Implicit::loads`]): what the next step's friction modes are decided on.
    fn record_loads(&mut self, d: &Dynamics, v0: &[Vec3], h: f64) {
        let n = v0.len();
        self.loads.clear();
        self.loads.resize(n, Vec3::ZERO);
        for g in &self.drags {
            let i = g.vertex;
            self.loads[i] -= g.force(v0[i] + self.dv[i]);
        }
        for i in 0..n {
            if self.limit_sum[i] > 0.0 {
                self.loads[i] += self.dv[i] * (d.mass[i] / h);
            }
        }
    }
}

/// Adds one solve's iteration time and work, and its setup, to the step's report.
fn tally(report: &mut StepReport, s: &SolveStats) {
    let its = f64::from(s.iterations);
    report.cg_time_s += s.seconds;
    report.setup_time_s += s.setup_seconds;
    report.factorisations += s.factorisations;
    report.analyses += s.analyses;
    report.cg_flops += s.flops * its;
    report.cg_bytes += s.bytes * its;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The energy (J) Newton's iterates created in two measured steps: the node's towel during
    /// an arm jump (allowance 9.1e-4 J) converging linearly, and the stiff cloth of
    /// `tests/implicit_newton.rs` (allowance 3.5e-6 J) overshooting before its quadratic phase.
    #[test]
    fn only_steady_slow_convergence_is_out_of_reach() {
        let towel = [1.260e-2, 1.017e-2, 8.850e-3, 7.911e-3];
        assert!(!out_of_reach([f64::NAN, towel[0], towel[1]], 9.1e-4, 7));
        assert!(out_of_reach([towel[0], towel[1], towel[2]], 9.1e-4, 6));
        let stiff = [1.024e-2, 9.769e-2, 4.362e-2, 3.430e-3];
        assert!(!out_of_reach([stiff[0], stiff[1], stiff[2]], 3.5e-6, 6));
        assert!(!out_of_reach([stiff[1], stiff[2], stiff[3]], 3.9e-6, 5));
        // Slow but within reach: 0.9 a step from twice the allowance takes 7 iterations.
        assert!(!out_of_reach([2.47e-3, 2.22e-3, 2.0e-3], 1e-3, 7));
        assert!(out_of_reach([2.47e-3, 2.22e-3, 2.0e-3], 1e-3, 6));
    }
}
