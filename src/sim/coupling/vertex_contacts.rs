//! The vertices the last pass's obstacle contacts press: the filter `S = I - n n^T` (the
//! survey's mass modification) holds each against the surfaces it presses, grouped per vertex
//! into [`HeldNormals`] (a wedge's two or three normals together); out, the filter's normal
//! impulse on each held vertex becomes the stage's friction bound for it.

use super::held_friction::next_limits;
use super::pinch_springs::facing_pair;
use super::{Coupling, StartState};
use crate::cloth::Cloth;
use crate::collide::{CollisionStage, HeldNormals};
use crate::effects::{EffectSet, State};
use crate::linalg::Filter;
use crate::Vec3;

/// One contact of the last collision pass, as the filter sees it.
struct VertexContact {
    vertex: usize,
    normal: Vec3,
    /// The surface's velocity at the contact.
    surface: Vec3,
    obstacle: usize,
    /// The lead-out's contact of a vertex that started inside the obstacle (`overlap.rs`).
    led_out: bool,
}

impl Coupling {
    /// Contacts of the last collision pass become constraints of this substep (the survey's mass
    /// modification, `S = I - n n^T`) when the scene's response asks for the filter. A contact
    /// whose vertex is pulled away from the surface by the other forces is released instead of
    /// held. A vertex held by two or three surfaces keeps its velocity along all their normals
    /// (see [`HeldNormals`]). Records the held vertices with their normals.
    pub(super) fn contact_constraints(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        (solves_contacts, solves_friction): (bool, bool),
        scratch: &mut Vec<Vec3>,
    ) {
        // Pinch springs need a solve that takes contact springs.
        let pinches = solves_contacts;
        self.held.clear();
        self.pinches.clear();
        let Some(stage) = stage else {
            return;
        };
        if !stage.settings().response.uses_filter() || stage.contacts().is_empty() {
            return;
        }
        let n = s.cloth.len();
        crate::linalg::scratch(scratch, n);
        let st = State {
            t: s.t,
            x: &s.cloth.x,
            v: &s.cloth.v,
        };
        s.effects.forces(&st, scratch);
        // The contacts grouped by vertex (in contact order within a vertex).
        let mut contacts: Vec<VertexContact> = stage
            .contacts()
            .iter()
            .map(|c| VertexContact {
                vertex: c.vertex as usize,
                normal: c.normal,
                surface: c.surface_velocity,
                obstacle: c.obstacle,
                led_out: stage.leads_out(c.vertex as usize, c.obstacle),
            })
            .filter(|c| c.vertex < n && self.constraints.filter[c.vertex] != Filter::Fixed)
            .collect();
        contacts.sort_by_key(|c| c.vertex);
        self.friction_limit.resize(n, [(Vec3::ZERO, 0.0); 3]);
        let mut friction = Vec::new();
        // Vertices between two facing obstacles, and their neighbours' cells reaching under
        // the same pads: pinch springs instead of the filter (see `pinch_springs`).
        let pinched = if pinches {
            let mut touching = vec![[usize::MAX; 2]; n];
            let mut pairs = Vec::new();
            let mut sides = Vec::new();
            for group in contacts.chunk_by(|a, b| a.vertex == b.vertex) {
                let i = group[0].vertex;
                sides.clear();
                sides.extend(
                    (group.iter())
                        .filter(|c| !c.led_out)
                        .map(|c| (c.obstacle, c.normal)),
                );
                touching[i] = touched(group);
                if let Some(pair) = facing_pair(&sides) {
                    pairs.push((i, pair));
                }
            }
            self.pinch_springs(stage, s, &pairs, &touching, solves_friction, &mut friction)
        } else {
            Vec::new()
        };
        for group in contacts.chunk_by(|a, b| a.vertex == b.vertex) {
            let i = group[0].vertex;
            let f = scratch[i];
            if pinched.binary_search(&i).is_ok() {
                continue;
            }
            let Some(normals) = pressing_normals(group, f) else {
                // Released, but on its way out of a solid: held again if the solve drives it
                // back in (see `Constraints::standby`).
                if let Some(c) = group.iter().find(|c| c.led_out) {
                    self.constraints.target_velocity[i] = c.surface;
                    self.constraints.standby.push((i, c.normal));
                }
                continue;
            };
            let (filter, target) = normals.filter();
            self.constraints.filter[i] = filter;
            self.constraints.target_velocity[i] = target;
            let mu = group
                .iter()
                .map(|c| stage.friction_coefficient(i, c.obstacle))
                .fold(0.0, f64::max);
            self.held.push((i, normals, mu));
            if solves_friction {
                self.held_friction(i, &normals, mu, f, &mut friction);
            }
        }
        self.constraints.friction.extend(friction);
    }

