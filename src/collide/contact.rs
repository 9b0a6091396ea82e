//! What the collision stage hands back about obstacle contacts: the contacts themselves
//! (for the next substep's constraint filter and for metrics).

use crate::Vec3;

/// A vertex touching an obstacle at the end of the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub vertex: u32,
    /// Unit world normal pointing out of the obstacle.
    pub normal: Vec3,
    /// World velocity of the obstacle's surface at the contact point.
    pub surface_velocity: Vec3,
    /// Index into the stage's obstacles.
    pub obstacle: usize,
}
