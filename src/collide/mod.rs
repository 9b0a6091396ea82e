//! Collision stage: rigid obstacles (scripted or robot-driven), a linear-cost broad phase,
//! three detection modes (spheres, proximity, continuous), contact response with Coulomb
//! friction, and cloth-cloth collision with an impact-zone fail-safe.
//!
//! Files: `settings` (modes), `contact` / `report` / `error` (what the stage hands back),
//! `feedback` (what the solver hands in), `stage` (what the stage owns), `resolve` (the order
//! of one `resolve`), `vertex_pass` (vertices vs obstacles, with `respond` for one vertex),
//! `pinch` and `wedge` (a vertex between several obstacles), `features` (obstacle edges and
//! rods vs cloth faces and edges), `self_contact` (cloth vs cloth), `held` (the filter of a
//! vertex held by several surfaces), `overlap` and `exit` (cloth that starts inside an
//! obstacle), `obstacle`, `motion`, `spec` (scene description), `broad`, `narrow` and `ring`
//! (geometry and the mesh's 1-ring).

mod arrival;
pub(crate) mod broad;
mod contact;
mod error;
mod exit;
mod features;
mod feedback;
pub mod held;
pub mod motion;
pub mod narrow;
pub mod obstacle;
pub(crate) mod overlap;
mod pinch;
mod report;
mod resolve;
mod respond;
mod ring;
mod self_contact;
mod settings;
mod solids;
pub mod spec;
mod stage;
mod vertex_pass;
mod wedge;

pub use arrival::Arrival;
pub use contact::Contact;
pub use error::StageError;
pub use features::{FeatureContact, DEEP as FEATURE_DEEP};
pub use feedback::SolverFeedback;
pub use held::HeldNormals;
pub use motion::Motion;
pub use obstacle::{Obstacle, ObstacleError};
pub use overlap::Overlap;
pub use report::CollisionReport;
pub use resolve::{ContactKind, StageRollback};
pub use self_contact::{SelfContactReport, SelfTouch};
pub use settings::{CollisionSettings, DetectionMode, ResponseMode};
pub use solids::Solids;
pub use spec::{
    validate_obstacles, BuildError, CollisionSpec, MotionSpec, ObstacleSpec, PoseSpec, ShapeSpec,
    SpecError, SpecProblem,
};
pub use stage::CollisionStage;
