//! Linear algebra shared by the force terms (`effects`), the time integrators (`integrate`) and
//! the collision stage (`collide`): the velocity filter, small dense helpers and scratch
//! buffers. It imports nothing of the simulator above it.

mod dense;
mod filter;
mod scratch;

pub(crate) use dense::outer;
pub use filter::Filter;
pub(crate) use scratch::scratch;
