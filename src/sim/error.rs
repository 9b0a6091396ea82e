//! The error of a simulation that diverged: what the guard measured, where, and (when the
//! stability bound says so) which effect is the cause.

use crate::effects::StiffnessBound;
use std::fmt;

/// Why a substep was rejected.
#[derive(Debug, Clone, PartialEq)]
pub enum Symptom {
    NonFinite,
    Speed(f64),
    /// Energy gained beyond the external work, in joules.
    EnergyGain {
        gained: f64,
        allowed: f64,
    },
}

/// A simulation that diverged and could not be rescued by the policy.
#[derive(Debug, Clone, PartialEq)]
pub struct DivergenceError {
    pub time: f64,
    pub step: f64,
    pub cloth: String,
    /// Vertex index within its cloth piece.
    pub vertex: usize,
    pub symptom: Symptom,
    pub integrator: &'static str,
    /// The stiffest elastic effect, with `h * omega` for the failed step.
    pub suspect: Option<(StiffnessBound, f64)>,
    pub stability_limit: Option<f64>,
}

impl fmt::Display for DivergenceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "cloth '{}' diverged at t = {:.4} s (step {:.3e} s, {}): vertex {} ",
            self.cloth, self.time, self.step, self.integrator, self.vertex
        )?;
        match &self.symptom {
            Symptom::NonFinite => write!(f, "has a non-finite position or velocity")?,
            Symptom::Speed(s) => write!(f, "moves at {s:.3e} m/s")?,
            Symptom::EnergyGain { gained, allowed } => write!(
                f,
                "is where energy runs away ({gained:.3e} J gained in one step, {allowed:.3e} J explained)"
            )?,
        }
        if let Some((b, h_omega)) = &self.suspect {
            write!(
                f,
                "; likely cause: {} (h*omega = {:.3}",
                b.parameter, h_omega
            )?;
            if let Some(limit) = self.stability_limit {
                write!(
                    f,
                    ", stability limit of {} is {:.3}",
                    self.integrator, limit
                )?;
            }
            write!(
                f,
                "): lower dt, raise solver.substeps or soften {}",
                b.parameter
            )?;
            if self.integrator != "implicit" {
                write!(f, ", or use the implicit integrator")?;
            }
        }
        Ok(())
    }
}

impl std::error::Error for DivergenceError {}
