//! Obstacle features (rod axes, box and mesh edges and corners) against cloth faces and edges.
//!
//! The vertex stage only asks whether a cloth vertex meets an obstacle. A thin obstacle (a 5 mm
//! rod, a box edge) can pass through a cloth face between vertices without any vertex touching
//! it. Here the obstacle is reduced to features in its local frame: corner points and segments,
//! inflated by a common radius (the rod radius, 0 for box and mesh edges). Each feature moves
//! with the obstacle from `pose_prev` to `pose` (linearly per feature point); each cloth
//! triangle and edge moves linearly from `x0` to `x1`. Corner points are tested against cloth
//! triangles and segments against cloth edges with the conservative-advancement CCD of
//! [`super::narrow`] at `eta = radius + thickness`: at the first time a segment comes within
//! `eta` of a triangle, the closest pair is a segment end vs the triangle or the segment vs a
//! triangle edge, so these two families catch every first contact.
//!
//! Response (Bridson et al. 2002 style, the obstacle has infinite mass): the cloth contact
//! point `c = sum w_k x_k` (barycentric weights) is pushed along the contact normal until it is
//! `eta` in front of the feature at the end pose; the displacement is split as
//! `dx_k = w_k m_k^-1 I` with `I = push / sum w_k^2 m_k^-1`, which moves `c` exactly by `push`
//! and never moves kinematic vertices. Each moving vertex of the contact loses its velocity
//! towards the feature (inelastic, so `c` no longer approaches) and its tangential velocity
//! loses `mu` times that normal change (Coulomb); see `respond` for why per vertex.
//!
//! Files: `set` (an obstacle's features), `contact` (hits, the shared cloth state, the contacts
//! handed to the solver), `sweep` (one pass's features in world space), one query per file
//! (`point_face`: corners vs cloth triangles; `segment_edge`: segments vs cloth edges),
//! `respond` (one contact's answer), `collider` (candidates and passes).

mod collider;
mod contact;
mod point_face;
mod respond;
mod segment_edge;
mod set;
mod sweep;

pub(crate) use collider::FeatureCollider;
pub(crate) use contact::ClothState;
pub use contact::{FeatureContact, DEEP};
pub(crate) use set::Features;
