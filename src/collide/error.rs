//! Errors of building a collision stage.

#[derive(Debug, thiserror::Error)]
pub enum StageError {
    #[error("triangle {tri} references vertex {vertex} but the cloth has {n} vertices")]
    BadTriangle { tri: usize, vertex: u32, n: usize },
    #[error("{what} has {got} entries, expected one per vertex ({n})")]
    BadLength {
        what: &'static str,
        got: usize,
        n: usize,
    },
    #[error("{what}[{index}] = {value} must be finite and >= 0")]
    BadValue {
        what: &'static str,
        index: usize,
        value: f64,
    },
}
