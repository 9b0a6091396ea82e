//! The collision stage of a simulation step: takes the integrator's candidate end-of-step
//! positions/velocities and fixes them against obstacles and (optionally) the cloth itself.

use super::broad::Aabb;
use super::features::{ClothState, FeatureCollider, Features};
use super::obstacle::Obstacle;
use super::respond::{obstacle_vertex, VertexInput};
use super::self_contact::SelfCollider;
use crate::{Pose, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// How contacts are detected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DetectionMode {
    /// Discrete: a sphere of radius `thickness` at each end-of-step vertex vs the obstacles at
    /// their end pose, and vs other vertices' spheres. Cheapest; misses thin features and fast
    /// motion (vertices can tunnel).
    Spheres,
    /// Discrete distance of each end-of-step vertex to the obstacles; cloth-cloth vertex-triangle
    /// and edge-edge proximity. Same obstacle test as `Spheres` (a point within `thickness` of a
    /// shape is a sphere touching it); better cloth-cloth coverage. Can still tunnel.
    Proximity,
    /// Swept tests over the step (obstacle motion included), then proximity. Cloth-cloth: CCD
    /// passes plus rigid impact zones, so the cloth never ends a step self-intersecting.
    Continuous,
}

/// How contacts are answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResponseMode {
    /// Positions snapped to `thickness` along the contact normal, velocities projected with
    /// Coulomb friction, and the friction's tangential velocity change applied to positions.
    Projection,
    /// Velocities projected with friction; positions only pushed out of the thickness layer; the
    /// caller feeds `contacts()` to the implicit solver's `(I - n n^T)` filter next step.
    Filter,
    /// Projection and the contacts for the filter.
    Both,
}

impl ResponseMode {
    /// Whether the implicit solver should constrain contact normals with `contacts()`.
    pub fn uses_filter(self) -> bool {
        matches!(self, ResponseMode::Filter | ResponseMode::Both)
    }

