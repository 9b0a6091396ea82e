//! The direct linear path: the step's solves preconditioned by the sparse Cholesky factor of
//! the filtered system `S A S + (I - S)`, refactorised (numerically) whenever `A`'s values or
//! the filter changed since, on the symbolic analysis kept for `A`'s pattern.
//!
//! The factor of the current matrix is exact: the modified PCG ends after one iteration. Pair
//! springs between cloth layers couple vertices outside `A`'s pattern (`contact::OffPattern`);
//! `A` holds their lumped, stiffer diagonal, so the factor is an approximate inverse of the
//! system with them and the iteration takes a few more steps instead of a new pattern (and a
//! new symbolic analysis) every time self-contact changes.
//!
//! An earlier matrix's factor (the last step's, or the same step's before an active-set
//! round's refits or at the last Newton iterate) measured a poor preconditioner on S1 64x64
//! (`cargo bench --bench contact`): 25-30 iterations a solve, each two triangular solves at
//! about a tenth of a factorisation, so every changed matrix is refactorised.

use super::solve::SolveKind;
use super::solver::Implicit;
use crate::integrate::cg::{Precond, SolveStats};
use crate::linalg::Filter;
use std::time::Instant;

impl Implicit {
    /// One solve on the direct path (see the module's doc). `None` when the factorisation
    /// failed or the iteration did not reach `tol` (degenerate input): the caller solves by
    /// PCG from the answer in `dv`.
    pub(super) fn solve_direct(
        &mut self,
        filt: &[Filter],
        kind: SolveKind,
        tol: f64,
    ) -> Option<SolveStats> {
        let max_it = self.settings.cg_max_iterations;
        let a = self.a.as_ref()?;
        let second = (kind == SolveKind::First).then_some(self.older.as_slice());
        if let Some(done) = (self.pcg).start(a, filt, &self.b, &self.z, tol, &mut self.dv, second) {
            return Some(done);
        }
        let direct = &mut self.direct;
        let clock = Instant::now();
        let (mut factorisations, mut analyses) = (0, 0);
        if !direct.is_current(a, filt) {
            let before = direct.chol.analyses;
            let done = direct.chol.factorise(a, filt);
            factorisations = 1;
            analyses = (direct.chol.analyses - before) as u32;
            if let Err(e) = done {
                log::debug!("direct solve unavailable ({e}); solving by PCG");
                direct.factored = None;
                return None;
            }
            direct.factored = Some((a.pattern_id(), a.version()));
            direct.filter.clear();
            direct.filter.extend_from_slice(filt);
        }
        let setup_seconds = clock.elapsed().as_secs_f64();
        let pre = Precond::Cholesky(&mut direct.chol);
        let mut stats = self.pcg.iterate(a, filt, pre, tol, max_it, &mut self.dv);
        (stats.setup_seconds, stats.factorisations, stats.analyses) =
            (setup_seconds, factorisations, analyses);
        (stats.residual <= tol).then_some(stats)
    }
}
