//! Flat and bit-pattern views of vector slices: `[Vec3]` as `[f64]` for SIMD loops, and as
//! `[u64]` for exact (`memcmp`) comparison of positions and masses.

use crate::Vec3;

/// Positions or forces as one flat `[x0, y0, z0, x1, ...]` slice.
pub(crate) fn flat(v: &[Vec3]) -> &[f64] {
    const _: () = assert!(std::mem::size_of::<Vec3>() == 3 * std::mem::size_of::<f64>());
    // SAFETY: `Vec3` (glam's DVec3) is `#[repr(C)]` with three f64 fields and no padding (size
    // checked above), so `v` is `3 v.len()` contiguous, initialised, aligned f64 values.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<f64>(), 3 * v.len()) }
}

/// The bit patterns of positions, for exact comparison.
pub(crate) fn bits(v: &[Vec3]) -> &[u64] {
    // SAFETY: as in `flat`; u64 has the size and alignment of f64 and every bit pattern is valid.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u64>(), 3 * v.len()) }
}

/// The bit patterns of `f64` values, for exact comparison by `memcmp`.
pub(crate) fn flat_bits(v: &[f64]) -> &[u64] {
    // SAFETY: u64 has the size and alignment of f64 and every bit pattern is valid.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u64>(), v.len()) }
}

/// Mutable [`flat`].
pub(crate) fn flat_mut(v: &mut [Vec3]) -> &mut [f64] {
    // SAFETY: as in `flat`; the result borrows `v` mutably and exclusively.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr().cast::<f64>(), 3 * v.len()) }
}
