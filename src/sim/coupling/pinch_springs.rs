//! Cloth squeezed between two obstacle surfaces (finger pads, a link folding onto another,
//! cloth pressed between a gripper and a table): each side presses the cloth with a spring of
//! its through-thickness compliance and rubs it with Coulomb friction against that side's
//! normal force, both sides in the same solve.
//!
//! A vertex touching two surfaces that face each other closer than its two contact layers
//! (`2 thickness`, the cloth's thickness in a pinch) cannot keep `thickness` from both. Held by
//! the filter it would be a rigid constraint with no normal force of its own, and friction
//! would have nothing to grip with. Here each side is a one-sided [`ContactSpring`] on the vertex: depth
//! `d = thickness - distance` into that side's layer, force `E A f d / thickness` (the half of
//! the cloth on that side compressed by `d`; `E` the material's `compressive_modulus`, `A` the
//! vertex's area, `f` the share of its cell between the two faces), aimed at where the surface
//! is at the substep's end. Its Jacobian enters backward Euler like the cloth's springs; the
//! two sides balance at the middle of the gap, where each presses with
//! `N = E A f (1 - gap / (2 thickness))`. Friction is one drag per side in that side's tangent
//! plane towards the surface's velocity, with the limit `mu N` of the start depth (see
//! [`crate::integrate::friction`]): it sticks while the load stays under `mu (N_a + N_b)` and
//! slides with Coulomb's force above; where the two sides carry the cloth together (pads on one
//! hand), one side's drags stick or slide as one patch, on their summed load and limit (see
//! [`Friction::patch`]). The vertex is not held by the filter; the collision stage,
//! told which vertices the solve squeezed ([`crate::collide::SolverFeedback::squeeze`]),
//! centres those between two faces as it centres any pinch, keeps those beside the pads' edges
//! out of the two solids rather than out of their layers (so none ends inside either side),
//! leaves their tangential velocity to the solve, and its feature passes skip their faces.
//!
//! The share `f` keeps the grip continuous as cloth slides through: a vertex stands for a cell
//! of its mesh spacing, and counted whole from the moment it enters the gap a sliding strip's
//! grip would jump by a whole column of cells at each entry (a quarter of a 2 cm pad's grip
//! at 5 mm spacing: the strip would stick again just above the threshold). The cell's share between the
//! faces is sampled along two tangent lines (each side's closest point a face facing the
//! other's, both distances at most the cloth's thickness), and the mesh neighbours of the
//! pinched vertices that touch neither side themselves (their cell reaching under the pads'
//! edges) are pinched by their share too.

use super::{Coupling, Pinch, StartState};
use crate::collide::CollisionStage;
use crate::integrate::{ContactSpring, Friction};
use crate::{Pose, Vec3};

/// Contact normals facing each other closer than this cosine (120 degrees) pinch the vertex
/// (the collision stage's pinch and `HeldNormals` use the same test).
const PINCH_COSINE: f64 = -0.5;

/// A sample of a cell is between the two faces when their normals there face each other this
/// closely (8 degrees off): beside a box's edge the closest points are on the edge, whose
/// normals tilt, and the cloth there is not squeezed by the faces.
const FACING_COSINE: f64 = -0.99;

/// Samples along each of the cell's two tangent lines.
const SAMPLES: usize = 16;

/// One side of a pinch: its plane (the mean of the covered samples' closest points and
/// normals) now and at the substep's end.
struct Side {
    obstacle: usize,
    /// Distance of the vertex from the side's plane now (m).
    distance: f64,
    end_point: Vec3,
    end_normal: Vec3,
    /// The plane's material point velocity over the substep (m/s).
    velocity: Vec3,
}

