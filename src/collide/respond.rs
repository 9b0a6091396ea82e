//! Obstacle contact response for one vertex: detection (swept or discrete), positional
//! correction, and the impulse form of Coulomb friction.
//!
//! Friction: the normal impulse per unit mass is the approaching normal velocity removed,
//! `dv_n`. The tangential velocity relative to the surface, `v_t`, is zeroed if
//! `|v_t| <= mu dv_n` (static) and otherwise shortened by `mu dv_n` (kinetic). Under gravity on a
//! plane tilted by `a`, `dv_n = g cos(a) h` and `v_t` grows by `g sin(a) h` per step, so a
//! particle at rest sticks iff `tan(a) <= mu` and a sliding one accelerates at
//! `g (sin a - mu cos a)`: exactly Coulomb's law, integrated over the step. The end point moves
//! by the velocity change over the part of the step in contact (`contact_share`): a vertex
//! that arrives mid-step sticks where it hit.

use super::contact::Contact;
use super::feedback::Held;
use super::obstacle::Obstacle;
use super::settings::{DetectionMode, ResponseMode};
use crate::Vec3;

/// A vertex within `th (1 + REST_BAND)` of an obstacle is in contact without being pushed. The
/// implicit solver's filter holds a contact vertex's normal velocity at the surface's, so it ends
/// the step exactly `th` away (up to rounding): with a strict `< th` test that contact would be
/// dropped, the next step run unconstrained (falling into the layer), the one after constrained
/// again, and so on, every other step without the filter and alternating with the vertices
/// around it: a jitter of resting cloth. The band (6 um at 6 mm) is far above rounding and far
/// below any visible gap.
const REST_BAND: f64 = 1e-3;

pub(crate) struct VertexInput {
    pub vertex: u32,
    pub x0: Vec3,
    pub thickness: f64,
    pub friction: f64,
    pub h: f64,
    pub mode: DetectionMode,
    pub response: ResponseMode,
    /// (world normal, normal velocity change) the implicit filter applied to this vertex this
    /// step, one per held surface (zero when not held): the one along this contact's normal
    /// counts in its friction bound.
    pub held: Held,
    /// Normals of the surfaces whose friction the solver applied already (zero: unused): their
    /// contacts keep the tangential velocity it left.
    pub friction_solved: [Vec3; 3],
    /// (direction in the obstacle's frame, most it moves per pass, whether it is out but an
    /// edge of it still cuts the solid) when the vertex started inside this obstacle and is on
    /// its way out (`overlap.rs`).
    pub exit: Option<(Vec3, f64, bool)>,
    /// Whether the solver squeezed the vertex between this obstacle and another with pinch
    /// springs (see [`super::SolverFeedback::squeeze`]).
    pub squeezed: bool,
}

