//! The multigrid hierarchy kept across steps, with the bookkeeping that decides when it gets new
//! values along its aggregates and when a full rebuild.

use crate::integrate::precond::Multigrid;
use crate::linalg::Filter;

/// Rebuild the hierarchy at least this often (steps); sooner when the iteration count exceeds
/// the one right after the last full build by a quarter (plus two).
pub(super) const REBUILD_EVERY: u32 = 50;

/// Cost of a rebuild along the kept aggregates (new values only), in PCG iterations: about two
/// at 64x64. A swinging towel's coarse levels go stale within a few substeps (each substep
/// adds a few iterations to its solve); such a rebuild brings the count back.
pub(super) const REFRESH_COST: u32 = 2;

/// Which build's iteration count the next step's first solve measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Pending {
    /// Both counts are measured.
    None,
    /// A build along the kept aggregates.
    Build,
    /// A full build.
    Full,
}

/// The multigrid state kept across steps.
///
/// Its iteration counts are those of a step's first solve only: the refits' and Newton's
/// solves start from the step's answer or solve for a correction and take a few iterations
/// whatever the hierarchy. Taken from any solve, the count after a full build would often be
/// a refit's (a few iterations), so the next step's first solve (tens) would read as drift and
/// ask for another full build, several times as many as needed on S1 64x64
/// (`benches/contact.rs`) and the 20 m/s rod of `benches/fast_links.rs` (whose remaining full
/// builds come from a split substep's count, smaller for its shorter step, taken as the
/// baseline of a full one).
pub(super) struct Hierarchy {
    pub(super) mg: Multigrid,
    /// Whose iteration count the next step's first solve sets.
    pub(super) pending: Pending,
    /// Solves since the last full build.
    pub(super) age: u32,
    /// Iterations of the first solve of the first step after the last build, and after the
    /// last full build.
    pub(super) iterations_at_build: u32,
    pub(super) iterations_at_full: u32,
    /// Iterations beyond `iterations_at_build` summed over the steps' first solves since the
    /// last build.
    pub(super) excess: u32,
    /// Rebuild along the kept aggregates before the next solve.
    pub(super) rebuild: bool,
    /// The filter the coarse levels were last built with (see [`Hierarchy::filter_changed`]).
    pub(super) filter: Vec<Filter>,
}

impl Hierarchy {
    /// Whether a step's filter differs from the one the coarse levels were built with: then
    /// the step's first solve gets coarse levels rebuilt along the kept aggregates. Contacts
    /// change the filter every step (held vertices come and go, normals turn as the cloth
    /// slides), and the smoothed prolongator of the old filter's operator preconditions the
    /// new one poorly: on S1 64x64 (a cloth resting on a sphere, hundreds of held vertices)
    /// the first solve of a step takes far more iterations on the last step's coarse levels
    /// than on rebuilt ones, while a rebuild costs about `REFRESH_COST` iterations. A filter
    /// that does not change (pins only, no contact) keeps the iteration-count schedule above.
    pub(super) fn filter_changed(&self, filter: &[Filter]) -> bool {
        self.filter.as_slice() != filter
    }
}