impl Coupling {
    /// Pinch springs and their friction for the vertices pinched between two obstacles
    /// (`pairs`: vertex and the two obstacles, from the last pass's contacts) and for their
    /// mesh neighbours without a contact of their own or touching only the same two
    /// (`touching`: per vertex, the obstacles of its contacts, `usize::MAX` for none; beside
    /// a pad's edge, cloth a little off the middle of the gap touches one pad's edge only).
    /// Returns the vertices given springs, sorted: the filter leaves them alone.
    pub(super) fn pinch_springs(
        &mut self,
        stage: &CollisionStage,
        s: &StartState,
        pairs: &[(usize, [usize; 2])],
        touching: &[[usize; 2]],
        solves_friction: bool,
        friction: &mut Vec<Friction>,
    ) -> Vec<usize> {
        let mut given = Vec::new();
        if pairs.is_empty() {
            return given;
        }
        let n = s.cloth.len();
        let mut candidates: Vec<(usize, [usize; 2])> = pairs.to_vec();
        let mut pair_of = vec![None; n];
        for &(i, p) in pairs {
            pair_of[i] = Some(p);
        }
        // Per vertex, the neighbour along the cloth's warp (u) most nearly: the cell's first
        // tangent, so the cells of a grid tile the pads' faces.
        let mut warp: Vec<(usize, f64)> = vec![(usize::MAX, -1.0); n];
        let uv = &s.cloth.uv;
        for t in &s.cloth.triangles {
            let t = t.map(|v| v as usize);
            if t.iter().any(|&v| v >= n || v >= uv.len()) {
                continue;
            }
            for (a, b) in
                [(0, 1), (1, 2), (2, 0), (1, 0), (2, 1), (0, 2)].map(|(a, b)| (t[a], t[b]))
            {
                let d = uv[b] - uv[a];
                let along = d.x.abs() / (d.x.abs() + d.y.abs()).max(f64::MIN_POSITIVE);
                if along > warp[a].1 {
                    warp[a] = (b, along);
                }
                let within = |p: [usize; 2]| {
                    (touching.get(b))
                        .is_some_and(|t| t.iter().all(|o| *o == usize::MAX || p.contains(o)))
                };
                if let Some(p) = pair_of[a].filter(|p| pair_of[b].is_none() && within(*p)) {
                    candidates.push((b, p));
                }
            }
        }
        candidates.sort_by_key(|c| c.0);
        candidates.dedup_by_key(|c| c.0);
        for (i, pair) in candidates {
            let along = warp[i].0;
            let x = &s.cloth.x;
            let tangent = (along < n).then(|| x[along] - x[i]);
            if self.pinch_vertex(stage, s, (i, tangent), pair, solves_friction, friction) {
                given.push(i);
            }
        }
        given
    }

    /// The springs and friction of vertex `i` (its cell's first tangent `tangent`, along a
    /// mesh edge) between the obstacles `pair`, when its cell has a share between their
    /// faces; returns whether it got them.
    fn pinch_vertex(
        &mut self,
        stage: &CollisionStage,
        s: &StartState,
        (i, tangent): (usize, Option<Vec3>),
        pair: [usize; 2],
        solves_friction: bool,
        friction: &mut Vec<Friction>,
    ) -> bool {
        let Some((share, [a, b])) = pinch_sides(stage, s, (i, tangent), pair, 0.0) else {
            // A cell the cloth's or the pads' motion carries under the pads within the step
            // is the pinch's too: the stage leaves its squeeze to the next solve's springs
            // (pushed out of the pads' layers at their edges, cloth sliding in fast was
            // stopped there).
            let reach = s.h * (s.cloth.v[i].length() + pads_speed(s, pair));
            if pinch_sides(stage, s, (i, tangent), pair, reach).is_some() {
                self.feedback.squeeze(i, pair);
            }
            return false;
        };
        let th = s.cloth.thickness[i];
        let Some(stiffness) = squeeze_stiffness(s, i).map(|k| k * share) else {
            return false;
        };
        let spring = |side: &Side| ContactSpring {
            verts: [i as u32; 4],
            weights: [1.0, 0.0, 0.0, 0.0],
            normal: side.end_normal,
            point: side.end_point,
            gap: th,
            stiffness,
            friction: 0.0,
        };
        let n = s.cloth.len();
        if !(spring(&a).is_valid(n) && spring(&b).is_valid(n)) {
            return false;
        }
        let first = self.constraints.contacts.len();
        let springs = [first, first + 1];
        let grip = carried_together(&a, &b, s.h, th);
        for (side, facing) in [(&a, b.obstacle), (&b, a.obstacle)] {
            if side.velocity != Vec3::ZERO {
                self.moving_springs.push(self.constraints.contacts.len());
            }
            self.constraints.contacts.push(spring(side));
            let normal_force = stiffness * (th - side.distance).max(0.0);
            let mu = stage.friction_coefficient(i, side.obstacle);
            if solves_friction && mu * normal_force > 0.0 {
                friction.push(Friction {
                    vertex: i as u32,
                    limit: mu * normal_force,
                    reference: side.velocity,
                    normal: Some(side.end_normal),
                    patch: grip.then_some([side.obstacle, facing].map(|o| o as u32)),
                });
            }
            if solves_friction {
                self.feedback.friction_solved(i, side.end_normal);
            }
        }
        self.feedback.squeeze(i, pair);
        self.pinches.push(Pinch { vertex: i, springs });
        true
    }

