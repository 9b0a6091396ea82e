//! Rigid obstacles: a parry shape plus previous/current pose (the sweep over one step), and the
//! f64 point queries the collision stage needs (closest surface point, first surface crossing).
//!
//! Axis conventions (parry's): capsule and cylinder are along the local y axis, centred at the
//! origin; a box is centred with `half_extents`; a plane passes through the local origin with the
//! given outward normal (the free side). Spheres, planes, boxes and capsules are evaluated analytically
//! in f64; cylinders and meshes go through parry (f32, in the obstacle's local frame, so the rounding is relative
//! to the obstacle's size, ~1e-7 m for a 1 m object). Meshes are treated as two-sided surfaces of
//! zero thickness (cloth keeps to the side it came from; the cloth thickness gives the gap), so
//! open meshes work as well as closed ones.
//!
//! Files: `shape` (the obstacle, its constructors and swept bounds), `query` (f64 point
//! queries: closest surface point, inside test, first crossing), `surface` (the queries'
//! answers), `cuboid` (the box's exact closest point and slab cast).

mod cuboid;
mod query;
mod shape;
mod surface;

pub(crate) use query::ON_SURFACE;
pub(crate) use shape::Geom;
pub use shape::{Obstacle, ObstacleError};
