//! The order of one `resolve` of the collision stage: obstacles culled, vertices against
//! obstacles, pinches and wedges, obstacle features against cloth faces and edges (and the
//! vertices they moved again), cloth against itself (and the vertices it moved against the
//! obstacles again, then its CCD again), then the penetration metric.

use super::contact::Contact;
use super::exit::{exit_of, is_exiting};
use super::features::{ClothState, FeatureContact};
use super::feedback::SolverFeedback;
use super::pinch::{center_pinched, contacts_by_vertex, pinched_by};
use super::report::CollisionReport;
use super::self_contact::{Repelled, SelfCollider, SelfOutcome, SelfTouch};
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
        self.resolve_with(x0, x1, v1, inv_mass, h, feedback, |_, _| {}, &mut |_, _| {})
    }

    /// [`Self::resolve`], with `between` run on the positions after the obstacles' passes and
    /// before cloth-cloth contact, which then sees what it moved, and `repelled` on cloth-cloth
    /// repulsion's answers before its CCD passes (the simulation holds both to a stretch bound
    /// there, `sim::limit::ResponseBound`).
    #[allow(clippy::too_many_arguments)]
    pub fn resolve_with(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        h: f64,
        feedback: &SolverFeedback,
        between: impl FnOnce(&CollisionStage, &mut [Vec3]),
        repelled: Repelled,
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
        let by_vertex = contacts_by_vertex(&self.contacts, &self.exits);
        let (obs, th) = (&self.obstacles, &self.thickness);
        let pinched = center_pinched(obs, feedback, th, &by_vertex, x0, x1, v1, n);
        separate_wedged(obs, th, &by_vertex, x0, x1, v1, n, &pinched);
        let pinched_by = pinched_by(&pinched, feedback, n);

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
            exits: &self.exits,
            slip: &self.exit_slip,
            pinched_by: &pinched_by,
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
        // the sideways part would accumulate every substep, squeezing the cloth out from under a
        // press at metres per second. Its place is the pinch's: undo the feature pass on it.
        // (The feature pass skips the faces and edges of a vertex pinched by the same obstacle:
        // the squeeze of the cloth there is the pinch's compliance, see `ClothState`.)
        for &(i, x, v, _) in &pinched {
            (x1[i], v1[i], moved[i]) = (x, v, false);
        }
        if report.feature_contacts > 0 {
            // A face pushed off a feature can carry a vertex into the obstacle's faces: test the
            // moved vertices again, keeping the latest contact per (obstacle, vertex).
            self.vertex_pass(x0, x1, v1, inv_mass, h, n, feedback, Some(&moved));
            self.keep_latest_contacts();
            for (flag, &m) in self.in_contact.iter_mut().zip(&moved) {
                *flag |= m;
            }
            let by_vertex = contacts_by_vertex(&self.contacts, &self.exits);
            let (obs, th) = (&self.obstacles, &self.thickness);
            let pinched = center_pinched(obs, feedback, th, &by_vertex, x0, x1, v1, n);
            separate_wedged(obs, th, &by_vertex, x0, x1, v1, n, &pinched);
        }
        self.feature_moved = moved;
        between(self, &mut x1[..n]);
        if let Some(mut sc) = self.self_collider.take() {
            self.resolve_self(
                &mut sc,
                &mut report,
                (x0, x1, v1),
                inv_mass,
                h,
                n,
                feedback,
                repelled,
            );
            if self.settings.count_self_intersections {
                report.self_intersections = Some(sc.count_intersections(x1));
            }
            self.self_collider = Some(sc);
        }

        // Penetration after the whole response, measured on contact vertices; cloth the scene
        // started inside an obstacle is not the step's penetration while it is led out (it is
        // counted as `exiting` instead).
        let mut deepest: f64 = 0.0;
        let led_out = |c: &&Contact| exit_of(&self.exits, c.vertex as usize, c.obstacle).is_some();
        for c in self.contacts.iter().filter(|c| !led_out(c)) {
            let o = &self.obstacles[c.obstacle];
            let i = c.vertex as usize;
            let local = o.pose.inverse_transform_point(x1[i]);
            let hint = o.pose_prev.inverse_transform_point(x0[i]);
            // Only penetrations count: a surface farther than the thickness adds nothing.
            if let Some(sp) = o.closest_local_within(local, hint, self.thickness[i]) {
                deepest = deepest.max(self.thickness[i] - sp.signed_distance);
            }
        }
        // And the vertices cloth-cloth contact moved, which the vertex pass may not have seen.
        if self.self_collider.is_some() {
            deepest = deepest.max(self.self_moved_penetration(x0, x1, n));
        }
        self.retire_exits(&x1[..n], &inv_mass[..n]);
        report.exiting = self.exits.len();
        report.contacts = self.contacts.len();
        report.deepest_penetration = deepest.max(0.0);
        report.time_s = start.elapsed().as_secs_f64();
        report
    }
}

/// Most rounds of cloth-cloth contact and the obstacle re-test of the vertices it moved.
const SELF_OBSTACLE_ROUNDS: usize = 4;

