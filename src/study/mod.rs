//! `drape dev study`: what accuracy costs in time. Runs fixed reference scenes across the accuracy
//! knobs (integrator, step, CG tolerance and cap, resolution), measures cost and error against a
//! cached fine-step RK4 reference, and writes `runs.csv`, `summary.md` and SVG plots.
//!
//! Files: [`plan`] (what to run), [`scenes`] (the reference scenes), [`run`] (one timed run),
//! [`reference`] (cached fine-step references), [`sweep`] (the whole study, [`run_study`]),
//! [`record`] (what is measured), [`analysis`] (fits, Pareto fronts), `csv`, `summary` and `plots`
//! (the outputs, sharing `format`), [`error`]. This file only declares and re-exports.

pub mod analysis;
mod csv;
pub mod error;
mod format;
pub mod plan;
mod plots;
pub mod record;
pub mod reference;
pub mod run;
pub mod scenes;
mod summary;
pub mod sweep;

pub use error::StudyError;
pub use plan::{Plan, PlannedRun};
pub use record::{RunRecord, StudyResult};
pub use run::{Horizon, RunSettings};
pub use scenes::StudyScene;
pub use sweep::run_study;
