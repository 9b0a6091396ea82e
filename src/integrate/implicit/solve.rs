//! The step's linear solves: the modified PCG preconditioned by the multigrid hierarchy kept
//! across steps (block Jacobi when it cannot be built or breaks down).

use super::hierarchy::{Hierarchy, Pending, REBUILD_EVERY, REFRESH_COST};
use super::settings::{LinearPath, Preconditioner};
use super::solver::Implicit;
use crate::integrate::cg::SolveStats;
use crate::integrate::precond::Multigrid;
use crate::linalg::Filter;
use crate::Vec3;

/// Which of a step's solves (see `step.rs`): it decides the start directions and what the
/// multigrid hierarchy gets before the iterations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SolveKind {
    /// The step's first solve: `dv` holds the last step's velocity change and `older` the one
    /// before, both start directions; its iteration count drives the rebuild schedule.
    First,
    /// A re-solve after an active-set round or the polish, from the current answer (`dv`): the
    /// matrix changed in the rows the round refitted.
    Round,
    /// A Newton correction, from zero, on the matrix assembled at the iterate: its coarse
    /// levels are rebuilt along the kept aggregates. The step's own coarse levels (at its start
    /// state) precondition the iterate's matrix poorly where the impact turned stiff springs
    /// (S1 64x64's landing, `cargo bench --bench contact`): rebuilt ones take several times
    /// fewer iterations, which saves far more than the rebuild costs.
    Newton,
}

impl Implicit {
    /// Solves `A dv = b` with the constrained part `z` (dv holds the start) on the step's linear
    /// path (see `path.rs`); the direct path hands a solve it cannot do to PCG.
    pub(super) fn solve(&mut self, filt: &[Filter], kind: SolveKind, tol: f64) -> SolveStats {
        if self.path == LinearPath::Direct {
            if let Some(stats) = self.solve_direct(filt, kind, tol) {
                return stats;
            }
        }
        let stats = self.solve_pcg(filt, kind, tol);
        if stats.iterations > 0 {
            self.auto.iterations += stats.iterations;
            self.auto.solves += 1;
        }
        stats
    }

    /// Solves `A dv = b` with the constrained part `z` (dv holds the start). A start that meets
    /// `tol` already (an active-set round that moved the answer less than that) returns at once:
    /// no preconditioner update, and the rebuild schedule counts only solves that iterate.
    ///
    /// A split or subdivided step (`short_step`) keeps the last full step's aggregates (see
    /// [`Self::update_hierarchy`]) and stays out of the rebuild schedule. Aggregated afresh, a
    /// short step's mass-dominated matrix coarsens poorly (few, dense coarse levels, each build
    /// several times a full substep's), and its smaller iteration count, taken as the
    /// schedule's baseline, makes the next full step's read as drift. Block Jacobi for short
    /// steps would be as cheap on the 20 m/s rod of `cargo bench --bench fast_links`, but more
    /// than doubles the CG iterations of S1 64x64 (`cargo bench --bench contact`), whose splits
    /// land the cloth on the ball.
    fn solve_pcg(&mut self, filt: &[Filter], kind: SolveKind, tol: f64) -> SolveStats {
        let max_it = self.settings.cg_max_iterations;
        let short = self.short_step;
        let history = kind == SolveKind::First;
        if history && !short {
            if let Some(h) = self.hierarchy.as_mut() {
                h.rebuild |= h.filter_changed(filt);
            }
        }
        let Some(a) = self.a.as_ref() else {
            unreachable!("prepared by the step");
        };
        let second = history.then_some(self.older.as_slice());
        if let Some(done) = (self.pcg).start(a, filt, &self.b, &self.z, tol, &mut self.dv, second) {
            // The start meets the tolerance (an active-set round that moved the answer less
            // than the tolerance): no preconditioner update, and nothing for the schedule.
            return done;
        }
        let clock = std::time::Instant::now();
        let use_mg = self.update_hierarchy(filt, short, kind).is_some();
        let setup_seconds = clock.elapsed().as_secs_f64();
        let Some(a) = self.a.as_ref() else {
            unreachable!("prepared by the step");
        };
        let mgref = match self.hierarchy.as_mut() {
            Some(h) if use_mg => Some(&mut h.mg),
            _ => None,
        };
        let mut stats = self
            .pcg
            .iterate(a, filt, mgref.into(), tol, max_it, &mut self.dv);
        if use_mg && (stats.residual.is_nan() || stats.residual > tol) && stats.iterations < max_it
        {
            // The multigrid-preconditioned iteration broke down early (degenerate input): retry
            // from scratch with block Jacobi and rebuild the hierarchy next step.
            log::debug!("multigrid PCG stopped early ({stats:?}); retrying with block Jacobi");
            self.hierarchy = None;
            self.dv.iter_mut().for_each(|x| *x = Vec3::ZERO);
            stats = self.pcg.solve(
                a,
                filt,
                &self.b,
                &self.z,
                None,
                tol,
                max_it,
                &mut self.dv,
                None,
            );
        }
        stats.setup_seconds = setup_seconds;
        if let Some(h) = self.hierarchy.as_mut().filter(|_| history && !short) {
            let its = stats.iterations;
            if h.pending != Pending::None {
                h.iterations_at_build = its;
                h.excess = 0;
                if h.pending == Pending::Full {
                    h.iterations_at_full = its;
                }
                h.pending = Pending::None;
            } else if its > h.iterations_at_full + h.iterations_at_full / 4 + 2 {
                h.age = REBUILD_EVERY; // drifted despite the cheap rebuilds: full rebuild next
            } else {
                // The coarse levels go stale as the cloth turns: new values once the iterations
                // lost to staleness add up to what the rebuild costs (at most twice the best
                // rebuild schedule's cost, as in ski rental).
                h.excess += its.saturating_sub(h.iterations_at_build);
                h.rebuild = h.excess >= REFRESH_COST;
            }
        }
        stats
    }