impl CollisionStage {
    /// Cloth against itself, then the vertices it moved against the obstacles again, and where
    /// that moved any, CCD against itself once more (no second repulsion: it would push the
    /// pairs the first left short again, doubling the push cap and overstretching the 2x
    /// crumple), up to [`SELF_OBSTACLE_ROUNDS`] times. A cloth-cloth correction moves a layer
    /// as far as the pair needs, which can carry a vertex into an obstacle, and unmeasured:
    /// without the re-test a crumpled heap ends substeps with vertices millimetres below the
    /// ground. Every vertex it moved is tested, those the vertex pass held against an obstacle
    /// too: they answer cloth-cloth contact as heavier, but still give way, and left out,
    /// crumple.yaml ends frames with vertices inside the ground's thickness layer. Not those on
    /// their way out of an obstacle the scene started them in: each round's lead-out would move
    /// them again (`tests/start_inside.rs`' cape with self-collision overstretches).
    #[allow(clippy::too_many_arguments)]
    fn resolve_self(
        &mut self,
        sc: &mut SelfCollider,
        report: &mut CollisionReport,
        (x0, x1, v1): (&[Vec3], &mut [Vec3], &mut [Vec3]),
        inv_mass: &[f64],
        h: f64,
        n: usize,
        feedback: &SolverFeedback,
        repelled: Repelled,
    ) {
        let mut before = std::mem::take(&mut self.before_self);
        before.clear();
        before.extend_from_slice(&x1[..n]);
        let mut mark = std::mem::take(&mut self.round_start);
        mark.clone_from(&before);
        let mut moved = std::mem::take(&mut self.self_moved);
        let mut out = self.self_pass(sc, x0, x1, v1, inv_mass, h, Some(repelled));
        for _ in 1..SELF_OBSTACLE_ROUNDS {
            moved.clear();
            let exits = &self.exits;
            let led_out = |i: usize| self.in_contact[i] && is_exiting(exits, i);
            moved.extend((0..n).map(|i| x1[i] != mark[i] && !led_out(i)));
            if !moved.iter().any(|&m| m) {
                break;
            }
            mark.clear();
            mark.extend_from_slice(&x1[..n]);
            self.vertex_pass(x0, x1, v1, inv_mass, h, n, feedback, Some(&moved));
            self.keep_latest_contacts();
            // Only the re-tested vertices can have moved: bring the mark up to date on them.
            let mut pushed = false;
            for ((m, &x), _) in mark
                .iter_mut()
                .zip(&x1[..n])
                .zip(&moved)
                .filter(|(_, &mv)| mv)
            {
                if *m != x {
                    (*m, pushed) = (x, true);
                }
            }
            if !pushed {
                break;
            }
            let again = self.self_pass(sc, x0, x1, v1, inv_mass, h, None);
            out.report.add(&again.report);
            out.report.obstacle_retests += 1;
            out.unresolved = again.unresolved;
        }
        // The layers resting on each other now: this substep's, and the last one's still over
        // their faces (see `SelfTouch`).
        let mut touches = std::mem::take(&mut self.touches_next);
        super::self_contact::refresh_touches(
            sc.touches(),
            &self.self_touches,
            &x1[..n],
            |v| sc.faces_around(v),
            &mut touches,
        );
        self.touches_next = std::mem::replace(&mut self.self_touches, touches);
        // What the penetration metric measures besides the contacts: every vertex moved here.
        moved.clear();
        moved.extend((0..n).map(|i| x1[i] != before[i]));
        (self.self_moved, self.before_self, self.round_start) = (moved, before, mark);
        report.unresolved = out.unresolved;
        report.self_contact = out.report;
    }
}

impl CollisionStage {
    /// One cloth-cloth pass over the stage's per-vertex data: the step's first, with its
    /// repulsion and the hook on its answers (`repelled`), or a later one.
    #[allow(clippy::too_many_arguments)]
    fn self_pass(
        &self,
        sc: &mut SelfCollider,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        h: f64,
        repelled: Option<Repelled>,
    ) -> SelfOutcome {
        let first = repelled.is_some();
        let mut none = |_: &[Vec3], _: &mut [Vec3]| {};
        sc.resolve(
            &self.settings,
            x0,
            x1,
            v1,
            inv_mass,
            &self.thickness,
            &self.friction,
            &self.in_contact,
            h,
            first,
            repelled.unwrap_or(&mut none),
        )
    }

    /// After a re-test by the vertex pass: one contact per (obstacle, vertex), the latest.
    fn keep_latest_contacts(&mut self) {
        self.contacts.sort_by_key(|c| (c.obstacle, c.vertex));
        self.contacts.reverse();
        self.contacts.dedup_by_key(|c| (c.obstacle, c.vertex));
    }
}

impl CollisionStage {
    /// Deepest penetration into an obstacle's thickness layer of a vertex cloth-cloth contact
    /// moved (0 when none), over the obstacles near enough to be tested this step: the vertex
    /// pass's contacts are measured by the caller, these may not be among them.
    fn self_moved_penetration(&self, x0: &[Vec3], x1: &[Vec3], n: usize) -> f64 {
        let moved = &self.self_moved;
        let mut deepest: f64 = 0.0;
        let max_th = self.thickness.iter().copied().fold(0.0, f64::max);
        for (oi, o) in self.obstacles.iter().enumerate() {
            if !self.near.get(oi).copied().unwrap_or(true) {
                continue;
            }
            let (lo, hi) = o.swept_aabb(max_th);
            let judged = |i: usize| {
                moved.get(i).copied().unwrap_or(false) && exit_of(&self.exits, i, oi).is_none()
            };
            for i in (0..n).filter(|&i| judged(i)) {
                let p = x1[i];
                if p.cmplt(lo).any() || p.cmpgt(hi).any() {
                    continue;
                }
                let local = o.pose.inverse_transform_point(p);
                let hint = o.pose_prev.inverse_transform_point(x0[i]);
                if let Some(sp) = o.closest_local_within(local, hint, self.thickness[i]) {
                    deepest = deepest.max(self.thickness[i] - sp.signed_distance);
                }
            }
        }
        deepest
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
    self_touches: Vec<SelfTouch>,
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
        s.self_touches.clone_from(&self.self_touches);
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
        self.self_touches.clone_from(&s.self_touches);
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
