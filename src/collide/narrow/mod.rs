//! Narrow-phase geometry in f64: static closest points, triangle-triangle intersection and
//! continuous collision detection (CCD) for linearly moving points, edges and triangles.
//!
//! Used by the collision stage for cloth self-collision (both sides moving) and for cloth vs
//! obstacle meshes. Everything is allocation-free and works on [`crate::Vec3`].
//!
//! Conventions: a moving primitive is given by its vertices at `t = 0` and at `t = 1`; hit
//! times are in `[0, 1]`; touching counts as contact (including at exactly `t = 0`/`t = 1`).

mod ccd;
mod closest;
pub mod cubic;
pub mod sweep;
mod tritri;

pub use ccd::{
    edge_edge_ccd, edge_edge_ccd_thick, vertex_triangle_ccd, vertex_triangle_ccd_thick, EeHit,
    VtHit, SLACK_REL, THICK_ACCEPT_REL,
};
pub use closest::{point_segment_closest, point_triangle_closest, segment_segment_closest};
pub use tritri::{triangles_intersect, TOUCH_REL};
