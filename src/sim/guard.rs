//! The divergence guard: every substep checks the integrator's output for non-finite values,
//! runaway energy and impossible speeds, and names the likely culprit when it fails.

use crate::effects::StiffnessBound;
use serde::{Deserialize, Serialize};
use std::fmt;

/// What to do when a substep diverges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DivergencePolicy {
    /// Redo the substep as two half steps (recursively, up to `max_subdivisions` levels) and report it.
    Subdivide,
    /// Stop with a [`DivergenceError`].
    Stop,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GuardSettings {
    pub policy: DivergencePolicy,
    /// Levels of halving before giving up (2^levels substeps at most per substep).
    pub max_subdivisions: u32,
    /// Fastest plausible vertex speed (m/s); anything faster is treated as a blow-up.
    pub max_speed: f64,
    /// Allowed growth of kinetic + elastic energy in one substep beyond the work of gravity, wind
    /// and moving attachments, relative to the energy at the start of the substep.
    pub energy_growth: f64,
}

impl Default for GuardSettings {
    fn default() -> Self {
        Self {
            policy: DivergencePolicy::Subdivide,
            max_subdivisions: 8,
            max_speed: 500.0,
            energy_growth: 0.5,
        }
    }
}

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

impl fmt::Display for DivergencePolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DivergencePolicy::Subdivide => "subdivide",
            DivergencePolicy::Stop => "stop",
        })
    }
}
