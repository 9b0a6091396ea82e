//! The direct path's factor and what it was computed from (the matrix's pattern and version and
//! the filter), so a solve refactorises only a changed system (see `direct`).

use crate::linalg::{BlockCsr, Filter, FilteredCholesky};

/// The factor and what it was computed from.
#[derive(Debug, Default)]
pub(super) struct Direct {
    pub(super) chol: FilteredCholesky,
    /// `(pattern, version)` of the matrix the factor holds, and its filter.
    pub(super) factored: Option<(u64, u64)>,
    pub(super) filter: Vec<Filter>,
}

impl Direct {
    pub(super) fn is_current(&self, a: &BlockCsr, filt: &[Filter]) -> bool {
        self.chol.has_factor()
            && self.factored == Some((a.pattern_id(), a.version()))
            && self.filter.as_slice() == filt
    }
}
