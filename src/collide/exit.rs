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

/// The (vertex, obstacle) pairs that slide without friction while `exits` lead cloth out of the
/// obstacle: the mesh neighbours (`neighbours`, see [`Exit::first`]) of exiting vertices that
/// are not on their way out of it themselves, sorted and without repeats, into `out`.
///
/// Why: the lead-out moves a patch that should never have been inside; friction against the
/// solid it leaves is no physics of that motion. A vertex beside drape_bot's forearm, pulled
/// into it by a neighbour rising out of it, is pushed back each substep, and its friction, a
/// half of that push, would hold it while the neighbour rises: like a rope round a capstan
/// their edge would grow far past rest. The exiting vertices keep their friction: without it
/// the hem of a cape led up out of drape_bot's base slides sideways in the box, and the cape
/// above, pushed up flat, buckles in one frame.
pub(crate) fn slip_around(exits: &[Exit], neighbours: &[u32], out: &mut Vec<(u32, u32)>) {
    out.clear();
    for e in exits {
        let around = &neighbours[e.first as usize..(e.first + e.count) as usize];
        out.extend(around.iter().map(|&w| (w, e.obstacle)));
    }
    out.sort_unstable();
    out.dedup();
    out.retain(|&(v, o)| exit_of(exits, v as usize, o as usize).is_none());
}

/// Whether `vertex` slides without friction on `obstacle` (`slip` from [`slip_around`]).
pub(crate) fn slips(slip: &[(u32, u32)], vertex: usize, obstacle: usize) -> bool {
    !slip.is_empty()
        && slip
            .binary_search(&(vertex as u32, obstacle as u32))
            .is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exit(vertex: u32, obstacle: u32, first: u32, count: u32) -> Exit {
        Exit {
            vertex,
            obstacle,
            dir: Vec3::Z,
            cap: 1e-3,
            edge_inside: false,
            first,
            count,
        }
    }

    /// A row 0-1-2-3 with 1 and 2 leaving obstacle 0 and 2 also obstacle 1: their neighbours
    /// that stay (0 and 3 for obstacle 0; 1 and 3 for obstacle 1, where 1 is not leaving)
    /// slide, each pair once; the leaving vertices keep their friction on what they leave.
    #[test]
    fn the_neighbours_that_stay_slide_and_the_leaving_vertices_do_not() {
        let neighbours = [0, 2, 1, 3];
        let exits = [exit(1, 0, 0, 2), exit(2, 0, 2, 2), exit(2, 1, 2, 2)];
        let mut slip = Vec::new();
        slip_around(&exits, &neighbours, &mut slip);
        assert_eq!(slip, vec![(0, 0), (1, 1), (3, 0), (3, 1)]);
        assert!(slips(&slip, 3, 1) && !slips(&slip, 2, 0) && !slips(&slip, 1, 0));
        slip_around(&[], &neighbours, &mut slip);
        assert!(slip.is_empty() && !slips(&slip, 0, 0));
    }
}
