//! The collision stage of a simulation step: takes the integrator's candidate end-of-step
//! positions/velocities and fixes them against obstacles and (optionally) the cloth itself.
//! This file holds what the stage owns (obstacles, per-vertex contact data, the colliders and
//! their buffers) and its accessors; `resolve.rs` holds the order of one `resolve`.

use super::broad::Aabb;
use super::contact::Contact;
use super::error::StageError;
use super::features::{FeatureCollider, FeatureContact, Features};
use super::feedback::Held;
use super::obstacle::Obstacle;
use super::self_contact::SelfCollider;
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
    pub(super) self_collider: Option<SelfCollider>,
    /// Per-obstacle edge/corner features and the cloth topology they are tested against.
    pub(super) features: Vec<Features>,
    pub(super) feature_collider: FeatureCollider,
    /// Per-vertex "moved by a feature contact" flags (reused).
    pub(super) feature_moved: Vec<bool>,
    /// Skip obstacles far from the cloth (on by default).
    pub(super) culling: bool,
    /// Per obstacle: near enough to the cloth to be tested this step.
    pub(super) near: Vec<bool>,
    /// Per vertex, the normals and normal velocity changes (m/s) the implicit solver's contact
    /// filter applied this step, one per held surface (see `set_held`); used once by the next
    /// `resolve`.
    pub(super) held: Vec<Held>,
    /// Per vertex: the normals of held surfaces whose friction the solver applied (zero:
    /// unused; see `set_friction_solved`); used once by the next `resolve`.
    pub(super) friction_solved: Vec<[Vec3; 3]>,
    /// The last `resolve`'s contacts of static obstacles' edges and corners.
    pub(super) feature_contacts: Vec<FeatureContact>,
    /// The cloth faces and edges (`verts` of [`super::FeatureContact`]) the solver held with
    /// an edge spring this step, sorted; see `set_sprung`. Used once by the next `resolve`.
    pub(super) sprung: Vec<[u32; 3]>,
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
            held: Vec::new(),
            friction_solved: Vec::new(),
            feature_contacts: Vec::new(),
            sprung: Vec::new(),
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
            self_collider,
            culling: true,
            near: Vec::new(),
        })
    }

    /// Turns far-obstacle culling on or off (off: every obstacle is tested every step; the
    /// results are the same, only slower).
    pub fn set_culling(&mut self, on: bool) {
        self.culling = on;
    }

    pub fn settings(&self) -> &CollisionSettings {
        &self.settings
    }

    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// Contacts found by the last `resolve` (for the implicit solver's filter and for metrics).
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// Records that the solver held `vertex` against a surface of normal `normal` this step,
    /// removing the normal velocity `dvn` (m/s, >= 0) that gravity would have given it (the
    /// caller's estimate of the filter's normal impulse per unit mass).
    /// The filter takes the normal impulse out of the stage's sight (the vertex arrives with no
    /// approaching velocity), so Coulomb friction in the next `resolve` adds `dvn` to the normal
    /// velocity change it sees; without it a held vertex slides frictionless. A vertex held by
    /// several surfaces (a wedge) gets one call per surface; a fourth one is ignored.
    pub fn set_held(&mut self, vertex: usize, normal: Vec3, dvn: f64) {
        if vertex >= self.n_vertices || !(dvn.is_finite() && dvn > 0.0) || !normal.is_finite() {
            return;
        }
        if self.held.len() != self.n_vertices {
            self.held.clear();
            self.held.resize(self.n_vertices, [(Vec3::ZERO, 0.0); 3]);
        }
        if let Some(slot) = self.held[vertex].iter_mut().find(|s| s.1 == 0.0) {
            *slot = (normal, dvn);
        }
    }

    /// Records that the solver applied the Coulomb friction of the surface with `normal` to
    /// `vertex` (held against it, see `set_held`): the next `resolve` leaves the tangential
    /// velocity of that contact alone instead of applying friction a second time.
    pub fn set_friction_solved(&mut self, vertex: usize, normal: Vec3) {
        if vertex >= self.n_vertices || !normal.is_finite() {
            return;
        }
        if self.friction_solved.len() != self.n_vertices {
            self.friction_solved.clear();
            self.friction_solved
                .resize(self.n_vertices, [Vec3::ZERO; 3]);
        }
        if let Some(slot) = self.friction_solved[vertex]
            .iter_mut()
            .find(|s| **s == Vec3::ZERO)
        {
            *slot = normal;
        }
    }

    /// The last `resolve`'s contacts of static obstacles' edges and corners with cloth faces and
    /// edges, for the implicit solver to hold as springs next substep.
    pub fn feature_contacts(&self) -> &[FeatureContact] {
        &self.feature_contacts
    }

    /// Records which feature contacts (their cloth faces and edges, `verts` of
    /// [`super::FeatureContact`]) the solver held with edge springs this step: the next `resolve`
    /// leaves those to the solver unless they end deep (see `features::DEEP`).
    pub fn set_sprung(&mut self, contacts: impl IntoIterator<Item = [u32; 3]>) {
        self.sprung.clear();
        self.sprung.extend(contacts);
        self.sprung.sort_unstable();
        self.sprung.dedup();
    }

    /// Coulomb coefficient between `vertex` and obstacle `obstacle` (the obstacle's own, else the
    /// cloth's).
    pub fn friction_coefficient(&self, vertex: usize, obstacle: usize) -> f64 {
        let cloth = self.friction.get(vertex).copied().unwrap_or(0.0);
        self.obstacles
            .get(obstacle)
            .and_then(|o| o.friction)
            .unwrap_or(cloth)
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
