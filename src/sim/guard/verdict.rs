//! The guard's verdict on a check: go on, split the substep in two (and why), or stop.

use super::settings::{DivergencePolicy, GuardSettings};
use crate::sim::error::Symptom;
use crate::sim::metrics::StepMetrics;
use crate::sim::span::Span;

/// Why a substep is redone as two halves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(in crate::sim) enum Why {
    /// An explicit step over its stability limit: halved before trying (an unstable mode is
    /// only caught by the energy check once it carries a visible share of the energy, and that
    /// energy would stay in the cloth).
    Stability,
    /// A moving obstacle would outrun the cloth near it (see [`crate::sim::fast`]).
    FastContact,
    /// The guard rejected the result (non-finite, too fast, energy gained, stretched by the
    /// collision response) and its policy subdivides.
    Rejected,
    /// The collision pass moved a vertex more than fast contact allows (see
    /// [`crate::sim::fast::jumped`]).
    ResponseJump,
    /// The self-contact fail-safe gave up on pairs of the cloth (a tangle): a shorter substep
    /// gives its impact zones less relative motion to undo.
    Tangle,
}

/// The first vertex (flat index) a check found bad, and what it measured there.
#[derive(Debug, Clone, PartialEq)]
pub(in crate::sim) struct Failure {
    pub vertex: usize,
    pub symptom: Symptom,
}

/// The guard's answer when a substep cannot stand as it is; the state is back at the
/// substep's start.
#[derive(Debug, Clone, PartialEq)]
pub(in crate::sim) enum Redo {
    /// Redo it as two halves.
    Split(Why),
    /// Stop the run.
    Fail(Failure),
}

/// The guard's verdict on one check: `Ok` goes on with the substep.
pub(in crate::sim) type Verdict = Result<(), Redo>;

impl Why {
    /// Counts the split in the step's metrics: for stability (before trying, or after a
    /// rejected result) or for fast contact (predicted, or the response's jump).
    pub fn count(self, m: &mut StepMetrics) {
        match self {
            Why::Stability | Why::Rejected | Why::Tangle => m.subdivisions += 1,
            Why::FastContact | Why::ResponseJump => m.contact_splits += 1,
        }
    }
}

/// A rejected substep (already rolled back): redone as halves when the policy allows, else the
/// run stops.
pub(super) fn rejected(g: &GuardSettings, span: Span, failure: Failure) -> Redo {
    if g.policy == DivergencePolicy::Subdivide && span.depth < g.max_subdivisions {
        Redo::Split(Why::Rejected)
    } else {
        Redo::Fail(failure)
    }
}
