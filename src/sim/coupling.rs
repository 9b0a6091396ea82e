//! The solver–collision coupling, both ways, in one place.
//!
//! Collision runs once per substep, after the solve; its contacts reach the solver only as the
//! next substep's constraints, and the solver's answer reaches the stage only as an explicit
//! [`SolverFeedback`] input of the next `resolve`:
//!
//! - **in** ([`Coupling::contacts_in`]): the last pass's obstacle contacts become the filter
//!   `S = I - n n^T` of the vertices they press (a wedge's two or three normals together, see
//!   [`HeldNormals`]), with the Coulomb friction of static surfaces when the integrator solves
//!   it; obstacles' edges, corners and rod axes that touch the cloth between vertices become
//!   one-sided springs when the integrator solves them.
//! - **out** ([`Coupling::solved`], [`Coupling::feedback_out`]): the springs' end forces become
//!   the next substep's friction limits; the filter's normal impulse on each held vertex
//!   becomes the stage's friction bound for it (and in-solve friction's next limits), and the
//!   contacts whose friction or spring the solver applied are marked so the stage does not
//!   answer them a second time.

use super::front::Front;
use crate::cloth::Cloth;
use crate::collide::{Arrival, CollisionStage, HeldNormals, SolverFeedback, FEATURE_DEEP};
use crate::effects::{EffectSet, State};
use crate::integrate::{Capabilities, Constraints, ContactSpring, Friction};
use crate::linalg::Filter;
use crate::Vec3;

/// `k h^2 / m` of an edge spring at the contact point's mass `m`: the spring stops the point
/// within a step, and a load of the cloth's own weight per vertex deflects it by `g h^2 / 1e3`
/// (a micrometre at 120 Hz). Springs as stiff as the cloth's stiffest mode (`m omega^2`, 40
/// times stiffer in tests/table_edge.rs) made the re-detection's drift of micrometres into
/// newtons and slowed a frictionless strip sliding over the edge (0.39 m instead of 0.57 m in
/// 2 s).
const CONTACT_STIFFNESS: f64 = 1e3;

/// `k h^2 / m` of a moving feature's spring, at the (split) substep's `h`: implicit Euler leaves
/// `1 / (1 + k h^2 / m)` of the contact's gap, 0.5 % here. Fast-contact splitting keeps a link's
/// move within a substep to a third of the cloth's spacing, so what is left (0.04 mm at 2.6 cm
/// spacing) is far below any cloth's thickness. Unlike a static edge's spring (at the scene's
/// substep, small in a split one), this term is as large in the matrix as the spring says: at
/// 1e3 the 5 mm rod at 20 m/s took 600 CG iterations a frame, at 200 284
/// (`benches/fast_links.rs`); no crossing either way, the largest edge over the 24 rod cases of
/// `tests/fast_links.rs` 1.152 -> 1.130, drape_bot's arm through a towel 1.153 -> 1.093.
const MOVING_CONTACT_STIFFNESS: f64 = 200.0;

/// `k h^2 / m` of the tangential anchor that holds an arriving vertex friction stops where its
/// path hit the layer (see `Coupling::arrival_springs`): it leaves a hundredth of the slip the
/// step would have carried it on by (44 um of a patch's 4.4 mm landing on a slope it sticks
/// to, `tests/landing.rs`). As stiff as the normal spring (1e3) the anchors held against the
/// pull of a whipping border: S1 64x64 (`cargo bench --bench contact`) over frictions
/// 0.46-0.54 ended its worst frame's largest edge at 1.086-1.258 against 1.078-1.140 here, p99
/// 1.028-1.036 against 1.026.
const ANCHOR_STIFFNESS: f64 = 100.0;

