//! Force terms, each its own unit. A scene names the effects it wants; only those are built,
//! so an effect a scene does not name costs nothing in the step (there is no `if enabled` anywhere).
//!
//! Every effect gives forces and, where the implicit solver needs them, analytic force Jacobians
//! `df/dx` and `df/dv` over the sparsity pattern it declares. `effect.rs` holds the trait,
//! `set.rs` the scene's set of effects, `cache.rs` the forces kept from the energy pass.

mod cache;
mod damping;
mod effect;
mod gravity;
pub mod plan;
mod set;
mod springs;
mod stencils;
mod wind;

pub use damping::{AirDrag, SpringDamping, VelocityDiffusion};
pub use effect::{Effect, State, StiffnessBound};
pub use gravity::Gravity;
pub use plan::{EffectKind, EffectPlan, Elements, Lattice, WindPlan};
pub use set::EffectSet;
pub use springs::{Knee, Springs};
pub use stencils::{Bending, StencilSet, Twist};
pub use wind::{Gust, Wind, WindKey};
