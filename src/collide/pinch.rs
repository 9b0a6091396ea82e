//! Pinch: a vertex between two obstacle surfaces that face each other closer than twice its
//! thickness is centred between them.

use super::contact::Contact;
use super::exit::{exit_of, Exit};
use super::obstacle::Obstacle;
use crate::Vec3;

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
/// the normal velocity of their mean. Returns the centred vertices with their new state.
pub(super) fn center_pinched(
    obstacles: &[Obstacle],
    thickness: &[f64],
    by_vertex: &[Contact],
    x0: &[Vec3],
    x1: &mut [Vec3],
    v1: &mut [Vec3],
    n: usize,
) -> Vec<(usize, Vec3, Vec3)> {
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
        pinched.push((i, x1[i], v1[i]));
    }
    pinched
}
