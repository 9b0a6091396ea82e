//! The answer to one feature contact: the cloth point pushed out along the normal by the
//! minimal-mass-weighted displacement, each moving vertex's approaching velocity removed with
//! Coulomb friction.

use super::contact::{ClothState, FeatureContact, Hit, DEEP};
use crate::collide::exit::slips;
use crate::collide::obstacle::Obstacle;
use crate::Vec3;

/// The end gap is set to `eta (1 + PUSH_SLACK)` so the next pass (tolerance `1e-6 eta`) does
/// not see the same contact again.
const PUSH_SLACK: f64 = 1e-3;

/// How much of the contact point's depth in the layer its held (kinematic) vertices put there:
/// `sum w_k (eta - gap_k)` over the held vertices inside the layer. The robot or the script
/// placed them, so it is the scene's motion, not the cloth's to answer: the free vertices are
/// pushed only out of their own part of the depth. Answered whole, the free end of an edge held
/// at its other end would move by the held end's depth over its own weight, a lever without
/// bound (a towel held at a gripper that the elbow folds onto: 2 mm of depth at a weight of 0.1
/// flung the free vertex 2 cm in one pass, at any step size).
fn held_depth(
    hit: &Hit,
    idx: &[usize; 3],
    im: &[f64; 3],
    x1: &[Vec3],
    n: Vec3,
    f_end: Vec3,
    eta: f64,
) -> f64 {
    (0..3)
        .filter(|&k| hit.w[k] != 0.0 && im[k] == 0.0 && !(k == 2 && idx[2] == idx[1]))
        .map(|k| hit.w[k] * (eta - n.dot(x1[idx[k]] - f_end)).max(0.0))
        .sum()
}

/// Answers one contact. `None` when it cannot move (all kinematic), else whether positions moved.
#[allow(clippy::too_many_arguments)]
pub(super) fn respond(
    o: &Obstacle,
    obstacle: usize,
    radius: f64,
    hit: &Hit,
    s: &ClothState,
    (x1, v1): (&mut [Vec3], &mut [Vec3]),
    touched: &mut [bool],
    contacts: &mut Vec<FeatureContact>,
) -> Option<bool> {
    let idx = hit.verts.map(|v| v as usize);
    let im = idx.map(|i| s.inv_mass[i].max(0.0));
    // A repeated vertex (edge hits use slot 2 with weight 0) must count once.
    let denom: f64 = (0..3).map(|k| hit.w[k] * hit.w[k] * im[k]).sum();
    if !(denom > 0.0 && denom.is_finite()) {
        return None;
    }
    let th = idx.iter().map(|&i| s.thickness[i]).fold(0.0, f64::max);
    let eta = radius + th;
    let n = hit.normal;
    let f_end = o.pose.transform_point(hit.local);
    let vs = if s.h > 0.0 {
        (f_end - o.pose_prev.transform_point(hit.local)) / s.h
    } else {
        Vec3::ZERO
    };
    let c: Vec3 = (0..3).map(|k| x1[idx[k]] * hit.w[k]).sum();
    let gap = n.dot(c - f_end);
    let beside_lead_out = (0..3).any(|k| hit.w[k] > 0.0 && slips(s.slip, idx[k], obstacle));
    let mu = if beside_lead_out {
        0.0
    } else {
        o.friction
            .unwrap_or_else(|| (0..3).map(|k| hit.w[k] * s.friction[idx[k]]).sum::<f64>())
    };
    // Every feature contact is handed to the solver (a moving obstacle's too: answered only
    // here, by position after the solve, the cloth it carries would lag a whole substep of its
    // motion behind it every substep, and that push would be a strain the solver never sees).
    let moving = o.pose_prev != o.pose;
    contacts.push(FeatureContact {
        verts: hit.verts,
        weights: hit.w,
        normal: n,
        point: f_end,
        gap: eta,
        mu: if moving { 0.0 } else { mu },
        obstacle,
        moving,
        local: hit.local,
        local_normal: o.pose.rotation.inverse() * n,
        end_point: f_end,
        end_normal: n,
    });
    if s.sprung.binary_search(&hit.verts).is_ok() && gap >= DEEP * eta {
        return Some(false);
    }
    let held = held_depth(hit, &idx, &im, x1, n, f_end, eta);
    let target = eta * (1.0 + PUSH_SLACK) - held;
    let mut moved = false;
    if gap < eta - held {
        let impulse = (target - gap) / denom;
        for k in 0..3 {
            if hit.w[k] != 0.0 {
                x1[idx[k]] += n * (hit.w[k] * im[k] * impulse);
                touched[idx[k]] = true;
            }
        }
        moved = true;
    }
    // Velocities per vertex, not through `c`: several cloth edges and faces around one vertex
    // touch the same feature at once (a strap over a box edge: the edge along the strap and the
    // diagonal), and distributing each contact's impulse over its vertices in turn over-corrects
    // the shared vertex, which leaves the step moving away from the feature while its
    // neighbours still approach it. That velocity, undone by the next step's push, never
    // decays, even at rest. Removing each moving vertex's own approaching
    // velocity is idempotent (a second contact with the same normal changes nothing), leaves
    // `c` not approaching, and is exact Coulomb friction per vertex.
    for k in 0..3 {
        if hit.w[k] == 0.0 || im[k] == 0.0 || (k == 2 && idx[2] == idx[1]) {
            continue;
        }
        let rel = v1[idx[k]] - vs;
        let vn = rel.dot(n);
        if vn >= 0.0 {
            continue;
        }
        let i = idx[k];
        let solved = s
            .friction_solved
            .get(i)
            .is_some_and(|fs| fs.iter().any(|sn| *sn != Vec3::ZERO && sn.dot(n) > 0.9));
        let dvn = -vn;
        let vt = rel - n * vn;
        let vt_len = vt.length();
        let mu_dvn = if solved { 0.0 } else { mu * dvn };
        let vt_new = if solved {
            vt
        } else if vt_len <= mu_dvn {
            Vec3::ZERO
        } else {
            vt * (1.0 - mu_dvn / vt_len)
        };
        v1[idx[k]] += n * dvn + (vt_new - vt);
        touched[idx[k]] = true;
    }
    Some(moved)
}
