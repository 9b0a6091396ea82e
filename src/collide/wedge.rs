//! Wedge: a vertex in contact with two or more obstacles that do not pinch it is pushed out of
//! their layers by alternating projections.

use super::contact::Contact;
use super::obstacle::Obstacle;
use crate::Vec3;

/// A vertex in contact with two or more obstacles and not pinched between them (a wedge:
/// cloth pressed by a robot's hand against its torso) is pushed out of one layer after
/// the other, in obstacle order: leaving the last one along its normal can carry it back into
/// an earlier one, whose solid it then ends inside. Alternating projections onto the layers
/// converge to their intersection (each round shrinks the remaining depth by the cosine of
/// the wedge's normals); approaching normal velocity is removed for each surface on the way.
#[allow(clippy::too_many_arguments)]
pub(super) fn separate_wedged(
    obstacles: &[Obstacle],
    thickness: &[f64],
    by_vertex: &[Contact],
    x0: &[Vec3],
    x1: &mut [Vec3],
    v1: &mut [Vec3],
    n: usize,
    pinched: &[(usize, Vec3, Vec3, [usize; 2])],
) {
    const ROUNDS: usize = 8;
    for group in by_vertex.chunk_by(|a, b| a.vertex == b.vertex) {
        let i = group[0].vertex as usize;
        // A pinched vertex (facing surfaces closer than two thicknesses) cannot leave both
        // layers: `center_pinched` put it midway.
        if group.len() < 2 || i >= n || pinched.iter().any(|p| p.0 == i) {
            continue;
        }
        let th = thickness[i];
        for _ in 0..ROUNDS {
            let mut moved = false;
            for &Contact {
                obstacle: oi,
                surface_velocity,
                ..
            } in group
            {
                let o = &obstacles[oi];
                let local = o.pose.inverse_transform_point(x1[i]);
                let hint = o.pose_prev.inverse_transform_point(x0[i]);
                let sp = o.closest_local(local, hint);
                // Rounding-level depths are left alone (the rounds would never end).
                let inside = sp.signed_distance < th * (1.0 - 1e-6);
                if !inside {
                    continue;
                }
                let normal = o.pose.transform_vector(sp.normal);
                x1[i] += normal * (th - sp.signed_distance);
                let vn = (v1[i] - surface_velocity).dot(normal);
                if vn < 0.0 {
                    v1[i] -= normal * vn;
                }
                moved = true;
            }
            if !moved {
                break;
            }
        }
    }
}
