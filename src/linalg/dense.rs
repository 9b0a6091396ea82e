//! Small dense helpers on 3-vectors and 3x3 blocks shared by the force kernels (`effects`), the
//! solver (`integrate`) and the garment seams.

use crate::{Mat3, Vec3};

/// Outer product `a b^T` (column `k` is `a b_k`).
#[inline]
pub(crate) fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}
