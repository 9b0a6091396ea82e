//! Collision stage: rigid obstacles (scripted or robot-driven), a linear-cost broad phase,
//! three detection modes (spheres, proximity, continuous), contact response with Coulomb
//! friction, and cloth-cloth collision with an impact-zone fail-safe.

mod broad;
mod features;
pub mod held;
pub mod motion;
pub mod narrow;
pub mod obstacle;
mod respond;
mod self_contact;
pub mod spec;
pub mod stage;

pub use features::{FeatureContact, DEEP as FEATURE_DEEP};
pub use held::HeldNormals;
pub use motion::Motion;
pub use obstacle::{Obstacle, ObstacleError};
pub use spec::{
    validate_obstacles, BuildError, CollisionSpec, MotionSpec, ObstacleSpec, PoseSpec, ShapeSpec,
    SpecError,
};
pub use stage::{
    CollisionReport, CollisionSettings, CollisionStage, Contact, DetectionMode, ResponseMode,
    StageError,
};
