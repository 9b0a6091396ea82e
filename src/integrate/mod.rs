//! Time integrators behind one trait: explicit (forward) Euler, symplectic Euler, classic RK4 and
//! implicit backward Euler after Baraff and Witkin ("Large Steps in Cloth Simulation", 1998).
//!
//! `integrator.rs` holds the trait with its capabilities and step report, `dynamics.rs` what a
//! step integrates (effects, masses, constraints), `kind.rs` the scene's choice of method.

mod cg;
mod contact;
mod dynamics;
mod explicit;
mod friction;
mod implicit;
mod integrator;
mod kind;
mod precond;
mod rk4;
#[cfg(test)]
mod test_systems;

pub use contact::ContactSpring;
pub use dynamics::{Constraints, Dynamics};
pub use explicit::{Euler, ExplicitEuler, SymplecticEuler};
pub use friction::{Friction, STICK_SPEED};
pub use implicit::{Implicit, ImplicitSettings, LinearPath, LinearSolver};
pub use integrator::{Capabilities, Integrator, StepReport};
pub use kind::IntegratorKind;
pub use rk4::Rk4;
