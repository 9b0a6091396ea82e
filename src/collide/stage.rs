//! The collision stage of a simulation step: takes the integrator's candidate end-of-step
//! positions/velocities and fixes them against obstacles and (optionally) the cloth itself.
//! This file holds what the stage owns (obstacles, per-vertex contact data, the colliders and
//! their buffers) and its accessors; `resolve.rs` holds the order of one `resolve`.

use super::broad::Aabb;
use super::contact::Contact;
use super::error::StageError;
use super::exit::Exit;
use super::features::{FeatureCollider, FeatureContact, Features};
use super::obstacle::Obstacle;
use super::self_contact::{SelfCollider, SelfTouch};
use super::settings::CollisionSettings;
use crate::{Pose, Vec3};

pub struct CollisionStage {
    pub(super) settings: CollisionSettings,
    pub(super) obstacles: Vec<Obstacle>,
    pub(super) n_vertices: usize,
    pub(super) thickness: Vec<f64>,
    pub(super) friction: Vec<f64>,
    pub(super) contacts: Vec<Contact>,
    /// One obstacle's answers: contact, new position and velocity (reused across steps).
    pub(super) scratch: Vec<(Contact, Vec3, Vec3)>,
    /// Swept vertex boxes of the current pass, the tested vertices by box low x, and one
    /// obstacle's candidates.
    pub(super) vertex_boxes: Vec<Aabb>,
    pub(super) order: Vec<u32>,
    pub(super) candidates: Vec<usize>,
    /// Per-vertex "touches an obstacle" flags, for cloth-cloth mass weighting.
    pub(super) in_contact: Vec<bool>,
    /// The end positions before cloth-cloth contact and at the last pass of it or of its
    /// obstacle re-test, and per vertex whether cloth-cloth contact moved it (reused).
    pub(super) before_self: Vec<Vec3>,
    pub(super) round_start: Vec<Vec3>,
    pub(super) self_moved: Vec<bool>,
    pub(super) self_collider: Option<SelfCollider>,
    /// The layers resting on each other at the end of the last `resolve`, sorted by (vertex,
    /// triangle), and a buffer for the next (see [`SelfTouch`]).
    pub(super) self_touches: Vec<SelfTouch>,
    pub(super) touches_next: Vec<SelfTouch>,
    /// Per-obstacle edge/corner features and the cloth topology they are tested against.
    pub(super) features: Vec<Features>,
    pub(super) feature_collider: FeatureCollider,
    /// Per-vertex "moved by a feature contact" flags (reused).
    pub(super) feature_moved: Vec<bool>,
    /// Skip obstacles far from the cloth (on by default).
    pub(super) culling: bool,
    /// Per obstacle: near enough to the cloth to be tested this step.
    pub(super) near: Vec<bool>,
    /// The last `resolve`'s contacts of static obstacles' edges and corners.
    pub(super) feature_contacts: Vec<FeatureContact>,
    /// Vertices that started inside a solid obstacle and are not out yet, sorted by vertex
    /// (`overlap.rs`).
    pub(super) exits: Vec<Exit>,
    /// The exits' mesh neighbours (see [`Exit::first`]).
    pub(super) exit_neighbours: Vec<u32>,
    /// Per vertex, how far the lead-outs moved it in the current vertex pass (reused): a vertex
    /// inside two solids (where the upper arm meets the forearm) follows both plans, and the
    /// two share one step.
    pub(super) exit_moved: Vec<f64>,
    /// (vertex, obstacle) pairs without friction while a patch leaves that obstacle: its
    /// exiting vertices and their mesh neighbours, sorted (see [`exit::slip_around`]).
    ///
    /// [`exit::slip_around`]: super::exit::slip_around
    pub(super) exit_slip: Vec<(u32, u32)>,
}

