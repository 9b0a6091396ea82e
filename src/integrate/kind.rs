//! The integrator a scene file names, and the method it builds.

use super::explicit::{ExplicitEuler, SymplecticEuler};
use super::implicit::{Implicit, ImplicitSettings, LinearSolver};
use super::integrator::Integrator;
use super::rk4::Rk4;
use serde::{Deserialize, Serialize};

/// Integrator choice in a scene file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorKind {
    ExplicitEuler,
    SymplecticEuler,
    Rk4,
    Implicit,
}

impl IntegratorKind {
    pub const ALL: [IntegratorKind; 4] = [
        IntegratorKind::ExplicitEuler,
        IntegratorKind::SymplecticEuler,
        IntegratorKind::Rk4,
        IntegratorKind::Implicit,
    ];

    pub fn build(self, implicit: ImplicitSettings) -> Box<dyn Integrator> {
        self.build_with(implicit, LinearSolver::default())
    }

    /// [`Self::build`] with the implicit step's linear path (`solver.linear`; the explicit
    /// methods solve no linear system and ignore it). `auto` and the default `pcg` yield to the
    /// environment's `DRAPE_LINEAR` (`pcg` or `direct`), which runs a test suite on one path
    /// throughout.
    pub fn build_with(
        self,
        implicit: ImplicitSettings,
        linear: LinearSolver,
    ) -> Box<dyn Integrator> {
        let linear = match (linear, std::env::var("DRAPE_LINEAR").as_deref()) {
            (LinearSolver::Auto, Ok("pcg")) => LinearSolver::Pcg,
            (LinearSolver::Auto | LinearSolver::Pcg, Ok("direct")) => LinearSolver::Direct,
            _ => linear,
        };
        match self {
            IntegratorKind::ExplicitEuler => Box::new(ExplicitEuler::default()),
            IntegratorKind::SymplecticEuler => Box::new(SymplecticEuler::default()),
            IntegratorKind::Rk4 => Box::new(Rk4::default()),
            IntegratorKind::Implicit => Box::new(Implicit::with_linear(implicit, linear)),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::ExplicitEuler => "explicit_euler",
            IntegratorKind::SymplecticEuler => "symplectic_euler",
            IntegratorKind::Rk4 => "rk4",
            IntegratorKind::Implicit => "implicit",
        }
    }
}
