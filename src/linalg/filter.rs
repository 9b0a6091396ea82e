//! The per-vertex velocity filter `S` of the constrained dynamics (Baraff and Witkin's "mass
//! modification"): which directions of a vertex move freely during a step.
//!
//! It lives below both `collide` (which decides from contacts what to hold, see
//! `collide/held.rs`) and `integrate` (whose methods filter accelerations or CG iterates), so
//! neither imports the other for it.

use super::dense::outer;
use crate::{Mat3, Vec3};

/// How a vertex's velocity is constrained during a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Filter {
    Free,
    /// The component along this unit direction is prescribed (a contact normal); the vertex
    /// moves freely in the plane orthogonal to it.
    Direction(Vec3),
    /// Only the component along this unit direction is free (a vertex held by two contact
    /// surfaces at once slides along their common edge line; both normals are prescribed).
    Line(Vec3),
    /// Fully prescribed (pinned or attached vertices).
    Fixed,
}

impl Filter {
    /// `S a`: removes the constrained components of `a`.
    #[inline]
    pub fn apply(&self, a: Vec3) -> Vec3 {
        match *self {
            Filter::Free => a,
            Filter::Direction(n) => a - n * n.dot(a),
            Filter::Line(e) => e * e.dot(a),
            Filter::Fixed => Vec3::ZERO,
        }
    }

    /// The constrained part `(I - S) a`.
    #[inline]
    pub fn constrained(&self, a: Vec3) -> Vec3 {
        a - self.apply(a)
    }

    /// `S` as a matrix: `I`, `I - n n^T`, `e e^T` or `0`.
    pub fn matrix(&self) -> Mat3 {
        match *self {
            Filter::Free => Mat3::IDENTITY,
            Filter::Direction(n) => Mat3::IDENTITY - outer(n, n),
            Filter::Line(e) => outer(e, e),
            Filter::Fixed => Mat3::ZERO,
        }
    }
}
