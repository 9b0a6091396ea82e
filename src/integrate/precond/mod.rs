//! Smoothed-aggregation algebraic multigrid for the implicit solver's 3x3-block system, after
//! Tamstorf, Jones and McCormick, "Smoothed Aggregation Multigrid for Cloth Simulation" (2015).
//!
//! Block Jacobi needs O(n) iterations once `h^2 k / m` is large, because it only smooths locally;
//! a multigrid V-cycle removes the smooth (long-wavelength) error on coarse levels and keeps the
//! PCG iteration count roughly independent of the resolution.
//!
//! Constraints: the matrix handed to [`Multigrid::build`] is the *filtered* operator
//! `S A S + c (I - S)` (built by [`Csr::filtered`]), which is SPD when `A` is, acts as `S A S` on the
//! free components and as a scaled identity on the constrained ones (`c` = mean diagonal entry of
//! the vertex, so both parts have comparable magnitude). PCG applies `S M^-1 S`, which is SPD on the
//! free subspace because the V-cycle below is symmetric (forward Gauss-Seidel before, backward
//! after, exact or symmetric-sweep coarsest solve) and every coarse matrix is a Galerkin product.
//!
//! Hierarchy: aggregates from the strong-connection block graph, tentative prolongator from the
//! translation near-null space (one 3x3 identity per vertex), smoothed once with damped block
//! Jacobi, Galerkin coarse matrices `P^T A P`, dense Cholesky on the coarsest level.
//!
//! By stage: `csr.rs` (the single-precision block matrix and the filtered fine operator),
//! `aggregate.rs` (aggregates from strong connections), `prolong.rs` (the smoothed
//! prolongator), `smooth.rs` (a level and its Gauss-Seidel sweeps), `dense.rs` (the coarsest
//! solve), `hierarchy.rs` (building and refreshing the levels), `cycle.rs` (the V-cycle).

mod aggregate;
mod csr;
mod cycle;
mod dense;
mod error;
mod hierarchy;
mod prolong;
mod smooth;

pub use csr::Csr;
pub use hierarchy::Multigrid;