    /// The number of pinched vertices and their grip: the sum over them of the mean of the
    /// two sides' end forces (N), from the solve's contact forces (`None`: not solved).
    pub(super) fn grip(&self, forces: Option<&[f64]>) -> (usize, f64) {
        let Some(forces) = forces else {
            return (self.pinches.len(), 0.0);
        };
        let at = |k: usize| forces.get(k).copied().unwrap_or(0.0);
        let total = (self.pinches.iter())
            .map(|p| 0.5 * (at(p.springs[0]) + at(p.springs[1])))
            .sum();
        (self.pinches.len(), total)
    }
}

/// The most opposed pair of a vertex's contacts (obstacle, outward normal) with two different
/// obstacles facing each other, if any.
pub(super) fn facing_pair(contacts: &[(usize, Vec3)]) -> Option<[usize; 2]> {
    let mut best: Option<(f64, usize, usize)> = None;
    for (a, ca) in contacts.iter().enumerate() {
        for cb in contacts.iter().skip(a + 1) {
            let d = ca.1.dot(cb.1);
            if ca.0 != cb.0 && d < PINCH_COSINE && best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, ca.0, cb.0));
            }
        }
    }
    best.map(|(_, a, b)| [a, b])
}

/// The stiffness (N/m) of one side's spring on vertex `i` with its whole cell pinched:
/// `E A / thickness`, `A` the vertex's area (its mass over its piece's areal density); `None`
/// for a vertex of no piece.
fn squeeze_stiffness(s: &StartState, i: usize) -> Option<f64> {
    let piece = (s.cloth.pieces.iter()).find(|p| p.vertices().contains(&i))?;
    let m = &piece.material;
    let area = s.cloth.mass[i] / m.density;
    let k = m.compressive_modulus * area / s.cloth.thickness[i];
    (k.is_finite() && k > 0.0).then_some(k)
}

/// Where obstacle `k` is now and at the substep's end.
fn poses(stage: &CollisionStage, s: &StartState, k: usize) -> Option<(Pose, Pose)> {
    let o = stage.obstacles().get(k)?;
    Some(s.obstacle_poses.get(k).copied().unwrap_or((o.pose, o.pose)))
}

