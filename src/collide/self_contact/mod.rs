//! Cloth-cloth collision: proximity repulsion (Bridson-Fedkiw-Anderson 2002: inelastic impulse
//! plus Coulomb friction on close pairs), bounded CCD passes, then rigid impact zones
//! (Provot 1997, Harmon et al. 2008) as the fail-safe so a step that starts free of
//! self-intersections also ends free of them.
//!
//! Every pair is written as a weighted sum of up to four vertices, `r = sum c_k x_k` (vertex-
//! triangle: `x_p - sum b_i x_i`; edge-edge: `(1-s) x_a + s x_b - (1-u) x_c - u x_d`;
//! vertex-vertex: `x_i - x_j`). A change `d` of `r` is distributed as `x_k += c_k w_k d / M` with
//! `M = sum c_k^2 w_k` (w = inverse mass), the minimal-kinetic-energy impulse; kinematic
//! vertices (w = 0) never move.
//!
//! Repulsion and CCD passes are Jacobi: every pair's correction is computed from the state the
//! pass starts in, and each vertex moves by the length-weighted mean of its pairs' moves
//! (`jacobi`), so the outcome does not depend on the order the broad phase lists pairs in (in
//! order, Gauss-Seidel, the pick towel at twice its resolution overstretches on some orders).
//!
//! Files: `stencil` (a pair as a weighted vertex sum), `collider` (topology and buffers),
//! `pairs` (broad phase; `bvh` its hierarchy with normal cones), `exempt` (pairs that are no
//! contact: rest proximity, seams being sewn; `rest` holds the rest-close lists), one query per
//! file (`proximity`, `ccd`, `intersections`), `jacobi` (a pass's position corrections averaged per
//! vertex), `impulses` (its velocity answers, momentum-conserving impulses), `changed` (the pairs a pass can skip: none of their vertices changed), `zones`
//! (the impact-zone fail-safe), `resolve` (their order per detection mode), `report` (its
//! counts), `touch` (the layers resting on each other, which the solver holds next substep).

mod bvh;
mod ccd;
mod changed;
mod collider;
mod exempt;
mod impulses;
mod intersections;
mod jacobi;
mod pairs;
mod proximity;
mod report;
mod resolve;
mod rest;
mod stencil;
mod touch;
mod zones;

pub(crate) use collider::SelfCollider;
pub use report::SelfContactReport;
pub(crate) use resolve::{Repelled, SelfOutcome};
pub(crate) use touch::refresh as refresh_touches;
pub use touch::SelfTouch;