    pub(crate) fn projects_tangent(self) -> bool {
        matches!(self, ResponseMode::Projection | ResponseMode::Both)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionSettings {
    pub mode: DetectionMode,
    pub self_collision: bool,
    pub response: ResponseMode,
    /// Cloth-cloth passes (CCD passes in continuous mode, repulsion passes otherwise).
    pub self_iterations: usize,
    /// Rigid impact-zone passes before the last resort (freeze colliding vertices at x0).
    pub zone_iterations: usize,
    /// Count exact triangle-triangle intersections after each step (costly, for metrics).
    pub count_self_intersections: bool,
}

impl Default for CollisionSettings {
    fn default() -> Self {
        Self {
            mode: DetectionMode::Continuous,
            self_collision: false,
            response: ResponseMode::Both,
            self_iterations: 8,
            zone_iterations: 16,
            count_self_intersections: false,
        }
    }
}

/// A vertex touching an obstacle at the end of the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub vertex: u32,
    /// Unit world normal pointing out of the obstacle.
    pub normal: Vec3,
    /// World velocity of the obstacle's surface at the contact point.
    pub surface_velocity: Vec3,
    /// Index into the stage's obstacles.
    pub obstacle: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CollisionReport {
    /// Number of obstacle contacts (see `CollisionStage::contacts`).
    pub contacts: usize,
    /// Obstacle-feature vs cloth face/edge contacts answered (thin rods, box and mesh edges),
    /// summed over the detection passes.
    pub feature_contacts: usize,
    /// Deepest remaining penetration of a contact vertex into an obstacle's thickness layer after
    /// the response (m, >= 0).
    pub deepest_penetration: f64,
    /// Exact count of intersecting non-adjacent triangle pairs at the end of the step, when
    /// `count_self_intersections` is on and self-collision is enabled.
    pub self_intersections: Option<usize>,
    /// Cloth-cloth colliding pairs the fail-safe could not resolve (kinematic vertices involved,
    /// or the step started intersecting).
    pub unresolved: usize,
    /// Obstacles skipped because their swept bounds are far from the cloth's (see
    /// [`CollisionStage::set_culling`]).
    pub culled: usize,
    /// Wall time of `resolve`.
    pub time_s: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum StageError {
    #[error("triangle {tri} references vertex {vertex} but the cloth has {n} vertices")]
    BadTriangle { tri: usize, vertex: u32, n: usize },
    #[error("{what} has {got} entries, expected one per vertex ({n})")]
    BadLength {
        what: &'static str,
        got: usize,
        n: usize,
    },
    #[error("{what}[{index}] = {value} must be finite and >= 0")]
    BadValue {
        what: &'static str,
        index: usize,
        value: f64,
    },
}

/// Up to three (normal, normal velocity change) a vertex was held with (zero: unused).
pub(crate) type Held = [(Vec3, f64); 3];

pub struct CollisionStage {
    settings: CollisionSettings,
    obstacles: Vec<Obstacle>,
    n_vertices: usize,
    thickness: Vec<f64>,
    friction: Vec<f64>,
    contacts: Vec<Contact>,
    /// One obstacle's answers: contact, new position and velocity (reused across steps).
    scratch: Vec<(Contact, Vec3, Vec3)>,
    /// Swept vertex boxes of the current pass, the tested vertices by box low x, and one
    /// obstacle's candidates.
    vertex_boxes: Vec<Aabb>,
    order: Vec<u32>,
    candidates: Vec<usize>,
    /// Per-vertex "touches an obstacle" flags, for cloth-cloth mass weighting.
    in_contact: Vec<bool>,
    self_collider: Option<SelfCollider>,
    /// Per-obstacle edge/corner features and the cloth topology they are tested against.
    features: Vec<Features>,
    feature_collider: FeatureCollider,
    /// Per-vertex "moved by a feature contact" flags (reused).
    feature_moved: Vec<bool>,
    /// Skip obstacles far from the cloth (on by default).
    culling: bool,
    /// Per obstacle: near enough to the cloth to be tested this step.
    near: Vec<bool>,
    /// Per vertex, the normals and normal velocity changes (m/s) the implicit solver's contact
    /// filter applied this step, one per held surface (see `set_held`); used once by the next
    /// `resolve`.
    held: Vec<Held>,
    /// Per vertex: the normals of held surfaces whose friction the solver applied (zero:
    /// unused; see `set_friction_solved`); used once by the next `resolve`.
    friction_solved: Vec<[Vec3; 3]>,
    /// The last `resolve`'s contacts of static obstacles' edges and corners.
    feature_contacts: Vec<super::features::FeatureContact>,
    /// The cloth faces and edges (`verts` of [`super::FeatureContact`]) the solver held with
    /// an edge spring this step, sorted; see `set_sprung`. Used once by the next `resolve`.
    sprung: Vec<[u32; 3]>,
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

    /// Marks the obstacles whose swept bounds come near the cloth's swept bounds this step;
    /// returns how many are far. The margin (three times the largest thickness plus the feature
    /// radius) covers every test the passes make: a vertex's box is inflated by its thickness,
    /// the obstacle's by the largest thickness, and a response moves a vertex by about one
    /// thickness.
    fn cull(&mut self, x0: &[Vec3], x1: &[Vec3], max_th: f64) -> usize {
        let n_obs = self.obstacles.len();
        self.near.clear();
        self.near.resize(n_obs, true);
        if !self.culling || x0.is_empty() {
            return 0;
        }
        let (lo, hi) = x0
            .par_iter()
            .chain(x1.par_iter())
            .with_min_len(1024)
            .fold(
                || (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(*p), hi.max(*p)),
            )
            .reduce(
                || (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        if !(lo.is_finite() && hi.is_finite()) {
            return 0;
        }
        let mut far = 0;
        for ((o, f), near) in self
            .obstacles
            .iter()
            .zip(&self.features)
            .zip(self.near.iter_mut())
        {
            let (olo, ohi) = o.swept_aabb(3.0 * max_th + f.radius());
            if lo.cmpgt(ohi).any() || hi.cmplt(olo).any() {
                *near = false;
                far += 1;
            }
        }
        far
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
    pub fn feature_contacts(&self) -> &[super::features::FeatureContact] {
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

    /// The contacts sorted by vertex (contact order kept within a vertex), for the passes that
    /// look at all of one vertex's contacts together.
    fn contacts_by_vertex(&self) -> Vec<Contact> {
        let mut by_vertex = self.contacts.clone();
        by_vertex.sort_by_key(|c| c.vertex);
        by_vertex
    }

    /// A vertex touching two obstacles whose surfaces face each other closer than twice its
    /// thickness cannot be `thickness` away from both: projected out of one layer after the
    /// other, it ended inside the first obstacle's solid, and alternating projections step after
    /// step pumped energy into its springs. Put it midway between the two surfaces instead, with
    /// the normal velocity of their mean. Returns the centred vertices with their new state.
    fn center_pinched(
        &self,
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
                let o = &self.obstacles[group[k].obstacle];
                let local = o.pose.inverse_transform_point(x1[i]);
                let hint = o.pose_prev.inverse_transform_point(x0[i]);
                o.closest_local(local, hint).signed_distance
            };
            let (da, db) = (distance(a), distance(b));
            let th = self.thickness[i];
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

    /// A vertex in contact with two or more obstacles and not pinched between them (a wedge:
    /// cloth pressed by a robot's hand against its torso) is pushed out of one layer after
    /// the other, in obstacle order: leaving the last one along its normal can carry it back into
    /// an earlier one, whose solid it then ends inside. Alternating projections onto the layers
    /// converge to their intersection (each round shrinks the remaining depth by the cosine of
    /// the wedge's normals); approaching normal velocity is removed for each surface on the way.
    fn separate_wedged(
        &self,
        by_vertex: &[Contact],
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        n: usize,
        pinched: &[(usize, Vec3, Vec3)],
    ) {
        const ROUNDS: usize = 8;
        for group in by_vertex.chunk_by(|a, b| a.vertex == b.vertex) {
            let i = group[0].vertex as usize;
            // A pinched vertex (facing surfaces closer than two thicknesses) cannot leave both
            // layers: `center_pinched` put it midway.
            if group.len() < 2 || i >= n || pinched.iter().any(|p| p.0 == i) {
                continue;
            }
            let th = self.thickness[i];
            for _ in 0..ROUNDS {
                let mut moved = false;
                for &Contact {
                    obstacle: oi,
                    surface_velocity,
                    ..
                } in group
                {
                    let o = &self.obstacles[oi];
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

    /// Cloth vertices against every obstacle (all vertices, or those flagged in `only`).
    #[allow(clippy::too_many_arguments)]
    fn vertex_pass(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        h: f64,
        n: usize,
        only: Option<&[bool]>,
    ) {
        let mode = self.settings.mode;
        let response = self.settings.response;
        let max_th = self.thickness.iter().copied().fold(0.0, f64::max);
        // Swept vertex boxes, computed once per pass for every obstacle.
        let thickness = &self.thickness;
        self.vertex_boxes.clear();
        self.vertex_boxes
            .par_extend((0..n).into_par_iter().with_min_len(1024).map(|i| {
                if inv_mass[i] <= 0.0 || only.is_some_and(|m| !m[i]) {
                    return Aabb::EMPTY;
                }
                let th = Vec3::splat(thickness[i]);
                Aabb {
                    lo: x0[i].min(x1[i]) - th,
                    hi: x0[i].max(x1[i]) + th,
                }
            }));
        // Tested vertices sorted by the low x of their box: an obstacle visits only the run
        // whose x range can meet its own (the cloth is a sheet, so a 1-D sweep prunes well).
        let boxes = &self.vertex_boxes;
        self.order.clear();
        self.order.extend(
            (0..n as u32).filter(|&i| boxes[i as usize].lo.cmple(boxes[i as usize].hi).all()),
        );
        self.order
            .sort_unstable_by(|&a, &b| boxes[a as usize].lo.x.total_cmp(&boxes[b as usize].lo.x));
        let widest = self
            .order
            .iter()
            .map(|&i| boxes[i as usize].hi.x - boxes[i as usize].lo.x)
            .fold(0.0, f64::max);
        for (oi, o) in self.obstacles.iter().enumerate() {
            if !self.near.get(oi).copied().unwrap_or(true) {
                continue;
            }
            let (olo, ohi) = o.swept_aabb(max_th);
            let ob = Aabb { lo: olo, hi: ohi };
            let friction = &self.friction;
            let boxes = &self.vertex_boxes;
            // Skipped vertices carry the empty box, which an unbounded box would still "overlap".
            let meets = |i: usize| boxes[i].lo.cmple(boxes[i].hi).all() && boxes[i].overlaps(&ob);
            self.candidates.clear();
            let order = &self.order;
            let first = order.partition_point(|&i| boxes[i as usize].lo.x < ob.lo.x - widest);
            let last = order.partition_point(|&i| boxes[i as usize].lo.x <= ob.hi.x);
            self.candidates.extend(
                order[first..last.max(first)]
                    .iter()
                    .map(|&i| i as usize)
                    .filter(|&i| meets(i)),
            );
            self.candidates.sort_unstable();
            self.candidates.dedup();
            // Their answers computed in parallel on copies and written back (vertices are
            // independent within one obstacle), in vertex order.
            let x1r: &[Vec3] = x1;
            let v1r: &[Vec3] = v1;
            let held = &self.held;
            let friction_solved = &self.friction_solved;
            self.scratch.clear();
            self.scratch.par_extend(
                self.candidates
                    .par_iter()
                    .copied()
                    .with_min_len(32)
                    .filter_map(|i| {
                        let input = VertexInput {
                            vertex: i as u32,
                            x0: x0[i],
                            thickness: thickness[i],
                            friction: o.friction.unwrap_or(friction[i]),
                            h,
                            mode,
                            response,
                            held: held.get(i).copied().unwrap_or([(Vec3::ZERO, 0.0); 3]),
                            friction_solved: friction_solved
                                .get(i)
                                .copied()
                                .unwrap_or([Vec3::ZERO; 3]),
                        };
                        let (mut x, mut v) = (x1r[i], v1r[i]);
                        let c = obstacle_vertex(o, oi, &input, &mut x, &mut v)?;
                        Some((c, x, v))
                    }),
            );
            for &(c, x, v) in &self.scratch {
                let i = c.vertex as usize;
                x1[i] = x;
                v1[i] = v;
                self.in_contact[i] = true;
                self.contacts.push(c);
            }
        }
    }

    /// Fixes candidate end-of-step positions `x1` and velocities `v1` (start positions `x0`, step
    /// `h`). Vertices with `inv_mass == 0` are never moved.
    pub fn resolve(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        h: f64,
    ) -> CollisionReport {
        let start = Instant::now();
        let n = self
            .n_vertices
            .min(x0.len())
            .min(x1.len())
            .min(v1.len())
            .min(inv_mass.len());
        self.contacts.clear();
        self.in_contact.clear();
        self.in_contact.resize(self.n_vertices, false);
        let mode = self.settings.mode;
        let max_th = self.thickness.iter().copied().fold(0.0, f64::max);
        let culled = self.cull(&x0[..n], &x1[..n], max_th);
        self.vertex_pass(x0, x1, v1, inv_mass, h, n, None);
        let by_vertex = self.contacts_by_vertex();
        let pinched = self.center_pinched(&by_vertex, x0, x1, v1, n);
        self.separate_wedged(&by_vertex, x0, x1, v1, n, &pinched);

        let mut report = CollisionReport {
            culled,
            ..Default::default()
        };
        // Obstacle edges and thin parts that pass between cloth vertices.
        let state = ClothState {
            x0: &x0[..n],
            inv_mass: &inv_mass[..n],
            thickness: &self.thickness[..n],
            friction: &self.friction[..n],
            h,
            mode,
            friction_solved: &self.friction_solved,
            sprung: &self.sprung,
        };
        self.feature_contacts.clear();
        let mut moved = std::mem::take(&mut self.feature_moved);
        moved.clear();
        moved.resize(n, false);
        for ((o, f), _) in self
            .obstacles
            .iter()
            .zip(&self.features)
            .zip(&self.near)
            .filter(|(_, near)| **near)
        {
            report.feature_contacts +=
                self.feature_collider
                    .resolve(o, f, &state, &mut x1[..n], &mut v1[..n], &mut moved);
            self.feature_contacts
                .extend_from_slice(self.feature_collider.contacts());
        }
        // A pinched vertex cannot be `thickness` from both surfaces, so neither can the cloth
        // edges and faces around it be from the obstacles' edges: their feature contacts push it
        // along a slanted normal, the vertex pass and the centring restore only its height, and
        // the sideways part accumulated every substep, squeezing the cloth out from under a press
        // (9 J of spring energy, 3.1 m/s). Its place is the pinch's: undo the feature pass on it.
        for &(i, x, v) in &pinched {
            (x1[i], v1[i], moved[i]) = (x, v, false);
        }
        if report.feature_contacts > 0 {
            // A face pushed off a feature can carry a vertex into the obstacle's faces: test the
            // moved vertices again, keeping the latest contact per (obstacle, vertex).
            self.vertex_pass(x0, x1, v1, inv_mass, h, n, Some(&moved));
            self.contacts.sort_by_key(|c| (c.obstacle, c.vertex));
            self.contacts.reverse();
            self.contacts.dedup_by_key(|c| (c.obstacle, c.vertex));
            for (flag, &m) in self.in_contact.iter_mut().zip(&moved) {
                *flag |= m;
            }
            let by_vertex = self.contacts_by_vertex();
            let pinched = self.center_pinched(&by_vertex, x0, x1, v1, n);
            self.separate_wedged(&by_vertex, x0, x1, v1, n, &pinched);
        }
        self.feature_moved = moved;
        self.held.clear();
        self.friction_solved.clear();
        self.sprung.clear();
        if let Some(sc) = self.self_collider.as_mut() {
            let out = sc.resolve(
                &self.settings,
                x0,
                x1,
                v1,
                inv_mass,
                &self.thickness,
                &self.friction,
                &self.in_contact,
                h,
            );
            report.unresolved = out.unresolved;
            if self.settings.count_self_intersections {
                report.self_intersections = Some(sc.count_intersections(x1));
            }
        }

        // Penetration after the whole response, measured on contact vertices.
        let mut deepest: f64 = 0.0;
        for c in &self.contacts {
            let o = &self.obstacles[c.obstacle];
            let i = c.vertex as usize;
            let local = o.pose.inverse_transform_point(x1[i]);
            let hint = o.pose_prev.inverse_transform_point(x0[i]);
            // Only penetrations count: a surface farther than the thickness adds nothing.
            if let Some(sp) = o.closest_local_within(local, hint, self.thickness[i]) {
                deepest = deepest.max(self.thickness[i] - sp.signed_distance);
            }
        }
        report.contacts = self.contacts.len();
        report.deepest_penetration = deepest.max(0.0);
        report.time_s = start.elapsed().as_secs_f64();
        report
    }
}
