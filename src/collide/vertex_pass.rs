//! The vertex pass of the collision stage: far obstacles culled, then every cloth vertex's swept
//! box against every near obstacle, answered by [`super::respond::obstacle_vertex`].

use super::broad::Aabb;
use super::exit::{exit_of, slips};
use super::feedback::SolverFeedback;
use super::respond::{obstacle_vertex, VertexInput};
use super::stage::CollisionStage;
use crate::Vec3;
use rayon::prelude::*;

impl CollisionStage {
    /// Marks the obstacles whose swept bounds come near the cloth's swept bounds this step;
    /// returns how many are far. The margin (three times the largest thickness plus the feature
    /// radius) covers every test the passes make: a vertex's box is inflated by its thickness,
    /// the obstacle's by the largest thickness, and a response moves a vertex by about one
    /// thickness.
    pub(super) fn cull(&mut self, x0: &[Vec3], x1: &[Vec3], max_th: f64) -> usize {
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

    /// Cloth vertices against every obstacle (all vertices, or those flagged in `only`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn vertex_pass(
        &mut self,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        h: f64,
        n: usize,
        feedback: &SolverFeedback,
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
        self.exit_moved.clear();
        if !self.exits.is_empty() {
            self.exit_moved.resize(n, 0.0);
        }
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
            let exits = &self.exits;
            let slip = &self.exit_slip;
            let moved = &self.exit_moved;
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
            let friction_solved = feedback.friction_solved_all();
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
                            friction: if slips(slip, i, oi) {
                                0.0
                            } else {
                                o.friction.unwrap_or(friction[i])
                            },
                            h,
                            mode,
                            response,
                            held: feedback.held(i),
                            friction_solved: friction_solved
                                .get(i)
                                .copied()
                                .unwrap_or([Vec3::ZERO; 3]),
                            exit: exit_of(exits, i, oi)
                                .map(|e| (e.dir, (e.cap - moved[i]).max(0.0), e.edge_inside)),
                            squeezed: feedback.squeezed_by(i, oi),
                        };
                        let (mut x, mut v) = (x1r[i], v1r[i]);
                        let c = obstacle_vertex(o, oi, &input, &mut x, &mut v)?;
                        Some((c, x, v))
                    }),
            );
            for &(c, x, v) in &self.scratch {
                let i = c.vertex as usize;
                // Whatever moved it counts against its lead-out's step (see `exit_moved`).
                if let Some(m) = self.exit_moved.get_mut(i) {
                    *m += (x - x1[i]).length();
                }
                x1[i] = x;
                v1[i] = v;
                self.in_contact[i] = true;
                self.contacts.push(c);
            }
        }
    }
}