/// The coupling's state: this substep's constraints and holds, the lagged forces of the last
/// solve, and the feedback for the stage.
#[derive(Debug, Default)]
pub(super) struct Coupling {
    /// The solver's constraints of this substep (filter, target velocities, friction, springs).
    pub constraints: Constraints,
    /// This substep's held vertices: (vertex, surfaces, largest Coulomb coefficient).
    held: Vec<(usize, HeldNormals, f64)>,
    /// Per vertex, the normals the last substep's solve held it against with their Coulomb
    /// limits `mu N` (N; 0: unused): the lagged normal forces of in-solve friction.
    friction_limit: Vec<[(Vec3, f64); 3]>,
    /// The last substep's edge springs (cloth face or edge) and their end forces (N), sorted.
    spring_forces: Vec<([u32; 4], f64)>,
    /// Indices into `constraints.contacts` from which the springs hold cloth layers apart
    /// (`layer_springs`); the obstacles' come before.
    layers_from: usize,
    /// What the solver did this substep, for the stage's `resolve`.
    pub feedback: SolverFeedback,
    /// Indices into `constraints.contacts` of the springs on moving features: they do work on
    /// the cloth, which the guard allows for.
    pub moving_springs: Vec<usize>,
    /// The mesh edges the front of a link's drag spreads over.
    front: Front,
    /// Scratch of `arrival_springs`: the vertices the last pass touched, and the arrivals.
    touched: Vec<bool>,
    /// This substep's arrivals, the index of each one's normal spring in
    /// `constraints.contacts`, and those springs' end forces (N) once solved.
    arrivals: Vec<Arrival>,
    arrival_springs: Vec<usize>,
    arrival_forces: Vec<f64>,
}

/// What the coupling reads at the start of a substep.
pub(super) struct StartState<'a> {
    pub cloth: &'a Cloth,
    pub effects: &'a EffectSet,
    pub t: f64,
    /// The scene's substep (not a subdivided one).
    pub h_scene: f64,
    /// This substep.
    pub h: f64,
}

impl Coupling {
    /// A new substep for `n` vertices: every vertex free, no friction, no feedback yet.
    pub fn begin(&mut self, n: usize) {
        if self.constraints.filter.len() != n {
            self.constraints = Constraints::free(n);
        } else {
            self.constraints.filter.fill(Filter::Free);
        }
        self.constraints.friction.clear();
        self.constraints.standby.clear();
        self.feedback.clear(n);
    }

    /// A new cloth of `n` vertices (the lagged forces are kept, as they were).
    pub fn replace_cloth(&mut self, n: usize) {
        self.constraints = Constraints::free(n);
    }

    /// Kinematic vertex `i` moves at `velocity` this substep.
    pub fn fix(&mut self, i: usize, velocity: Vec3) {
        self.constraints.filter[i] = Filter::Fixed;
        self.constraints.target_velocity[i] = velocity;
    }

    /// Contacts in: the last collision pass's contacts become this substep's constraints
    /// (edge springs first, then the held vertices' filter and friction), as far as the
    /// integrator solves them (`caps`). `scratch` holds the start forces.
    pub fn contacts_in(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        caps: &Capabilities,
        scratch: &mut Vec<Vec3>,
    ) {
        self.edge_springs(stage, s, caps);
        self.contact_constraints(stage, s, caps.solves_friction, scratch);
        self.arrival_springs(stage, s, caps);
        self.layers_from = self.constraints.contacts.len();
        self.layer_springs(stage, s, caps);
    }

    /// The solve is done: its edge springs' end forces (`None` when it does not solve them)
    /// are the normal forces of their friction next substep.
    pub fn solved(&mut self, contact_forces: Option<&[f64]>) {
        self.spring_forces.clear();
        self.arrival_forces.clear();
        if let Some(forces) = contact_forces {
            // Each arrival's normal spring (its anchor's tangential springs follow it).
            self.arrival_forces.extend(
                (self.arrival_springs.iter()).map(|&k| forces.get(k).copied().unwrap_or(0.0)),
            );
            self.spring_forces.extend(
                self.constraints.contacts[..self.layers_from]
                    .iter()
                    .zip(forces)
                    .map(|(c, f)| (c.verts, *f)),
            );
            self.spring_forces.sort_by_key(|a| a.0);
        }
    }