/// The share of vertex `i`'s cell (widened by `reach` on every side) between the faces of the
/// obstacles `pair` and the two sides' planes there; `None` when no part of it is.
fn pinch_sides(
    stage: &CollisionStage,
    s: &StartState,
    (i, tangent): (usize, Option<Vec3>),
    pair: [usize; 2],
    reach: f64,
) -> Option<(f64, [Side; 2])> {
    let x = *s.cloth.x.get(i)?;
    let th = s.cloth.thickness[i];
    let obstacles = stage.obstacles();
    let (oa, ob) = (obstacles.get(pair[0])?, obstacles.get(pair[1])?);
    let (pa, pb) = (poses(stage, s, pair[0])?, poses(stage, s, pair[1])?);
    // World closest point and normal of obstacle `o` at pose `now` to `q`.
    let closest = |o: &crate::collide::Obstacle, now: &Pose, q: Vec3| {
        let local = now.inverse_transform_point(q);
        let sp = o.closest_local(local, local);
        (
            now.transform_point(sp.point),
            now.transform_vector(sp.normal),
            sp.signed_distance,
        )
    };
    // The cell's tangent frame: across the pinch's direction (the two sides' normals at the
    // vertex, against each other: tilted alike beside the pads' edges, their difference is
    // still across the gap), the first along the mesh edge `tangent`. The cell is as long as
    // that edge along it and as wide as its area makes it across (a vertex on the cloth's
    // border has half a cell, across the border).
    let normal = (closest(oa, &pa.0, x).1 - closest(ob, &pb.0, x).1).try_normalize()?;
    let along = tangent.map(|t| t - normal * normal.dot(t));
    let t1 = along
        .and_then(Vec3::try_normalize)
        .unwrap_or_else(|| normal.any_orthonormal_vector());
    let t2 = normal.cross(t1);
    let area = cell_area(s, i)?;
    let length = along
        .map_or(area.sqrt(), |t| t.length())
        .max(f64::MIN_POSITIVE);
    let half = [0.5 * length + reach, 0.5 * area / length + reach];
    // Per line, the covered samples and their mean position; over all lines, the sums of the
    // sides' points and normals. The second line goes through the first's covered part (a
    // cell beside a pad's edge is covered on one side of the vertex only), and where the first
    // line through the vertex missed, the first again through the second's.
    let mut sum = [(Vec3::ZERO, Vec3::ZERO); 2];
    let mut count = 0usize;
    let mut line = |centre: Vec3, t: Vec3, half: f64| -> (usize, Vec3) {
        let (mut covered, mut at) = (0usize, Vec3::ZERO);
        for k in 0..SAMPLES {
            let offset = ((k as f64 + 0.5) / SAMPLES as f64 - 0.5) * 2.0 * half;
            let q = centre + t * offset;
            let (qa, na, da) = closest(oa, &pa.0, q);
            let (qb, nb, db) = closest(ob, &pb.0, q);
            if da < 0.0 || db < 0.0 || da + db >= 2.0 * th || na.dot(nb) > FACING_COSINE {
                continue;
            }
            covered += 1;
            at += q;
            sum[0].0 += qa;
            sum[0].1 += na;
            sum[1].0 += qb;
            sum[1].1 += nb;
        }
        count += covered;
        (
            covered,
            if covered > 0 {
                at / covered as f64
            } else {
                centre
            },
        )
    };
    let mut first = line(x, t1, half[0]);
    let second = line(first.1, t2, half[1]);
    if first.0 == 0 && second.0 > 0 {
        first = line(second.1, t1, half[0]);
    }
    let covered = [first.0, second.0];
    let share = covered[0] as f64 * covered[1] as f64 / (SAMPLES * SAMPLES) as f64;
    if share <= 0.0 {
        return None;
    }
    let count = count as f64;
    let side = |k: usize, o: usize, (now, end): (Pose, Pose)| -> Option<Side> {
        let point = sum[k].0 / count;
        let normal = sum[k].1.try_normalize()?;
        // The plane moves with the obstacle: its point and normal at the substep's end.
        let local = now.inverse_transform_point(point);
        let end_point = end.transform_point(local);
        let end_normal = end.transform_vector(now.rotation.inverse() * normal);
        let velocity = if s.h > 0.0 {
            (end_point - point) / s.h
        } else {
            Vec3::ZERO
        };
        Some(Side {
            obstacle: o,
            distance: normal.dot(x - point),
            end_point,
            end_normal: end_normal.try_normalize()?,
            velocity,
        })
    };
    Some((share, [side(0, pair[0], pa)?, side(1, pair[1], pb)?]))
}

/// Whether the two sides carry the cloth between them together (a grip: its frictions form a
/// patch, see [`Friction::patch`]): their tangential motion relative to each other over the
/// substep `h` shears the cloth by less than [`GRIP_SHEAR`] of its `thickness`. Pads on one hand
/// do; a flange sweeping cloth over a table does not, and there the cloth slides on one side or
/// the other vertex by vertex.
fn carried_together(a: &Side, b: &Side, h: f64, thickness: f64) -> bool {
    let relative = a.velocity - b.velocity;
    let n = a.end_normal;
    let shear = (relative - n * n.dot(relative)).length() * h;
    shear < GRIP_SHEAR * thickness
}

/// The shear of the cloth's thickness per substep below which two sides grip it together.
const GRIP_SHEAR: f64 = 0.1;

/// The faster of the two obstacles' translations over the substep (m/s).
fn pads_speed(s: &StartState, pair: [usize; 2]) -> f64 {
    let speed = |k: usize| {
        (s.obstacle_poses.get(k)).map_or(0.0, |(a, b)| {
            (b.translation - a.translation).length() / s.h.max(f64::MIN_POSITIVE)
        })
    };
    speed(pair[0]).max(speed(pair[1]))
}

/// Vertex `i`'s area (m^2): its mass over its piece's areal density.
fn cell_area(s: &StartState, i: usize) -> Option<f64> {
    let piece = (s.cloth.pieces.iter()).find(|p| p.vertices().contains(&i))?;
    let area = s.cloth.mass[i] / piece.material.density;
    (area.is_finite() && area > 0.0).then_some(area)
}