/// Detects and answers one vertex against one obstacle, updating `x` (end position) and `v`.
pub(crate) fn obstacle_vertex(
    o: &Obstacle,
    obstacle: usize,
    inp: &VertexInput,
    x: &mut Vec3,
    v: &mut Vec3,
) -> Option<Contact> {
    let th = inp.thickness;
    let a = o.pose_prev.inverse_transform_point(inp.x0);
    let mut p = o.pose.inverse_transform_point(*x);
    let p_solved = p;
    if let Some((dir, cap, edge_inside)) = inp.exit {
        // Out of the solid it goes on while an edge of it cuts the solid, or while it is inside
        // the contact layer: there the patch's way out, not the nearest face, sets its path.
        let step = match o.exit_along(p, dir) {
            Some(depth) => Some((depth + th).min(cap)),
            None if edge_inside => Some(cap),
            None => o.layer_step(p, dir, th).map(|gap| gap.min(cap)),
        };
        if let Some(step) = step {
            return Some(lead_out(o, obstacle, inp, dir, step, p, x, v));
        }
    }
    // (local contact point, local normal) of the last correction.
    let mut contact: Option<(Vec3, Vec3)> = None;
    // How far from the surface the vertex is pushed: out of the contact layer, or, squeezed
    // by a pinch, out of the solid only (its depth in the layer is the cloth's compression,
    // which the pinch's springs answer; pushed out of it, cloth sliding into a gripper would
    // stop dead at the pads' edges).
    let push = if inp.squeezed { 0.0 } else { th };

    if inp.mode == DetectionMode::Continuous && !o.contains_local(a) {
        // Path in the obstacle frame: start in the pose_prev frame, end in the pose frame.
        if let Some(hit) = o.cast_local(a, p) {
            // Put the end point back on the hit face's side, `th` above its tangent plane.
            let gap = hit.normal.dot(p - hit.point);
            if gap < push {
                p += hit.normal * (push - gap);
            }
            contact = Some((hit.point, hit.normal));
        }
    }
    // Discrete proximity at the end (also catches starts inside and curved faces after a hit).
    if let Some(sp) = o.closest_local_within(p, a, th * (1.0 + REST_BAND)) {
        if sp.signed_distance < push {
            p += sp.normal * (push - sp.signed_distance);
            contact = Some((sp.point, sp.normal));
        } else if contact.is_none() && sp.signed_distance < th * (1.0 + REST_BAND) {
            // Resting exactly at `th` (where the last push or the implicit filter left it): still
            // a contact, so the filter keeps holding it next step (see `REST_BAND`).
            contact = Some((sp.point, sp.normal));
        }
    }
    let (q, n_local) = contact?;

    let h = inp.h;
    let n = o.pose.transform_vector(n_local);
    let surface_velocity = if h > 0.0 {
        (o.pose.transform_point(q) - o.pose_prev.transform_point(q)) / h
    } else {
        Vec3::ZERO
    };
    *x = o.pose.transform_point(p);
    let contact = Contact {
        vertex: inp.vertex,
        normal: n,
        surface_velocity,
        obstacle,
    };
    if inp.squeezed {
        // The solve set its velocity (springs and friction of the squeeze); only one pushed
        // out of the solid loses its approaching velocity.
        if p != p_solved {
            let vn = (*v - surface_velocity).dot(n);
            *v -= n * vn.min(0.0);
        }
        return Some(contact);
    }

    let rel = *v - surface_velocity;
    let vn = rel.dot(n);
    let dvn = (-vn).max(0.0);
    let vt = rel - n * vn;
    let vt_len = vt.length();
    let held = inp
        .held
        .iter()
        .map(|(hn, dv)| dv * hn.dot(n).max(0.0))
        .fold(0.0, f64::max);
    let mu_dvn = inp.friction * (dvn + held);
    // Cosine above which a contact normal is one of the held surfaces.
    const SAME_SURFACE: f64 = 0.9;
    let solved = inp
        .friction_solved
        .iter()
        .any(|sn| *sn != Vec3::ZERO && sn.dot(n) > SAME_SURFACE);
    let vt_new = if solved {
        vt
    } else if vt_len <= mu_dvn {
        Vec3::ZERO
    } else {
        vt * (1.0 - mu_dvn / vt_len)
    };
    *v = surface_velocity + vt_new + n * vn.max(0.0);
    if inp.response.projects_tangent() {
        // Friction acted during the part of the step in contact: move the end point by that.
        let share = contact_share(a, p_solved, q, n_local, th);
        *x += (vt_new - vt) * (h * share);
    }
    Some(contact)
}

/// The share of the step a vertex spent in contact, moving from `a` to `p` (local) against the
/// tangent plane at `q` with normal `n`: 1 when it started within the contact layer `th`, else
/// the part of its path after it entered the layer. The friction of a vertex that arrived
/// during the step acts only from then on; undoing the whole step's tangential motion would put
/// a vertex landing on a slope back up it, where its free fall started, and on the contact
/// bench's S1 (a cloth dropped on a sphere, friction 0.5) would pull the vertices reaching the
/// sphere's rim inwards by a good part of a spacing while their neighbours fall on, stretching
/// their edges and splitting the landing into many more substeps (`sim/fast.rs`, `jumped`).
fn contact_share(a: Vec3, p: Vec3, q: Vec3, n: Vec3, th: f64) -> f64 {
    let (d0, d1) = (n.dot(a - q), n.dot(p - q));
    if d0 > th && d1 < d0 {
        (1.0 - (d0 - th) / (d0 - d1)).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// A vertex that started inside `o`, moved `step` along `dir` (local) on its way out: a push by
/// position that adds no speed, with the approaching normal velocity removed so the next solve
/// holds it against going back in. No friction: it slides out along the plan.
#[allow(clippy::too_many_arguments)]
fn lead_out(
    o: &Obstacle,
    obstacle: usize,
    inp: &VertexInput,
    dir: Vec3,
    step: f64,
    p: Vec3,
    x: &mut Vec3,
    v: &mut Vec3,
) -> Contact {
    let p = p + dir * step;
    *x = o.pose.transform_point(p);
    let n = o.pose.transform_vector(dir);
    let surface_velocity = if inp.h > 0.0 {
        (*x - o.pose_prev.transform_point(p)) / inp.h
    } else {
        Vec3::ZERO
    };
    let rel = *v - surface_velocity;
    let vn = rel.dot(n);
    *v -= n * vn.min(0.0);
    Contact {
        vertex: inp.vertex,
        normal: n,
        surface_velocity,
        obstacle,
    }
}
