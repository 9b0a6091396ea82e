//! Pinch: a vertex between two obstacle surfaces that face each other closer than twice its
//! thickness is centred between them.

use super::contact::Contact;
use super::exit::{exit_of, Exit};
use super::feedback::SolverFeedback;
use super::obstacle::Obstacle;
use crate::Vec3;

/// Contact normals facing each other closer than this cosine (8 degrees off) meet two faces
/// (the pinch's interior), not a face and an edge.
const FACING: f64 = -0.99;

/// The contacts sorted by vertex (contact order kept within a vertex), for the passes that
/// look at all of one vertex's contacts together. A vertex on its way out of an obstacle it
/// started inside is not pressed against that obstacle's surface: its lead-out contact stays
/// out (otherwise a wedge with the palm projects a vertex leaving a finger out of the finger's
/// side at once, stretching its edge to the next finger's vertex far past rest).
pub(super) fn contacts_by_vertex(contacts: &[Contact], exits: &[Exit]) -> Vec<Contact> {
    let mut by_vertex: Vec<Contact> = (contacts.iter())
        .filter(|c| exit_of(exits, c.vertex as usize, c.obstacle).is_none())
        .copied()
        .collect();
    by_vertex.sort_by_key(|c| c.vertex);
    by_vertex
}

/// A vertex touching two obstacles whose surfaces face each other closer than twice its
/// thickness cannot be `thickness` away from both: projected out of one layer after the
/// other, it ended inside the first obstacle's solid, and alternating projections step after
/// step pumped energy into its springs. Put it midway between the two surfaces instead, with
/// the normal velocity of their mean. Returns the centred vertices with their new state and
/// the two obstacles pinching each. A vertex whose squeeze between the two the solver took
/// (`feedback`, pinch springs of the cloth's compliance) beside the surfaces' edges (normals
/// not [`FACING`]) is listed as it is, not centred: the springs balance it in the gap, and
/// the vertex pass kept it out of both solids.
#[allow(clippy::too_many_arguments)]
pub(super) fn center_pinched(
    obstacles: &[Obstacle],
    feedback: &SolverFeedback,
    thickness: &[f64],
    by_vertex: &[Contact],
    x0: &[Vec3],
    x1: &mut [Vec3],
    v1: &mut [Vec3],
    n: usize,
) -> Vec<(usize, Vec3, Vec3, [usize; 2])> {
    let mut pinched = Vec::new();
    for group in by_vertex.chunk_by(|a, b| a.vertex == b.vertex) {
        let i = group[0].vertex as usize;
        if group.len() < 2 || i >= n {
            continue;
        }
        // The most opposed pair of contact normals.
        let mut best: Option<(f64, usize, usize)> = None;
        for a in 0..group.len() {
            for b in a + 1..group.len() {
                let d = group[a].normal.dot(group[b].normal);
                if d < -0.5 && best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, a, b));
                }
            }
        }
        let Some((_, a, b)) = best else { continue };
        let pair = [group[a].obstacle, group[b].obstacle];
        let squeezed = (feedback.squeeze_of(i)).is_some_and(|p| pair.iter().all(|o| p.contains(o)));
        // Squeezed beside the pads' edges (normals tilted towards each other), the vertex is
        // left where the springs put it: centring it along one tilted normal would shove it
        // along the pads.
        if squeezed && group[a].normal.dot(group[b].normal) > FACING {
            pinched.push((i, x1[i], v1[i], pair));
            continue;
        }
        let distance = |k: usize| {
            let o = &obstacles[group[k].obstacle];
            let local = o.pose.inverse_transform_point(x1[i]);
            let hint = o.pose_prev.inverse_transform_point(x0[i]);
            o.closest_local(local, hint).signed_distance
        };
        let (da, db) = (distance(a), distance(b));
        let th = thickness[i];
        if da >= th && db >= th {
            continue;
        }
        // Along a's normal, the surfaces are da below and db above (opposed normals).
        let na = group[a].normal;
        let gap = da + db;
        if gap >= 2.0 * th {
            continue;
        }
        x1[i] += na * (0.5 * gap - da);
        let vs = 0.5 * (group[a].surface_velocity + group[b].surface_velocity).dot(na);
        v1[i] += na * (vs - v1[i].dot(na));
        pinched.push((i, x1[i], v1[i], pair));
    }
    pinched
}

/// Per vertex (of `n`), the two obstacles pinching it (`None`: not pinched): those centred
/// or listed by [`center_pinched`] and those the solver squeezed; empty when no vertex is.
pub(super) fn pinched_by(
    pinched: &[(usize, Vec3, Vec3, [usize; 2])],
    feedback: &SolverFeedback,
    n: usize,
) -> Vec<Option<[usize; 2]>> {
    let squeezed = (0..n).filter_map(|i| feedback.squeeze_of(i).map(|p| (i, p)));
    let mut by = Vec::new();
    for (i, p) in squeezed {
        by.resize(n, None);
        by[i] = Some(p);
    }
    if pinched.is_empty() {
        return by;
    }
    by.resize(n, None);
    for &(i, _, _, obstacles) in pinched {
        if let Some(slot) = by.get_mut(i) {
            *slot = Some(obstacles);
        }
    }
    by
}