impl CollisionStage {
    /// `triangles` index the flat particle array of all cloths; `thickness` (m, the contact radius
    /// of each vertex) and `friction` (Coulomb mu) are per vertex.
    pub fn new(
        settings: CollisionSettings,
        obstacles: Vec<Obstacle>,
        triangles: Vec<[u32; 3]>,
        n_vertices: usize,
        thickness: Vec<f64>,
        friction: Vec<f64>,
    ) -> Result<Self, StageError> {
        for (what, v) in [("thickness", &thickness), ("friction", &friction)] {
            if v.len() != n_vertices {
                return Err(StageError::BadLength {
                    what,
                    got: v.len(),
                    n: n_vertices,
                });
            }
            if let Some(i) = v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(StageError::BadValue {
                    what,
                    index: i,
                    value: v[i],
                });
            }
        }
        for (k, t) in triangles.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= n_vertices) {
                return Err(StageError::BadTriangle {
                    tri: k,
                    vertex: v,
                    n: n_vertices,
                });
            }
        }
        let self_collider = settings
            .self_collision
            .then(|| SelfCollider::new(&triangles, n_vertices));
        let features = obstacles.iter().map(Features::of).collect();
        let feature_collider = FeatureCollider::new(&triangles);
        Ok(Self {
            settings,
            features,
            feature_collider,
            feature_moved: Vec::new(),
            feature_contacts: Vec::new(),
            obstacles,
            n_vertices,
            thickness,
            friction,
            contacts: Vec::new(),
            scratch: Vec::new(),
            vertex_boxes: Vec::new(),
            order: Vec::new(),
            candidates: Vec::new(),
            in_contact: vec![false; n_vertices],
            before_self: Vec::new(),
            round_start: Vec::new(),
            self_moved: Vec::new(),
            self_collider,
            self_touches: Vec::new(),
            touches_next: Vec::new(),
            culling: true,
            near: Vec::new(),
            exits: Vec::new(),
            exit_neighbours: Vec::new(),
            exit_moved: Vec::new(),
            exit_slip: Vec::new(),
        })
    }

    /// Turns far-obstacle culling on or off (off: every obstacle is tested every step; the
    /// results are the same, only slower).
    pub fn set_culling(&mut self, on: bool) {
        self.culling = on;
    }

    /// Seams being sewn: `seams[k]` pairs the vertices seam k pulls together. Until the stage is
    /// replaced (the weld), self-contact skips every pair across a seam's neighbourhoods, so
    /// repulsion does not hold the seam open. No effect without self-collision.
    pub fn set_sewing_seams(&mut self, seams: &[Vec<(u32, u32)>], x: &[Vec3]) {
        if let Some(sc) = self.self_collider.as_mut() {
            sc.set_seams(seams, x, &self.thickness);
        }
    }

    pub fn settings(&self) -> &CollisionSettings {
        &self.settings
    }

    /// Vertex `i`'s contact thickness (m; 0 past the cloth).
    pub fn thickness_of(&self, i: usize) -> f64 {
        self.thickness.get(i).copied().unwrap_or(0.0)
    }

    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// Contacts found by the last `resolve` (for the implicit solver's filter and for metrics).
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// The last `resolve`'s contacts of static obstacles' edges and corners with cloth faces and
    /// edges, for the implicit solver to hold as springs next substep.
    pub fn feature_contacts(&self) -> &[FeatureContact] {
        &self.feature_contacts
    }

    /// The last `resolve`'s pairs of cloth layers resting on each other (a vertex over a face of
    /// another layer), for the implicit solver to hold apart next substep; empty without
    /// self-collision.
    pub fn self_touches(&self) -> &[SelfTouch] {
        &self.self_touches
    }

    /// Coulomb coefficient between `vertex` and obstacle `obstacle` (the obstacle's own, else the
    /// cloth's; 0 beside a lead-out from that obstacle, see [`super::exit::slip_around`]).
    pub fn friction_coefficient(&self, vertex: usize, obstacle: usize) -> f64 {
        if super::exit::slips(&self.exit_slip, vertex, obstacle) {
            return 0.0;
        }
        let cloth = self.friction.get(vertex).copied().unwrap_or(0.0);
        self.obstacles
            .get(obstacle)
            .and_then(|o| o.friction)
            .unwrap_or(cloth)
    }

    /// Whether `vertex` is being led out of obstacle `obstacle` (it started inside it or in its
    /// contact layer, see `overlap.rs`): its contact is the lead-out's, not a surface's.
    pub fn leads_out(&self, vertex: usize, obstacle: usize) -> bool {
        super::exit::exit_of(&self.exits, vertex, obstacle).is_some()
    }

    /// Moves scripted obstacles over `[t0, t1]`: `pose_prev = pose_at(t0)`, `pose = pose_at(t1)`.
    /// External obstacles keep their last pose as `pose_prev` (call `set_obstacle_pose` after).
    pub fn advance_obstacles(&mut self, t0: f64, t1: f64) {
        for o in &mut self.obstacles {
            if o.motion.is_scripted() {
                o.pose_prev = o.motion.pose_at(&o.initial_pose, t0);
                o.pose = o.motion.pose_at(&o.initial_pose, t1);
            } else {
                o.pose_prev = o.pose;
            }
        }
    }

    /// Sets the end-of-step pose of obstacle `idx` (robot-driven). Ignored for an invalid index
    /// or a non-finite pose (returns false).
    pub fn set_obstacle_pose(&mut self, idx: usize, pose: Pose) -> bool {
        match self.obstacles.get_mut(idx) {
            Some(o) if pose.is_finite() => {
                o.pose = pose;
                true
            }
            _ => false,
        }
    }
}
