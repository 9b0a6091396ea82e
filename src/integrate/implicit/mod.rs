//! Implicit backward Euler after Baraff and Witkin (1998): one linearised solve per step,
//!
//! `(M - h df/dv - h^2 df/dx) dv = h (f0 + h df/dx v0)`,   `v1 = v0 + dv`,   `x1 = x0 + h v1`,
//!
//! with the modified preconditioned conjugate gradient that keeps every iterate inside the
//! constraint set: the filter `S_i = I - p p^T` removes constrained directions and the constrained
//! components of `dv` are fixed to `z` (the velocity change that meets the target).
//!
//! When that one solve creates energy (stiff springs rotating: see `newton::EnergyCheck`), Newton
//! iterations on the nonlinear system `M dv = h f(x0 + h v1, v1)` follow until it no longer does;
//! ordinary cloth steps pass the check after the single solve and cost one extra force pass.
//!
//! The preconditioner is smoothed-aggregation multigrid on the filtered operator (see
//! [`super::precond`]); its hierarchy gets new values along the same aggregates when the
//! iteration count drifts up or a step's contacts changed the filter, a full rebuild when that
//! no longer helps, and block Jacobi takes over whenever the hierarchy cannot be built. The solve starts from the combination of the
//! last two steps' velocity changes that is best in the energy norm.
//!
//! Files by concern: `settings.rs` (the scene's solver settings), `solver.rs` (the solver's
//! buffers and its `Integrator` face), `step.rs` (one step: assemble, solve, refit, Newton),
//! `assembly.rs` (the linearised system), `refit.rs` (friction drags and contact springs as an
//! active set), `holds.rs` (contact holds that may only push), `newton.rs` (the energy check
//! that decides on Newton iterations), `solve.rs` (the conjugate gradient with its multigrid
//! hierarchy kept across steps, see `hierarchy.rs`). The conjugate gradient itself is
//! [`super::cg`], the multigrid [`super::precond`].

mod assembly;
mod auto;
mod direct;
mod factor;
mod hierarchy;
mod holds;
mod newton;
mod path;
mod refit;
mod settings;
mod solve;
mod solver;
mod step;

pub use settings::{ImplicitSettings, LinearPath, LinearSolver};
pub use solver::Implicit;
