//! Which linear path a step runs: the scene's `solver.linear`, and for `auto` the cheaper path
//! by a cost model calibrated on `cargo bench --bench contact`.
//!
//! The choice is made from counts, not from the wall clock of the running simulation: a
//! simulation stays a function of its input, bit for bit, whatever else loads the machine.
//! The count is the factorisation's multiply-adds from the symbolic analysis of the cloth's
//! pattern (once per topology); the threshold is where the measured direct path stops being
//! faster than PCG with its multigrid (see `AUTO_MAX_FACTOR_FLOPS`).

use super::settings::{LinearPath, LinearSolver};
use super::solver::Implicit;
use crate::linalg::Filter;

/// Factorisation multiply-adds up to which `auto` takes the direct path.
pub(super) const AUTO_MAX_FACTOR_FLOPS: f64 = 2e9;

/// What `auto` decided, for which pattern.
#[derive(Debug, Default)]
pub(super) struct AutoPath {
    decided: Option<(u64, LinearPath)>,
}

impl Implicit {
    /// Sets the path of the step about to solve (its matrix assembled).
    pub(super) fn choose_path(&mut self, _filt: &[Filter]) {
        self.path = match self.linear {
            LinearSolver::Pcg => LinearPath::Pcg,
            LinearSolver::Direct => LinearPath::Direct,
            LinearSolver::Auto => self.auto_path(),
        };
    }

    /// `auto`'s path for the current pattern: direct while one factorisation costs at most
    /// `AUTO_MAX_FACTOR_FLOPS` (PCG when the analysis fails).
    fn auto_path(&mut self) -> LinearPath {
        let Some(a) = self.a.as_ref() else {
            return LinearPath::Pcg;
        };
        let pattern = a.pattern_id();
        if let Some((p, path)) = self.auto.decided {
            if p == pattern {
                return path;
            }
        }
        let path = match self.direct.chol.analyse(a) {
            Ok(()) if self.direct.chol.factor_flops() <= AUTO_MAX_FACTOR_FLOPS => {
                LinearPath::Direct
            }
            _ => LinearPath::Pcg,
        };
        log::debug!(
            "linear path {} ({:.2e} multiply-adds a factorisation)",
            path.name(),
            self.direct.chol.factor_flops()
        );
        self.auto.decided = Some((pattern, path));
        path
    }
}
