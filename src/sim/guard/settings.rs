//! The guard's settings: what it does when a substep diverges, how deep it may split, and its
//! thresholds.

use serde::{Deserialize, Serialize};
use std::fmt;

/// What to do when a substep diverges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DivergencePolicy {
    /// Redo the substep as two half steps (recursively, up to `max_subdivisions` levels) and report it.
    Subdivide,
    /// Stop with a [`crate::sim::DivergenceError`].
    Stop,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GuardSettings {
    pub policy: DivergencePolicy,
    /// Levels of halving before giving up (2^levels substeps at most per substep).
    pub max_subdivisions: u32,
    /// Levels of halving fast contact may use (at most `max_subdivisions`; none: all of them).
    /// A link that outruns the cloth splits the substep until it moves a third of a spacing
    /// per piece, which for a large jump of a link over fine cloth costs many splits in one
    /// frame. A live node bounds that cost here; the substeps that would have split further
    /// are counted (`StepMetrics::contact_splits_refused`) and reported on `/diagnostics`.
    pub max_contact_split_levels: Option<u32>,
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
            max_contact_split_levels: None,
            max_speed: 500.0,
            energy_growth: 0.5,
        }
    }
}

impl GuardSettings {
    /// How many levels of halving fast contact may split a scene substep into: the guard's, or
    /// fewer when `max_contact_split_levels` bounds what a live node spends on it.
    pub(super) fn split_levels(&self) -> u32 {
        (self.max_contact_split_levels)
            .map_or(self.max_subdivisions, |l| l.min(self.max_subdivisions))
    }
}

impl fmt::Display for DivergencePolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DivergencePolicy::Subdivide => "subdivide",
            DivergencePolicy::Stop => "stop",
        })
    }
}
