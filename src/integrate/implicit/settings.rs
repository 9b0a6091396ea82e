//! The implicit solver's settings, as a scene file gives them, and its choice of preconditioner.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImplicitSettings {
    /// Relative residual at which conjugate gradients stop.
    pub cg_tolerance: f64,
    pub cg_max_iterations: u32,
    /// Newton iterations follow the linearised solve while a spring stretches more than this
    /// share of its rest length beyond what the linearisation predicts (see
    /// `implicit::newton::unseen_stretch`); the energy check applies besides.
    pub linearisation_tolerance: f64,
}

impl Default for ImplicitSettings {
    fn default() -> Self {
        Self {
            cg_tolerance: 1e-5,
            cg_max_iterations: 200,
            linearisation_tolerance: 0.1,
        }
    }
}

impl ImplicitSettings {
    /// Settings a scene could name: a finite tolerance in (0, 1), a cap of at least one
    /// iteration and a finite positive linearisation tolerance (the scene's validation enforces
    /// the same for files).
    pub fn is_usable(&self) -> bool {
        self.cg_tolerance.is_finite()
            && self.cg_tolerance > 0.0
            && self.cg_tolerance < 1.0
            && self.cg_max_iterations >= 1
            && self.linearisation_tolerance.is_finite()
            && self.linearisation_tolerance > 0.0
    }
}

/// Which `M^-1` the conjugate gradient uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preconditioner {
    BlockJacobi,
    /// Smoothed-aggregation multigrid, falling back to block Jacobi when its setup fails.
    Multigrid,
}

/// How the implicit step solves its linear systems (`solver.linear` in a scene file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolver {
    /// The cheaper of the two for the cloth, from the costs its first solves measure (see
    /// `implicit::path`).
    Auto,
    /// Conjugate gradients preconditioned by the multigrid hierarchy: the default, the cheaper
    /// path on every benchmark scene but the smallest (`cargo bench --bench contact`).
    #[default]
    Pcg,
    /// A sparse Cholesky factorisation of the filtered system per changed matrix.
    Direct,
}

impl LinearSolver {
    pub fn name(self) -> &'static str {
        match self {
            LinearSolver::Auto => "auto",
            LinearSolver::Pcg => "pcg",
            LinearSolver::Direct => "direct",
        }
    }
}

/// The linear path a step ran (what `auto` chose, or what the scene asked for).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LinearPath {
    #[default]
    Pcg,
    Direct,
}

impl LinearPath {
    pub fn name(self) -> &'static str {
        match self {
            LinearPath::Pcg => "pcg",
            LinearPath::Direct => "direct",
        }
    }
}
