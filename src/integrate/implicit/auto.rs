//! What the `auto` linear path remembers between steps (see `path`).

/// What `auto` knows: the PCG counts of the current step, the steps the direct path was
/// predicted cheaper in a row, and the pattern it moved to the direct path for.
#[derive(Debug, Default)]
pub(super) struct AutoPath {
    pub(super) iterations: u32,
    pub(super) solves: u32,
    pub(super) cheaper: u32,
    pub(super) direct_for: Option<u64>,
}
