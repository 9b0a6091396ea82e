//! The order of one `resolve` of the collision stage: obstacles culled, vertices against
//! obstacles, pinches and wedges, obstacle features against cloth faces and edges (and the
//! vertices they moved again), cloth against itself, then the penetration metric.

use super::features::ClothState;
use super::feedback::SolverFeedback;
use super::pinch::{center_pinched, contacts_by_vertex};
use super::report::CollisionReport;
use super::stage::CollisionStage;
use super::wedge::separate_wedged;
use crate::Vec3;
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
