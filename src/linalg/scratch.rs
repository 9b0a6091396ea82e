//! Reusable scratch buffers: the step's passes keep their vectors across steps and only resize
//! them when the vertex count changes, so a step allocates nothing.

use crate::Vec3;

/// Resizes a scratch buffer without reallocating when the size is unchanged (contents are
/// zeroed only when the size changes; callers overwrite every entry).
pub(crate) fn scratch(buf: &mut Vec<Vec3>, n: usize) {
    if buf.len() != n {
        buf.clear();
        buf.resize(n, Vec3::ZERO);
    }
}
