//! The order of one `resolve` of the collision stage: obstacles culled, vertices against
//! obstacles, pinches and wedges, obstacle features against cloth faces and edges (and the
//! vertices they moved again), cloth against itself, then the penetration metric.

use super::contact::Contact;
use super::features::{ClothState, FeatureContact};
use super::feedback::SolverFeedback;
use super::pinch::{center_pinched, contacts_by_vertex};
use super::report::CollisionReport;
use super::stage::CollisionStage;
use super::wedge::separate_wedged;
use crate::{Pose, Vec3};
use std::time::Instant;

impl CollisionStage {
    /// Fixes candidate end-of-step positions `x1` and velocities `v1` (start positions `x0`, step
    /// `h`). Vertices with `inv_mass == 0` are never moved. `feedback` is what the solver did in
    /// this substep (the default when it held nothing; see [`SolverFeedback`]).
    pub fn resolve(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        h: f64,
        feedback: &SolverFeedback,
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
        self.vertex_pass(x0, x1, v1, inv_mass, h, n, feedback, None);
        let by_vertex = contacts_by_vertex(&self.contacts);
        let (obs, th) = (&self.obstacles, &self.thickness);
        let pinched = center_pinched(obs, th, &by_vertex, x0, x1, v1, n);
        separate_wedged(obs, th, &by_vertex, x0, x1, v1, n, &pinched);

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
            friction_solved: feedback.friction_solved_all(),
            sprung: feedback.sprung(),
        };
        self.feature_contacts.clear();
        let mut moved = std::mem::take(&mut self.feature_moved);
        moved.clear();
        moved.resize(n, false);
        for (oi, ((o, f), _)) in self
            .obstacles
            .iter()
            .zip(&self.features)
            .zip(&self.near)
            .enumerate()
            .filter(|(_, (_, near))| **near)
        {
            report.feature_contacts += self.feature_collider.resolve(
                o,
                oi,
                f,
                &state,
                &mut x1[..n],
                &mut v1[..n],
                &mut moved,
            );
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
            self.vertex_pass(x0, x1, v1, inv_mass, h, n, feedback, Some(&moved));
            self.contacts.sort_by_key(|c| (c.obstacle, c.vertex));
            self.contacts.reverse();
            self.contacts.dedup_by_key(|c| (c.obstacle, c.vertex));
            for (flag, &m) in self.in_contact.iter_mut().zip(&moved) {
                *flag |= m;
            }
            let by_vertex = contacts_by_vertex(&self.contacts);
            let (obs, th) = (&self.obstacles, &self.thickness);
            let pinched = center_pinched(obs, th, &by_vertex, x0, x1, v1, n);
            separate_wedged(obs, th, &by_vertex, x0, x1, v1, n, &pinched);
        }
        self.feature_moved = moved;
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
            report.self_contact = out.report;
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

/// What a substep's collision pass changes in the stage besides the cloth (obstacle poses and
/// the contacts fed forward to the next substep), saved so that a substep the guard rejects
/// after the collision pass can be redone from its start (see [`CollisionStage::save_into`]).
#[derive(Debug, Clone, Default)]
pub struct StageRollback {
    poses: Vec<(Pose, Pose)>,
    contacts: Vec<Contact>,
    feature_contacts: Vec<FeatureContact>,
}

/// Which of the stage's passes moved a cloth vertex in the last `resolve`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactKind {
    /// An obstacle's face held the vertex (the vertex pass).
    ObstacleVertex,
    /// An obstacle's edge, corner or rod axis pushed a cloth face or edge (the feature pass).
    Feature,
    /// Cloth against cloth (the self-contact pass; only when it is on).
    SelfContact,
}

impl std::fmt::Display for ContactKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ContactKind::ObstacleVertex => "obstacle contact (vertex against a face)",
            ContactKind::Feature => "obstacle feature contact (an edge or rod between vertices)",
            ContactKind::SelfContact => "self-contact",
        })
    }
}

impl CollisionStage {
    /// Saves the obstacle poses and the fed-forward contacts into `s` (its buffers reused).
    pub fn save_into(&self, s: &mut StageRollback) {
        s.poses.clear();
        s.poses
            .extend(self.obstacles.iter().map(|o| (o.pose_prev, o.pose)));
        s.contacts.clone_from(&self.contacts);
        s.feature_contacts.clone_from(&self.feature_contacts);
    }

    /// Moves the feature contacts of obstacles that move in the coming substep to where their
    /// features are at its end (`end_pose(k)`: obstacle `k`'s pose then, `None` when it does not
    /// move), for the solver's springs.
    pub fn aim_feature_contacts(&mut self, end_pose: impl Fn(usize) -> Option<Pose>) {
        for c in self.feature_contacts.iter_mut() {
            if let Some(pose) = end_pose(c.obstacle) {
                c.end_point = pose.transform_point(c.local);
                c.end_normal = (pose.rotation * c.local_normal).normalize();
                c.moving = true;
                c.mu = 0.0;
            }
        }
    }

    /// Puts back what [`Self::save_into`] saved.
    pub fn restore(&mut self, s: &StageRollback) {
        for (o, (a, b)) in self.obstacles.iter_mut().zip(&s.poses) {
            (o.pose_prev, o.pose) = (*a, *b);
        }
        self.contacts.clone_from(&s.contacts);
        self.feature_contacts.clone_from(&s.feature_contacts);
    }

    /// The pass of the last `resolve` that moved `vertex`, if one did (the feature pass first:
    /// it runs between the vertex passes and its moves are the ones the vertex pass re-tests),
    /// else self-contact when it is on and `moved` says the vertex moved.
    pub fn contact_kind(&self, vertex: usize, moved: bool) -> Option<ContactKind> {
        if self.feature_moved.get(vertex).copied().unwrap_or(false) {
            return Some(ContactKind::Feature);
        }
        if self.contacts.iter().any(|c| c.vertex as usize == vertex) {
            return Some(ContactKind::ObstacleVertex);
        }
        (moved && self.self_collider.is_some()).then_some(ContactKind::SelfContact)
    }
}
