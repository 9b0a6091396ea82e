//! The position-only forces kept from the guard's energy pass, for the next force evaluation at
//! the same positions (see [`PositionForces`]).

use crate::linalg::bits;
use crate::Vec3;

/// Sum of the position-only forces at the configuration `x` of the last energy evaluation.
///
/// The divergence guard evaluates the energy of every substep's result `x_{n+1}`; doing so in the
/// same pass as the forces and keeping those forces means the next substep, which starts from
/// `x_{n+1}`, does not evaluate them again. The cache is used only when the positions are
/// bitwise identical, so it never changes a result.
#[derive(Default)]
pub(super) struct PositionForces {
    pub(super) x: Vec<Vec3>,
    pub(super) f: Vec<Vec3>,
    /// The second half's forces when the pass is split across two threads.
    pub(super) half: Vec<Vec3>,
    /// `f` still lacks `half` (the sum is left to the consumer, which can do it in parallel).
    pub(super) split: bool,
    pub(super) valid: bool,
}

impl PositionForces {
    /// Whether the cached forces are those at exactly `x`.
    /// Compares bit patterns (a `memcmp`), the criterion that guarantees identical forces.
    pub(super) fn hit(&self, x: &[Vec3]) -> bool {
        self.valid && self.f.len() == x.len() && bits(&self.x) == bits(x)
    }
}