    /// Feedback out: the normal impulse per unit mass the filter gave each held vertex, for the
    /// stage's friction; implicit Euler is `m (v1 - v0) = h f(x1, v1) + impulse`. The solver's
    /// own constraint impulses when it reports them (`impulses`), else estimated from the end
    /// forces (in `scratch`). Start-of-step forces, `f0 h / m`, overstate it up to 1e3 times
    /// for a vertex pressed by springs that the implicit step relaxes: every held vertex then
    /// stuck, and friction's projection back stretched the springs every step. Also sets
    /// in-solve friction's Coulomb limits for the next substep: `mu N` of this solve's normal
    /// impulses (zero for vertices not held now).
    #[allow(clippy::too_many_arguments)]
    pub fn feedback_out(
        &mut self,
        cloth: &Cloth,
        effects: &EffectSet,
        v0: &[Vec3],
        (t, h): (f64, f64),
        solves_friction: bool,
        impulses: Option<&[Vec3]>,
        scratch: &mut Vec<Vec3>,
    ) {
        let n = cloth.len();
        self.friction_limit.clear();
        self.friction_limit.resize(n, [(Vec3::ZERO, 0.0); 3]);
        // Arrival springs that ended acting: their normal impulse counts in the stage's
        // friction bound, as a held vertex's does.
        for (a, f) in self.arrivals.iter().zip(&self.arrival_forces) {
            let i = a.vertex as usize;
            if *f > 0.0 && i < n {
                self.feedback.hold(i, a.normal, f * h / cloth.mass[i]);
            }
        }
        if self.held.is_empty() {
            return;
        }
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
            // holds the linearisation error of a stretched cloth's end-state forces (up to 1e4
            // times the real normal force), and as friction's normal force it made stretched
            // cloth stick harder the more it was stretched.
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
                for (slot, (normal, l)) in self.friction_limit[i]
                    .iter_mut()
                    .zip(normals.normals().iter().zip(split))
                {
                    *slot = (*normal, mu * l.max(0.0) * m / h);
                }
            }
        }
    }

    /// Obstacle edges and corners the cloth touched in the last collision pass (a moving one's
    /// aimed at the end of this substep, without friction) become
    /// one-sided springs of this substep when the integrator solves them (see
    /// [`ContactSpring`]), with in-solve Coulomb friction whose limit is `mu` times the force
    /// the same contact's spring ended the last substep with, shared by weight. The stage then
    /// leaves those contacts to the solver unless they end deep.
    fn edge_springs(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        caps: &Capabilities,
    ) {
        self.constraints.contacts.clear();
        self.constraints.front_strain.clear();
        self.moving_springs.clear();
        self.layers_from = 0;
        if !caps.solves_contacts {
            return;
        }
        // The scene's substep, not a subdivided one: a spring stiffened by `1 / h^2` as the guard
        // halves the step would only store more energy in a contact that is already deep.
        let h = s.h_scene;
        let n = s.cloth.len();
        let Some(stage) = stage else {
            return;
        };
        let (mass, filter) = (&s.cloth.mass, &self.constraints.filter);
        let lagged = &self.spring_forces;
        let mut sprung = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for c in stage.feature_contacts() {
            // A face or edge answered in two passes is one contact: keep the first.
            if c.verts.iter().any(|&v| v as usize >= n) || !seen.insert(c.verts) {
                continue;
            }
            let [a, b, d] = c.verts;
            let [wa, wb, wd] = c.weights;
            let mut spring = ContactSpring {
                verts: [a, b, d, d],
                weights: [wa, wb, wd, 0.0],
                normal: c.normal,
                point: c.point,
                gap: c.gap,
                stiffness: 0.0,
                friction: 0.0,
            };
            // `k h^2 / m` at the contact point's mass. A moving feature's spring is stiff for
            // this substep (split where a link moves fast): it must carry the cloth with the
            // link within the substep, not within a scene substep's time.
            let (h, k) = if c.moving {
                (s.h, MOVING_CONTACT_STIFFNESS)
            } else {
                (h, CONTACT_STIFFNESS)
            };
            let m: f64 = spring.slots().map(|(i, w)| w * mass[i]).sum();
            spring.stiffness = k * m / (h * h);
            let movable = spring.slots().any(|(i, _)| filter[i] != Filter::Fixed);
            // A contact already deep (cloth pinched below its thickness under a press that
            // stopped) stays with the collision stage's pinch and push: as a spring it would
            // start with a large stored force (17 J released in one step, measured).
            let deep = spring.depth(&s.cloth.x) > (1.0 - FEATURE_DEEP) * c.gap;
            // A moving feature holds the cloth where it will be at the substep's end.
            (spring.point, spring.normal) = (c.end_point, c.end_normal);
            if !spring.is_valid(n) || !movable || deep {
                continue;
            }
            // The normal force of the last solve's spring on this face or edge (none for a new
            // contact: the collision stage gave it friction): the start depth holds the
            // re-detection's drift, micrometres that the stiff spring turns into newtons.
            let normal_force = lagged
                .binary_search_by(|l| l.0.cmp(&spring.verts))
                .map_or(0.0, |k| lagged[k].1);
            if caps.solves_friction {
                spring.friction = c.mu * normal_force;
            }
            sprung.push(c.verts);
            if c.moving {
                self.moving_springs.push(self.constraints.contacts.len());
            }
            self.constraints.contacts.push(spring);
        }
        self.feedback.set_sprung(sprung);
        self.front.strain(
            s.cloth,
            &self.constraints.contacts,
            &self.moving_springs,
            s.h,
            &mut self.constraints.front_strain,
        );
    }

    /// Free vertices whose start velocity carries them into a static solid's contact layer
    /// within this substep (see [`CollisionStage::arrivals`]) get a one-sided spring on the
    /// layer's tangent plane, as stiff as an edge's: the solve stops them at the layer with
    /// their neighbours, where the response would push them back alone after it. A spring acts
    /// only while the solved step ends inside the layer (the active set, see [`ContactSpring`]).
    /// One that Coulomb friction stops where it hits is anchored there in the tangent plane
    /// too (see [`ANCHOR_STIFFNESS`]); a sliding one's friction is the stage's, after the
    /// solve. Vertices the last pass touched (held or released) are the stage's, as are those
    /// starting in a solid or its layer.
    fn arrival_springs(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        caps: &Capabilities,
    ) {
        self.arrivals.clear();
        self.arrival_springs.clear();
        let Some(stage) = stage.filter(|_| caps.solves_contacts) else {
            return;
        };
        let n = s.cloth.len();
        self.touched.clear();
        self.touched.resize(n, false);
        for c in stage.contacts() {
            if let Some(t) = self.touched.get_mut(c.vertex as usize) {
                *t = true;
            }
        }
        let (filter, touched) = (&self.constraints.filter, &self.touched);
        let skip = |i: usize| filter[i] != Filter::Free || touched[i];
        let mut arrivals = std::mem::take(&mut self.arrivals);
        stage.arrivals(&s.cloth.x, &s.cloth.v, s.h, skip, &mut arrivals);
        let h = s.h_scene;
        for a in &arrivals {
            let i = a.vertex;
            let spring = ContactSpring {
                verts: [i; 4],
                weights: [1.0, 0.0, 0.0, 0.0],
                normal: a.normal,
                point: a.point,
                gap: a.gap,
                stiffness: CONTACT_STIFFNESS * s.cloth.mass[i as usize] / (h * h),
                friction: 0.0,
            };
            // An invalid spring (non-finite input) keeps its slot; the solver leaves it unused.
            self.arrival_springs.push(self.constraints.contacts.len());
            self.constraints.contacts.push(spring);
            if a.sticks {
                // Friction stops it where it hits: anchored there along the tangent plane by
                // two opposed one-sided springs per direction (the active set keeps the one on
                // the side the vertex ends), so the solve ends it there, neighbours included.
                let (t1, t2) = a.normal.any_orthonormal_pair();
                for t in [t1, -t1, t2, -t2] {
                    self.constraints.contacts.push(ContactSpring {
                        normal: t,
                        point: a.hit,
                        gap: 0.0,
                        stiffness: ANCHOR_STIFFNESS * spring.stiffness / CONTACT_STIFFNESS,
                        ..spring
                    });
                }
            }
        }
        self.arrivals = arrivals;
    }

    /// Contacts of the last collision pass become constraints of this substep (the survey's mass
    /// modification, `S = I - n n^T`) when the scene's response asks for the filter. A contact
    /// whose vertex is pulled away from the surface by the other forces is released instead of
    /// held. A vertex held by two or three surfaces keeps its velocity along all their normals
    /// (see [`HeldNormals`]). Records the held vertices with their normals.
    fn contact_constraints(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        solves_friction: bool,
        scratch: &mut Vec<Vec3>,
    ) {
        self.held.clear();
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
        for group in contacts.chunk_by(|a, b| a.vertex == b.vertex) {
            let i = group[0].vertex;
            let f = scratch[i];
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

    /// In-solve friction of vertex `i` held against `normals` (force `f` on it), one per surface:
    /// each surface rubs with its own velocity (a cloth wedged between a moving hand and a
    /// static torso is dragged by one and held by the other; one drag towards their mean
    /// velocity with both limits summed dragged it at half the hand's speed with twice the
    /// grip). The Coulomb limit is the last substep's `mu N` for that surface when the solve
    /// held the vertex against it, else `mu` times the force pressing it into it now.
    fn held_friction(
        &self,
        i: usize,
        normals: &HeldNormals,
        mu: f64,
        f: Vec3,
        out: &mut Vec<Friction>,
    ) {
        let lagged = self.friction_limit.get(i).copied().unwrap_or_default();
        for (n, surface) in normals.normals().iter().zip(normals.surfaces()) {
            let limit = match lagged.iter().find(|l| l.1 > 0.0 && l.0.dot(*n) > 0.9) {
                Some(l) => l.1,
                None => mu * (-f.dot(*n)).max(0.0),
            };
            if limit > 0.0 {
                out.push(Friction {
                    vertex: i as u32,
                    limit,
                    reference: *surface,
                });
            }
        }
    }
}

impl Coupling {
    /// Layers of cloth resting on each other in the last collision pass (a vertex over a face of
    /// another layer, [`crate::collide::SelfTouch`]) become one-sided springs of this substep
    /// between the vertex and the face's point under it (`x_p - sum b_i x_i` along the face's
    /// normal), when the integrator solves springs. The solve then carries a layer's support
    /// into the cloth around the vertex, instead of moving the vertex into the layer for the
    /// repulsion to push back alone, and the vertex's weight into the layer under it: the
    /// spring's forces on its two sides are equal and opposite. A pair closer than its contact
    /// distance is held where it is: pushed apart within the solve, the deficit would leave as
    /// speed, `deficit / h`, where the repulsion moves positions only. Stiffness
    /// [`LAYER_STIFFNESS`] at the pair's effective mass. A vertex and a face of another layer
    /// share no block of the matrix: the spring's Jacobian is lumped onto the diagonal there
    /// ([`ContactSpring::add_jacobian`]) and completed in the solver's products
    /// (`integrate::contact::OffPattern`).
    ///
    /// Measured alternatives, on chair.yaml (a cloth folding over the seat's front edge) and a
    /// towel on a hammock (`tests/resting_layers.rs`): a spring on each side, anchored on where
    /// the other side goes at the pair's common velocity, held both sides still against each
    /// other's ghost: the hammock carried 1.19 N under a 0.34 N towel (its own tension, pushing
    /// up, went into the ghost) and only a load added for the towel's weight bowed it at all;
    /// with the anchors moved by gravity's pull over the substep as well, a lower layer held up
    /// by the cloth's tension (not an obstacle) was pushed down by `g h^2` a substep at a
    /// hundred to a thousand times its weight: chair's cloth slid off the seat and gathered
    /// 0.47 J lying on the ground. A vertex spring alone with its last force as the face's
    /// load: a vertex held by the seat under a face carried 4 N (2500 times its weight) into
    /// that load, and the face was thrown at 5.4 m/s.
    ///
    /// The springs carry no friction: the repulsion's Coulomb friction still acts on the pairs
    /// it answers.
    fn layer_springs(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        caps: &Capabilities,
    ) {
        let Some(stage) = stage.filter(|_| caps.solves_contacts) else {
            return;
        };
        let (x, mass, filter) = (&s.cloth.x, &s.cloth.mass, &self.constraints.filter);
        let n = x.len();
        let k = LAYER_STIFFNESS / (s.h_scene * s.h_scene);
        for t in stage.self_touches() {
            let [a, b, c] = t.triangle;
            let [wa, wb, wc] = t.bary;
            let mut spring = ContactSpring {
                verts: [t.vertex, a, b, c],
                weights: [1.0, -wa, -wb, -wc],
                normal: t.normal,
                point: Vec3::ZERO,
                gap: 0.0,
                stiffness: 0.0,
                friction: 0.0,
            };
            if !spring.verts.iter().all(|&i| (i as usize) < n)
                || spring.slots().all(|(i, _)| filter[i] == Filter::Fixed)
            {
                continue;
            }
            spring.gap = (spring.along(x) + RESTORE * t.gap).min(LAYER_REST * t.gap);
            spring.stiffness = k * spring.point_mass(mass);
            if spring.is_valid(n) && spring.gap > 0.0 {
                self.constraints.contacts.push(spring);
            }
        }
    }
}

/// `k h^2 / m` of a layer spring at its point's mass `m` and the scene's substep: a load of its
/// own weight deflects it by `g h^2 / 100`, 0.03 mm at 60 Hz. As stiff as a static edge's
/// (`CONTACT_STIFFNESS`, 1e3) it took sphere_drape.yaml's solves from 6.4 k CG iterations over
/// 3 s to 15.9 k, at 100 10.1 k; the crumple at twice its resolution 12.8 k (without the
/// springs) to 16.6 k, at 100 6.5 k, with its largest edge 1.367 -> 1.217, at 100 1.237.
const LAYER_STIFFNESS: f64 = 100.0;

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

/// The surfaces a vertex with the contacts `group` is held against this substep, given the
/// force `f` on it, or `None` when it is released from all.
///
/// A contact whose surface the force pulls the vertex off is released, but not alone: the
/// surfaces still held steer the vertex. In a wedge (cloth pressed by a moving slanted face
/// against a table) the springs lift an edge vertex a little off the table while the face
/// pushes it along its normal, which points into the table; released from the table, the
/// solver drove it 9 mm through it in one substep and the collision stage's push back stored
/// 0.7 J in the springs. So a released contact is taken back while the held ones' filtered
/// force, or their surfaces' velocities, drive the vertex into its surface.
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

/// A layer spring's rest length in contact distances: a little beyond the repulsion's, so that a
/// pair the spring holds under a load of a few times its weight (`g h^2 / 50` a substep, 0.05
/// mm at 60 Hz against a 10 mm distance) stays out of the repulsion's reach. At the contact
/// distance itself, the repulsion answered every resting pair every substep, and its averaged
/// moves, which do not conserve momentum, took 5 % of a towel's weight off the hammock under it.
const LAYER_REST: f64 = 1.02;

/// How much of its contact distance a layer spring may restore in one substep: a pair found
/// deep gets the rest of the way over the next substeps, not as speed, `deficit / h`, at once.
const RESTORE: f64 = 0.1;
