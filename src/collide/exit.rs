//! A vertex on its way out of an obstacle it started inside: the plan `overlap.rs` makes at
//! build, which the vertex pass follows and the feature passes step aside for.

use crate::Vec3;

/// One vertex that started inside a solid obstacle (or in its contact layer, on the rim of a
/// patch inside), and how it leaves: along `dir` (unit, in the obstacle's frame, so it turns
/// with the obstacle) by at most `cap` per collision pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Exit {
    pub vertex: u32,
    pub obstacle: u32,
    pub dir: Vec3,
    pub cap: f64,
    /// Out of the solid, but a mesh edge of it still cuts through: it goes on out along `dir`.
    pub edge_inside: bool,
    /// Its mesh neighbours: `CollisionStage::exit_neighbours[first..first + count]`.
    pub first: u32,
    pub count: u32,
}

/// Whether `vertex` is on its way out of any obstacle (`exits` sorted by vertex).
pub(crate) fn is_exiting(exits: &[Exit], vertex: usize) -> bool {
    !exits.is_empty()
        && (exits.binary_search_by_key(&(vertex as u32, 0), |e| (e.vertex, 0))).is_ok()
}

/// How vertex `vertex` leaves obstacle `obstacle` (`exits` sorted by vertex, then obstacle),
/// while it is still on its way out.
pub(crate) fn exit_of(exits: &[Exit], vertex: usize, obstacle: usize) -> Option<&Exit> {
    if exits.is_empty() {
        return None;
    }
    let key = (vertex as u32, obstacle as u32);
    (exits.binary_search_by_key(&key, |e| (e.vertex, e.obstacle)))
        .ok()
        .map(|k| &exits[k])
}
