//! The `garments:` section of a scene file.

use crate::cloth::Material;
use crate::collide::PoseSpec;
use serde::{Deserialize, Serialize};

/// A garment: panels cut from one material, sewn along seams around the body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentSpec {
    pub name: String,
    #[serde(default)]
    pub material: Material,
    /// Target triangle edge length of the meshes (m).
    #[serde(default = "edge_length")]
    pub edge_length: f64,
    pub panels: Vec<PanelSpec>,
    #[serde(default)]
    pub seams: Vec<SeamSpec>,
    #[serde(default)]
    pub sewing: SewingSpec,
    /// Garment vertices held by robot links once the garment is welded.
    #[serde(default)]
    pub attach: Vec<GarmentAttachSpec>,
}

/// Welded garment vertices within `radius` of `point` (in the link's frame, at t = 0) follow the
/// link, keeping their offset: `{ link: left_upper_arm, point: [0, 0, -0.04], radius: 0.07 }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentAttachSpec {
    pub link: String,
    pub point: [f64; 3],
    pub radius: f64,
}

fn edge_length() -> f64 {
    0.03
}

/// A flat pattern piece.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanelSpec {
    pub name: String,
    /// Closed polygon in the pattern plane (m); the last point connects back to the first.
    pub outline: Vec<[f64; 2]>,
    /// Warp direction in the pattern plane, degrees from the outline's x axis.
    #[serde(default)]
    pub grain: f64,
    #[serde(default)]
    pub placement: PlacementSpec,
}

/// Where the flat pattern starts: its (x, y) plane mapped by `pose` (normal = local z), optionally
/// wrapped first onto a cylinder whose axis runs along local y, `radius` behind the plane.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlacementSpec {
    #[serde(default)]
    pub pose: PoseSpec,
    #[serde(default)]
    pub wrap: Option<WrapSpec>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WrapSpec {
    pub radius: f64,
}

/// One side of a seam: the outline of `panel` from vertex `from` forward (increasing index,
/// wrapping) to vertex `to`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeamSide {
    pub panel: String,
    pub from: usize,
    pub to: usize,
}

/// Sews stretch `a` to stretch `b`: `a.from` meets `b.from` (or `b.to` when `reversed`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeamSpec {
    pub name: String,
    pub a: SeamSide,
    pub b: SeamSide,
    #[serde(default)]
    pub reversed: bool,
}

/// The sewing schedule: seam springs whose rest length shrinks linearly from the initial gap to
/// zero over `close_time`, then hold until every gap is below `tolerance` (or fail at `max_time`).
/// Gravity and wind are off meanwhile; collisions stay on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SewingSpec {
    /// Seam spring stiffness (N/m).
    pub stiffness: f64,
    /// Time over which the seams close (s).
    pub close_time: f64,
    /// Largest seam gap at which the pairs are welded (m).
    pub tolerance: f64,
    /// Sewing fails if the gaps are not closed by then (s).
    pub max_time: f64,
}

impl Default for SewingSpec {
    fn default() -> Self {
        Self {
            stiffness: 2000.0,
            close_time: 1.0,
            tolerance: 1e-3,
            max_time: 4.0,
        }
    }
}
