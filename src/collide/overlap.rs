//! Cloth that starts inside an obstacle, reported when the scene is built: how many vertices,
//! inside which obstacle, and how deep the deepest one is. The collision stage pushes such
//! vertices out over the first steps (a solid's inside is known; meshes are two-sided surfaces
//! and have none), which a user should know about before reading the results.

use super::stage::CollisionStage;
use crate::Vec3;

/// The cloth vertices inside one obstacle.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlap {
    pub obstacle: String,
    pub vertices: usize,
    /// Distance of the deepest one below the obstacle's surface (m).
    pub deepest: f64,
}

impl std::fmt::Display for Overlap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} cloth vertices start inside obstacle '{}' (the deepest {:.1} mm below its \
             surface)",
            self.vertices,
            self.obstacle,
            self.deepest * 1e3
        )
    }
}

impl CollisionStage {
    /// The obstacles that vertices `x` are inside (at the obstacles' current poses), with their
    /// counts; empty when the cloth starts clear.
    pub fn overlaps(&self, x: &[Vec3]) -> Vec<Overlap> {
        let mut out = Vec::new();
        for o in &self.obstacles {
            let (mut vertices, mut deepest) = (0, 0.0f64);
            for p in x {
                let local = o.pose.inverse_transform_point(*p);
                if o.contains_local(local) {
                    vertices += 1;
                    let sp = o.closest_local(local, local);
                    deepest = deepest.max(-sp.signed_distance);
                }
            }
            if vertices > 0 {
                out.push(Overlap {
                    obstacle: o.name.clone(),
                    vertices,
                    deepest,
                });
            }
        }
        out
    }
}
