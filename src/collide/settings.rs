//! The collision stage's settings: how contacts are detected and how they are answered.

use serde::{Deserialize, Serialize};

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