    /// The normal impulse per unit mass the filter gave each held vertex, split over the
    /// surfaces it was held against, for the stage's friction; implicit Euler is
    /// `m (v1 - v0) = h f(x1, v1) + impulse`. The solver's own constraint impulses when it
    /// reports them (`impulses`), else estimated from the end forces (in `scratch`).
    /// Start-of-step forces, `f0 h / m`, would overstate it by orders of magnitude for a vertex
    /// pressed by springs that the implicit step relaxes: every held vertex would stick, and
    /// friction's projection back would stretch the springs every step. When the solve solves
    /// friction (`solves_friction`), marks the held vertices' friction as solved and sets its
    /// Coulomb limits for the next substep (see [`next_limits`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn held_feedback(
        &mut self,
        cloth: &Cloth,
        effects: &EffectSet,
        v0: &[Vec3],
        (t, h): (f64, f64),
        solves_friction: bool,
        impulses: Option<&[Vec3]>,
        scratch: &mut Vec<Vec3>,
    ) {
        if self.held.is_empty() {
            return;
        }
        let n = cloth.len();
        if impulses.is_none() {
            crate::linalg::scratch(scratch, n);
            let s = State {
                t: t + h,
                x: &cloth.x,
                v: &cloth.v,
            };
            effects.forces(&s, scratch);
        }
        for (i, normals, mu) in &self.held {
            let i = *i;
            let m = cloth.mass[i];
            // The solver's own constraint impulse when it reports one: the estimate below also
            // holds the linearisation error of a stretched cloth's end-state forces (which can
            // exceed the real normal force by orders of magnitude), and as friction's normal
            // force it would make stretched cloth stick harder the more it is stretched.
            let dv = match impulses.and_then(|r| r.get(i)) {
                Some(r) => *r / m,
                None => cloth.v[i] - v0[i] - scratch[i] * (h / m),
            };
            let split = normals.split(dv);
            for (normal, dvn) in normals.normals().iter().zip(split) {
                self.feedback.hold(i, *normal, dvn);
            }
            if solves_friction {
                for normal in normals.normals() {
                    self.feedback.friction_solved(i, *normal);
                }
                next_limits(&mut self.friction_limit[i], normals, split, *mu, m, h);
            }
        }
    }
}

/// The obstacles of one vertex's contacts `group` when there are at most two (unused slots
/// `usize::MAX`), else `[usize::MAX - 1; 2]` (no pair holds them all): see
/// [`Coupling::pinch_springs`].
fn touched(group: &[VertexContact]) -> [usize; 2] {
    let mut out = [usize::MAX; 2];
    for c in group {
        if out.contains(&c.obstacle) {
            continue;
        }
        match out.iter_mut().find(|o| **o == usize::MAX) {
            Some(slot) => *slot = c.obstacle,
            None => return [usize::MAX - 1; 2],
        }
    }
    out
}

/// The surfaces a vertex with the contacts `group` is held against this substep, given the
/// force `f` on it, or `None` when it is released from all.
///
/// A contact whose surface the force pulls the vertex off is released, but not alone: the
/// surfaces still held steer the vertex. In a wedge (cloth pressed by a moving slanted face
/// against a table) the springs lift an edge vertex a little off the table while the face
/// pushes it along its normal, which points into the table; released from the table, the
/// solver would drive it through the table within a substep, and the collision stage's push
/// back would store that depth as energy in the springs (`tests/contact_wedge.rs`). So a
/// released contact is taken back while the held ones' filtered force, or their surfaces'
/// velocities, drive the vertex into its surface.
fn pressing_normals(group: &[VertexContact], f: Vec3) -> Option<HeldNormals> {
    let mut held: Vec<bool> = group.iter().map(|c| f.dot(c.normal) <= 0.0).collect();
    let build = |held: &[bool]| {
        HeldNormals::from_contacts(
            group
                .iter()
                .zip(held)
                .filter(|(_, h)| **h)
                .map(|(c, _)| (c.normal, c.surface)),
        )
    };
    let mut normals = build(&held);
    if normals.is_empty() {
        return None;
    }
    // Each pass can only add contacts, so at most one pass per contact.
    for _ in 0..group.len() {
        let (filter, target) = normals.filter();
        let f_free = filter.apply(f);
        let driven = target - filter.apply(target);
        let mut added = false;
        for (c, h) in group.iter().zip(held.iter_mut()) {
            if !*h && (f_free.dot(c.normal) < 0.0 || (driven - c.surface).dot(c.normal) < 0.0) {
                *h = true;
                added = true;
            }
        }
        if !added {
            break;
        }
        normals = build(&held);
    }
    Some(normals)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A still contact of vertex 0 against a surface with normal `normal`.
    fn contact(normal: Vec3) -> VertexContact {
        VertexContact {
            vertex: 0,
            normal: normal.normalize(),
            surface: Vec3::ZERO,
            obstacle: 0,
            led_out: false,
        }
    }

    #[test]
    fn a_vertex_pressed_into_its_surface_is_held() {
        let group = [contact(Vec3::Z)];
        let normals = pressing_normals(&group, Vec3::new(0.3, 0.0, -1.0)).unwrap();
        assert_eq!(normals.normals(), &[Vec3::Z]);
    }

    #[test]
    fn a_vertex_pulled_off_its_only_surface_is_released() {
        let group = [contact(Vec3::Z)];
        assert!(pressing_normals(&group, Vec3::new(0.3, 0.0, 1.0)).is_none());
    }

    #[test]
    fn a_wedge_takes_back_the_surface_the_held_one_drives_the_vertex_into() {
        // A table, and a slanted face whose normal points into it. The force lifts the vertex
        // off the table but presses it into the face, which alone would slide it down into
        // the table: the table is held again.
        let (table, face) = (Vec3::Z, Vec3::new(1.0, 0.0, -0.3));
        let group = [contact(table), contact(face)];
        let f = Vec3::new(-1.0, 0.0, 0.1);
        assert!(f.dot(table) > 0.0 && f.dot(face) < 0.0);
        let normals = pressing_normals(&group, f).unwrap();
        assert_eq!(normals.normals().len(), 2);
        assert_eq!(normals.normals()[0], table);
    }

    #[test]
    fn a_surface_the_force_pulls_off_and_the_held_ones_do_not_drive_into_stays_released() {
        // Two walls at a right angle: the force presses the vertex into one and pulls it off
        // the other, which the first one's filtered force does not reach.
        let group = [contact(Vec3::X), contact(Vec3::Z)];
        let normals = pressing_normals(&group, Vec3::new(0.5, 0.0, -1.0)).unwrap();
        assert_eq!(normals.normals(), &[Vec3::Z]);
    }
}
