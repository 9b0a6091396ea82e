//! What the point queries answer: a surface point with its normal and signed distance, and a
//! segment's first crossing.

use crate::Vec3;

/// Closest point on the obstacle surface in the obstacle's local frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SurfacePoint {
    pub point: Vec3,
    /// Outward unit normal (for surfaces: pointing towards the query point's side).
    pub normal: Vec3,
    /// Distance to the surface, negative inside a solid.
    pub signed_distance: f64,
}

/// First crossing of the surface along a local segment.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SurfaceHit {
    pub point: Vec3,
    /// Unit normal facing the segment's start.
    pub normal: Vec3,
}
