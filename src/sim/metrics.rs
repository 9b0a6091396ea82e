//! What one frame step did: the metrics every step reports, gathered from the solver's and
//! the collision stage's reports of each substep.

use super::limit::LimitPass;
use crate::collide::{CollisionReport, SelfContactReport};
use crate::integrate::{LinearPath, StepReport};

/// What one frame step did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepMetrics {
    pub time: f64,
    pub substeps: u32,
    /// Substeps that were redone as smaller steps by the divergence guard.
    pub subdivisions: u32,
    /// Substeps split in two because an obstacle moved fast relative to the cloth near it, or
    /// rolled back and split because the collision response moved a vertex more than a third of
    /// its spacing (see `sim::fast`): the contact is resolved in steps the collision stage can
    /// follow.
    pub contact_splits: u32,
    /// Substeps in which an obstacle still outran the cloth, or the response still jumped a
    /// vertex, but the guard's `max_contact_split_levels` allowed no further split: the contact
    /// was answered coarser than fast contact asks (see `sim::fast`).
    pub contact_splits_refused: u32,
    pub force_evaluations: u32,
    pub cg_iterations: u32,
    pub cg_residual_max: f64,
    /// Wall time of the conjugate-gradient iterations (s) and their floating-point operations
    /// and least bytes streamed (see [`StepReport::cg_bytes`]).
    pub cg_time_s: f64,
    pub cg_flops: f64,
    pub cg_bytes: f64,
    /// The implicit step's linear path (last substep; `None` for explicit methods).
    pub linear_path: Option<LinearPath>,
    /// Wall time (s) of the linear solves' setup (Cholesky factorisations or multigrid
    /// updates) and of assembling the systems (see [`StepReport::setup_time_s`]).
    pub setup_time_s: f64,
    pub assembly_time_s: f64,
    /// Numeric Cholesky factorisations and symbolic analyses (the direct path).
    pub factorisations: u32,
    pub analyses: u32,
    pub kinetic_energy: f64,
    pub potential_energy: f64,
    pub max_speed: f64,
    pub wall_time_s: f64,
    /// Obstacle contacts at the end of the step.
    pub contacts: usize,
    /// Deepest penetration into an obstacle's thickness layer over the step's substeps (m).
    pub deepest_penetration: f64,
    /// Intersecting non-adjacent triangle pairs at the end of the step, when counted.
    pub self_intersections: Option<usize>,
    /// Cloth-cloth pairs the collision fail-safe could not resolve.
    pub unresolved_contacts: usize,
    pub collision_time_s: f64,
    /// Obstacles skipped by the collision stage as far from the cloth (last substep).
    pub culled_obstacles: usize,
    /// Vertices that started inside a solid obstacle and are still on their way out (last
    /// substep; see `CollisionStage::plan_exits`).
    pub exiting_vertices: usize,
    /// Cloth-cloth counts summed over the substeps (largest zone: the largest seen).
    pub self_contact: SelfContactReport,
    /// Cloth-cloth contacts whose friction slid in the step's last substep: vertices over
    /// another layer's face whose in-solve friction ended slipping, plus the pairs the
    /// collision pass's impulses left sliding at their Coulomb limit.
    pub slipping_vertices: usize,
    /// Edges the strain limit shortened after the solves, summed over the substeps (`None`:
    /// no material sets `strain_limit`).
    pub strain_limited: Option<u32>,
    /// Largest elongation beyond the strain limit its passes left, over the substeps, as a
    /// fraction of the allowed length (0: the limit held; see `sim::limit`).
    pub strain_limit_excess: f64,
    /// Vertices squeezed between two obstacle surfaces (a pinch: finger pads closed on cloth),
    /// in the last substep's solve.
    pub pinched_vertices: usize,
    /// Kinematic vertices (pinned, attached, grasped) inside an obstacle's solid at the step's
    /// end, and the deepest (m; an obstacle's own mesh inside by its winding number): the scene
    /// drives held cloth into a solid (a trajectory that folds a link onto the hand holding the
    /// cloth, fingers closing past the cloth a grasp rule holds), which no response can move,
    /// and the free cloth around it is torn between the two.
    pub held_inside: usize,
    pub held_inside_depth: f64,
    /// The pinch's grip in the last substep's solve (N): over the pinched vertices, the sum of
    /// the mean normal force of their two sides (what each pad presses the cloth with; the
    /// friction holding it is at most `mu` times twice this).
    pub grip_normal_force: f64,
}

impl StepMetrics {
    /// Adds one solve's counts.
    pub(super) fn add_solve(&mut self, stats: &StepReport) {
        self.force_evaluations += stats.force_evaluations;
        self.cg_iterations += stats.cg_iterations;
        self.cg_residual_max = self.cg_residual_max.max(stats.cg_residual);
        self.cg_time_s += stats.cg_time_s;
        self.cg_flops += stats.cg_flops;
        self.cg_bytes += stats.cg_bytes;
        self.linear_path = stats.linear_path;
        self.setup_time_s += stats.setup_time_s;
        self.assembly_time_s += stats.assembly_time_s;
        self.factorisations += stats.factorisations;
        self.analyses += stats.analyses;
    }

    /// Sets the last substep's pinched vertices and grip normal force (N).
    pub(super) fn add_pinch(&mut self, (vertices, force): (usize, f64)) {
        self.pinched_vertices = vertices;
        self.grip_normal_force = force;
    }

    /// Adds one substep's strain limiting.
    pub(super) fn add_limit(&mut self, r: &LimitPass) {
        *self.strain_limited.get_or_insert(0) += r.shortened;
        self.strain_limit_excess = self.strain_limit_excess.max(r.excess);
    }

    /// Adds one collision pass: the last substep's contacts and culling, the deepest
    /// penetration and intersection count over the substeps, the sums of the rest.
    pub(super) fn add_collision(&mut self, r: &CollisionReport) {
        self.contacts = r.contacts;
        self.deepest_penetration = self.deepest_penetration.max(r.deepest_penetration);
        self.self_intersections = match (self.self_intersections, r.self_intersections) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
        self.unresolved_contacts += r.unresolved;
        self.collision_time_s += r.time_s;
        self.culled_obstacles = r.culled;
        self.exiting_vertices = r.exiting;
        self.self_contact.add(&r.self_contact);
        self.slipping_vertices += r.self_contact.slipping;
    }
}