    /// Gives the multigrid the current filtered matrix: a fresh hierarchy when none exists or the
    /// last one has aged (iterations drifting up or `REBUILD_EVERY` steps), else only the finest
    /// level (only its rows an active-set round changed, when that is all that changed since:
    /// `BlockCsr::edited_rows` and `Multigrid::refilter_finest`). `None` means block Jacobi
    /// (multigrid disabled or its setup failed).
    ///
    /// A short step (`short`: split or subdivided) gets coarse values along the last full step's
    /// aggregates at its first solve, the finest level alone at its re-solves, and leaves the
    /// schedule as it was, with a rebuild due at the next full step. A Newton correction gets
    /// coarse values for its matrix in either (see [`SolveKind::Newton`]).
    pub(super) fn update_hierarchy(
        &mut self,
        filt: &[Filter],
        short: bool,
        kind: SolveKind,
    ) -> Option<&mut Multigrid> {
        if self.preconditioner != Preconditioner::Multigrid {
            return None;
        }
        let a = self.a.as_ref()?;
        let n = a.rows();
        let reuse = self
            .hierarchy
            .as_ref()
            .is_some_and(|h| h.mg.rows() == n && h.age < REBUILD_EVERY);
        if reuse {
            if let Some(h) = self.hierarchy.as_mut() {
                let rebuild = kind == SolveKind::Newton
                    || if short {
                        kind == SolveKind::First
                    } else {
                        h.rebuild
                    };
                // An active-set round's refits and releases change a few rows: only those are
                // refiltered when nothing else changed since the last filtering.
                let refiltered = match a.edited_rows() {
                    Some(edited) if !rebuild => h.mg.refilter_finest(a, filt, edited),
                    _ => Ok(false),
                };
                let done = match refiltered {
                    Ok(true) => Ok(()),
                    Ok(false) => {
                        let mut fine = h.mg.take_finest();
                        fine.filtered(a, filt);
                        if rebuild {
                            h.mg.rebuild(fine)
                        } else {
                            h.mg.refresh_finest(fine)
                        }
                    }
                    Err(e) => Err(e),
                };
                match done {
                    Ok(()) if short => h.rebuild = true,
                    Ok(()) => {
                        h.age += 1;
                        if rebuild && h.pending == Pending::None {
                            h.pending = Pending::Build;
                        }
                        h.rebuild = false;
                        if rebuild {
                            h.filter.clear();
                            h.filter.extend_from_slice(filt);
                        }
                    }
                    Err(e) => {
                        log::debug!("multigrid refresh failed ({e}); rebuilding");
                        self.hierarchy = None;
                        return None;
                    }
                }
                if let Some(a) = self.a.as_mut() {
                    a.clear_edits();
                }
                return self.hierarchy.as_mut().map(|h| &mut h.mg);
            }
        }
        // A fresh hierarchy, in the storage of the one it replaces.
        let (mut fine, old) = match self.hierarchy.take() {
            Some(Hierarchy { mut mg, .. }) => (mg.take_finest(), Some(mg)),
            None => (std::mem::take(&mut self.filtered), None),
        };
        fine.filtered(a, filt);
        let built = match old {
            Some(mg) => Multigrid::build_reusing(fine, mg),
            None => Multigrid::build(fine),
        };
        match built {
            Ok(mg) => {
                if let Some(a) = self.a.as_mut() {
                    a.clear_edits();
                }
                self.hierarchy = Some(Hierarchy {
                    mg,
                    pending: Pending::Full,
                    age: 0,
                    iterations_at_build: 0,
                    iterations_at_full: 0,
                    excess: 0,
                    rebuild: false,
                    filter: filt.to_vec(),
                });
                self.hierarchy.as_mut().map(|h| &mut h.mg)
            }
            Err(e) => {
                log::debug!("multigrid setup failed ({e}); using block Jacobi");
                self.hierarchy = None;
                None
            }
        }
    }
}
