//! collide (placeholder)

pub mod narrow;
