//! The multigrid hierarchy kept across steps, with the bookkeeping that decides when it gets new
//! values along its aggregates and when a full rebuild.

use crate::integrate::precond::Multigrid;

/// Rebuild the hierarchy at least this often (steps); sooner when the iteration count exceeds
/// the one right after the last full build by a quarter (plus two).
pub(super) const REBUILD_EVERY: u32 = 50;

/// Cost of a rebuild along the kept aggregates (new values only), in PCG iterations (measured
/// about two at 64x64). A swinging towel's coarse levels go stale within a few substeps
/// (measured 20, 23, 27, 31 iterations at ages 0 to 3); such a rebuild brings the count back.
pub(super) const REFRESH_COST: u32 = 2;

/// The multigrid state kept across steps.
pub(super) struct Hierarchy {
    pub(super) mg: Multigrid,
    /// Solves since the last build (full or along the kept aggregates).
    pub(super) steps: u32,
    /// Solves since the last full build.
    pub(super) age: u32,
    /// Iterations of the first solve after the last build, and after the last full build.
    pub(super) iterations_at_build: u32,
    pub(super) iterations_at_full: u32,
    /// Iterations beyond `iterations_at_build` summed over the solves since the last build.
    pub(super) excess: u32,
    /// Rebuild along the kept aggregates before the next solve.
    pub(super) rebuild: bool,
}
