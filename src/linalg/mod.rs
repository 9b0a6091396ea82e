//! Linear algebra shared by the force terms (`effects`), the time integrators (`integrate`) and
//! the collision stage (`collide`): the block-sparse system matrix and its pattern, the
//! velocity filter, the filtered system's sparse Cholesky factor, small dense helpers, flat
//! views and scratch buffers. It imports nothing of the simulator above it.

mod cholesky;
mod dense;
mod filter;
mod flat;
mod scratch;
mod sparse;

pub use cholesky::{CholeskyError, FilteredCholesky};
pub(crate) use dense::outer;
pub use filter::Filter;
pub(crate) use flat::{bits, flat, flat_bits, flat_mut};
pub(crate) use scratch::scratch;
pub use sparse::{BlockCsr, PairSlots, PatternBuilder};
