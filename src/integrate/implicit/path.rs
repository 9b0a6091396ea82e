//! Which linear path a step runs: the scene's `solver.linear`, and for `auto` the path a cost
//! model calibrated on `cargo bench --bench contact` predicts cheaper.
//!
//! `auto` starts on PCG and moves to the direct path for the rest of the cloth's pattern once
//! the direct path's predicted cost was below PCG's for [`SWITCH_STEPS`] steps in a row. The
//! prediction uses counts only (PCG's iterations and solves in the step, the factor's
//! multiply-adds and size from the symbolic analysis), never the running clock, so a simulation
//! stays a function of its input, bit for bit, whatever else loads the machine.
//!
//! Calibration (2-core machine, both paths of one bench run): a PCG iteration with the
//! multigrid costs about `PCG_SECONDS_PER_VERTEX` per vertex (0.385 ms at 32x32, 1.42 ms at
//! 64x64); a numeric factorisation about `FACTOR_SECONDS_PER_FLOP` per multiply-add (50 ms
//! for the 4.3e8 of 64x64) and the two triangular solves of an iteration about
//! `SOLVE_SECONDS_PER_VALUE` per value of `L` (7 ms for 2.1e6 at 64x64). So the direct path
//! pays when PCG needs more than about 30 (32x32) to 40 (64x64) iterations a solve.

use super::settings::{LinearPath, LinearSolver};
use super::solver::Implicit;

const PCG_SECONDS_PER_VERTEX: f64 = 3.6e-7;
const FACTOR_SECONDS_PER_FLOP: f64 = 1.16e-10;
const SOLVE_SECONDS_PER_VALUE: f64 = 3.3e-9;

/// Steps in a row the direct path must be predicted cheaper before `auto` takes it.
const SWITCH_STEPS: u32 = 3;

impl Implicit {
    /// Sets the path of the step about to solve (its matrix assembled), reading the last
    /// step's counts when `auto` decides.
    pub(super) fn choose_path(&mut self) {
        self.path = match self.linear {
            LinearSolver::Pcg => LinearPath::Pcg,
            LinearSolver::Direct => LinearPath::Direct,
            LinearSolver::Auto => self.auto_path(),
        };
        (self.auto.iterations, self.auto.solves) = (0, 0);
    }

    fn auto_path(&mut self) -> LinearPath {
        let Some(a) = self.a.as_ref() else {
            return LinearPath::Pcg;
        };
        let pattern = a.pattern_id();
        if self.auto.direct_for == Some(pattern) {
            return LinearPath::Direct;
        }
        if self.auto.solves == 0 {
            return LinearPath::Pcg;
        }
        let pcg = f64::from(self.auto.iterations) * PCG_SECONDS_PER_VERTEX * a.rows() as f64;
        // The analysis is kept for the direct path; it is needed only once PCG iterates long.
        let analysed = pcg > 0.0 && self.direct.chol.analyse(a).is_ok();
        let direct = f64::from(self.auto.solves)
            * (FACTOR_SECONDS_PER_FLOP * self.direct.chol.factor_flops()
                + SOLVE_SECONDS_PER_VALUE * self.direct.chol.factor_len() as f64);
        if analysed && direct < pcg {
            self.auto.cheaper += 1;
        } else {
            self.auto.cheaper = 0;
        }
        if self.auto.cheaper >= SWITCH_STEPS {
            log::debug!(
                "linear path: direct ({:.1} ms predicted a step against PCG's {:.1} ms)",
                1e3 * direct,
                1e3 * pcg
            );
            self.auto.direct_for = Some(pattern);
            return LinearPath::Direct;
        }
        LinearPath::Pcg
    }
}
