//! The simulation: `Simulation::step` as a table of contents of named stages (`step`) over a
//! substep's `span`, what the simulation holds and what the outside may change between steps
//! (`simulation`), the model and the work kept beside the state (`model`), moving frames
//! (`frames`), the solver–collision coupling both ways (`coupling`) with the impact front a
//! link's drag sends (`front`), the divergence guard with every redo decision (`guard`; the
//! geometry of fast contact `fast`, the strain bound `strain`, its vertex pass `scan`, its
//! error `error`), the strain limit (`limit`), energies (`energy`) and metrics (`metrics`).

mod coupling;
mod energy;
mod error;
mod fast;
mod frames;
mod front;
mod guard;
mod limit;
mod metrics;
mod model;
mod scan;
mod simulation;
mod span;
mod step;
mod strain;

pub use error::{Cause, DivergenceError, Symptom};
pub use frames::{FrameScript, Frames};
pub use guard::{DivergencePolicy, GuardSettings};
pub use metrics::StepMetrics;
pub use model::StepSettings;
pub use simulation::Simulation;
