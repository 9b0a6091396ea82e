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
//!
//! One file per kind of contact constraint, in the order `contacts_in` builds them:
//!
//! - `edge_springs`: obstacle edges, corners and rod axes as one-sided springs, on static and
//!   moving features, with in-solve friction from their lagged end forces;
//! - `vertex_contacts`: the filter `S = I - n n^T` of the vertices the contacts press, grouped
//!   per vertex into the surfaces it is held against, and their normal impulses out;
//! - `pinch_springs`: a vertex squeezed between two facing surfaces, pressed by each with a
//!   spring of the cloth's through-thickness compliance and rubbed by each with its friction
//!   (instead of the filter);
//! - `held_friction`: in-solve Coulomb friction of the held vertices, one per surface, and its
//!   lagged limits;
//! - `arrival`: springs that stop free vertices arriving at a static solid's contact layer,
//!   anchored where friction stops them;
//! - `layer_springs`: layers of cloth resting on each other, held apart by vertex-face springs.

mod arrival;
mod edge_springs;
mod held_friction;
mod layer_springs;
mod pinch_springs;
mod vertex_contacts;

use super::front::Front;
use crate::cloth::Cloth;
use crate::collide::{Arrival, CollisionStage, HeldNormals, SolverFeedback};
use crate::effects::EffectSet;
use crate::integrate::{Capabilities, Constraints, STICK_SPEED};
use crate::linalg::Filter;
use crate::{Pose, Vec3};

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
    /// Per vertex, the end forces (N) of the last substep's layer springs on it as their
    /// vertex (summed over its faces), sorted: the normal force of its friction next substep,
    /// kept by the vertex as it slides from face to face.
    layer_forces: Vec<(u32, f64)>,
    /// Vertices whose cloth-cloth friction in the last solve ended slipping (see
    /// [`Coupling::solved`]).
    pub layer_slipping: usize,
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
    /// This substep's pinched vertices and their two springs (`pinch_springs`).
    pinches: Vec<Pinch>,
    /// The last solve's pinched vertices and grip (see [`Coupling::grip`]).
    pub pinch_grip: (usize, f64),
}

/// A pinched vertex's two springs (`pinch_springs`) (indices into the constraints' contacts).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Pinch {
    pub vertex: usize,
    pub springs: [usize; 2],
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
    /// Each obstacle's pose at the substep's start and end (empty without a collision stage).
    pub obstacle_poses: &'a [(Pose, Pose)],
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
        let solves = (caps.solves_contacts, caps.solves_friction);
        self.contact_constraints(stage, s, solves, scratch);
        self.arrival_springs(stage, s, caps);
        self.layers_from = self.constraints.contacts.len();
        self.layer_springs(stage, s, caps);
    }

    /// The solve is done: its edge springs' end forces (`None` when it does not solve them)
    /// are the normal forces of their friction next substep. `v`, the end velocities, gives
    /// the vertices whose layer friction ended slipping: a vertex over another layer's face,
    /// its spring pressed and its friction acting, moving over the face faster than
    /// [`STICK_SPEED`] (counted once per vertex).
    pub fn solved(&mut self, contact_forces: Option<&[f64]>, v: &[Vec3]) {
        self.layer_slipping = 0;
        if let Some(forces) = contact_forces {
            let mut last = None;
            for (c, f) in self
                .constraints
                .contacts
                .iter()
                .zip(forces)
                .skip(self.layers_from)
            {
                let u = c.point_velocity(v);
                let slip = u - c.normal * c.normal.dot(u);
                if *f > 0.0
                    && c.friction > 0.0
                    && slip.length() > STICK_SPEED
                    && last != Some(c.verts[0])
                {
                    self.layer_slipping += 1;
                    last = Some(c.verts[0]);
                }
            }
        }
        self.spring_forces.clear();
        self.arrival_forces.clear();
        self.pinch_grip = self.grip(contact_forces);
        self.layer_forces.clear();
        if let Some(forces) = contact_forces {
            let layers = self.constraints.contacts.iter().zip(forces);
            self.layer_forces.extend(
                layers
                    .skip(self.layers_from)
                    .map(|(c, f)| (c.verts[0], *f))
                    .filter(|(_, f)| *f > 0.0),
            );
            self.layer_forces.sort_by_key(|a| a.0);
            self.layer_forces.dedup_by(|b, a| {
                let same = a.0 == b.0;
                if same {
                    a.1 += b.1;
                }
                same
            });
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

    /// Feedback out: the normal impulse per unit mass the arrival springs and the filter gave
    /// each vertex they held, for the stage's friction, and in-solve friction's Coulomb limits
    /// for the next substep: `mu N` of this solve's normal impulses (zero for vertices not held
    /// now). The filter's impulse is the solver's `impulses` when it reports them, else
    /// estimated from the end forces (in `scratch`); see `held_feedback` in `vertex_contacts`.
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
        self.arrival_feedback(cloth, h);
        self.held_feedback(
            cloth,
            effects,
            v0,
            (t, h),
            solves_friction,
            impulses,
            scratch,
        );
    }
}
