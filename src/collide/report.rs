//! What one `resolve` of the collision stage did (metrics).

use super::self_contact::SelfContactReport;

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CollisionReport {
    /// Number of obstacle contacts (see `CollisionStage::contacts`).
    pub contacts: usize,
    /// Obstacle-feature vs cloth face/edge contacts answered (thin rods, box and mesh edges),
    /// summed over the detection passes.
    pub feature_contacts: usize,
    /// Deepest remaining penetration of a contact vertex into an obstacle's thickness layer after
    /// the response (m, >= 0); not of cloth the scene started inside an obstacle while it is
    /// led out (`exiting`).
    pub deepest_penetration: f64,
    /// Exact count of intersecting non-adjacent triangle pairs at the end of the step, when
    /// `count_self_intersections` is on and self-collision is enabled.
    pub self_intersections: Option<usize>,
    /// Cloth-cloth colliding pairs the fail-safe could not resolve (kinematic vertices involved,
    /// or the step started intersecting).
    pub unresolved: usize,
    /// What cloth-cloth collision did (counts; zero without self-collision).
    pub self_contact: SelfContactReport,
    /// Obstacles skipped because their swept bounds are far from the cloth's (see
    /// [`super::CollisionStage::set_culling`]).
    pub culled: usize,
    /// Vertices that started inside a solid obstacle and are still on their way out (see
    /// [`super::CollisionStage::plan_exits`]).
    pub exiting: usize,
    /// Wall time of `resolve`.
    pub time_s: f64,
}
