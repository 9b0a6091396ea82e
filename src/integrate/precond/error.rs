//! Why a multigrid hierarchy could not be built.

use thiserror::Error;

/// Why a hierarchy could not be built; the caller falls back to block Jacobi.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MultigridError {
    #[error("level {level}: row {row} has no diagonal block")]
    MissingDiagonal { level: usize, row: usize },
    #[error("level {level}: diagonal block of row {row} is singular or not finite")]
    SingularDiagonal { level: usize, row: usize },
    #[error("coarsest matrix ({rows} unknowns) is not positive definite at pivot {pivot}")]
    CoarseNotPositive { rows: usize, pivot: usize },
    #[error("empty system")]
    Empty,
}
