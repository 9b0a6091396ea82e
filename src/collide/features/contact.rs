//! Feature contacts: the CCD's hits, the cloth state the passes share, and the contacts of
//! static obstacles handed to the solver.

use crate::collide::exit::Exit;
use crate::collide::settings::DetectionMode;
use crate::Vec3;

/// One feature-vs-cloth contact found by the CCD.
#[derive(Debug, Clone, Copy)]
pub(super) struct Hit {
    pub t: f64,
    pub verts: [u32; 3],
    pub w: [f64; 3],
    /// World unit normal from the feature towards the side the cloth came from.
    pub normal: Vec3,
    /// Feature contact point in the obstacle's local frame.
    pub local: Vec3,
}

/// Per-step inputs shared by detection and response.
pub(crate) struct ClothState<'a> {
    pub x0: &'a [Vec3],
    pub inv_mass: &'a [f64],
    pub thickness: &'a [f64],
    pub friction: &'a [f64],
    pub h: f64,
    pub mode: DetectionMode,
    /// Per vertex, the normals whose friction the solver applied (empty: none).
    pub friction_solved: &'a [[Vec3; 3]],
    /// The cloth faces and edges the solver held with an edge spring this step (sorted).
    pub sprung: &'a [[u32; 3]],
    /// Vertices on their way out of an obstacle they started inside (`overlap.rs`): features
    /// skip their faces and edges, which cross the obstacle by construction (the arm's rod axes
    /// and box edges would push those patches out sideways at once, tearing them far past rest).
    pub exits: &'a [Exit],
    /// (vertex, obstacle) pairs without friction beside a lead-out (`exit::slip_around`).
    pub slip: &'a [(u32, u32)],
    /// Per vertex (empty: none), the two obstacles pinching it (`pinch.rs`): an obstacle's
    /// features skip the faces and edges of a vertex it pinches. The cloth between a pinched
    /// vertex and the pad's edge is squeezed like the vertex (the pinch's compliance holds
    /// it); pushed out of both pads' layers at once by their edges, it would be flapped up and
    /// down every substep, and the free cloth beyond the pads would gain energy.
    pub pinched_by: &'a [Option<[usize; 2]>],
}

/// A contact of an obstacle's edge, corner or rod axis with the cloth, for the implicit solver
/// to hold as a one-sided spring next substep (see [`crate::integrate::ContactSpring`]): the
/// cloth point `sum weights_k x_k` stays `gap` in front of `point` along `normal`. For a moving
/// obstacle the feature moves on during that substep: `end_point` and `end_normal` are where
/// it is at the substep's end (set by [`crate::collide::CollisionStage::aim_feature_contacts`];
/// equal to `point` and `normal` for a static one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureContact {
    pub verts: [u32; 3],
    pub weights: [f64; 3],
    /// World unit normal from the feature towards the cloth.
    pub normal: Vec3,
    /// The feature's contact point (world).
    pub point: Vec3,
    /// Contact distance `radius + thickness` (m).
    pub gap: f64,
    /// Coulomb coefficient of the solver's friction (0 for a moving obstacle: its friction
    /// does work and stays with the collision stage).
    pub mu: f64,
    /// Index of the obstacle in the stage.
    pub obstacle: usize,
    /// Whether the obstacle moved over the substep the contact was found in.
    pub moving: bool,
    /// `point` and `normal` in the obstacle's frame.
    pub local: Vec3,
    pub local_normal: Vec3,
    /// Where the feature point and normal are at the end of the substep the spring acts in.
    pub end_point: Vec3,
    pub end_normal: Vec3,
}

/// A contact the solver held as a spring is answered here only once the cloth point is deeper
/// than this fraction of the contact distance into it (a safety net: the spring's deflection
/// under load is micrometres). Above it, a push by position would stretch the cloth over the
/// edge: the solver moves the segment's vertices with their neighbours and the push moves only
/// them back, and that spurious tension's normal force grips a strip the hanging weight pulls
/// off a table with many times its weight (tests/table_edge.rs).
pub const DEEP: f64 = 0.5;
