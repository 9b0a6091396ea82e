//! One detection pass's view of an obstacle's features: their world positions at the start and
//! end pose, their swept boxes hashed, and the per-pair rules both queries share (contact
//! distance, kinematic pairs skipped, box normal cones).

use super::contact::ClothState;
use super::set::{in_cone, Features};
use crate::collide::broad::{Aabb, SpatialHash};
use crate::collide::obstacle::Obstacle;
use crate::Vec3;

/// The features of `o` swept over one pass, against the cloth moving from `x0` to `x1`.
pub(super) struct Sweep<'a, 's> {
    pub o: &'a Obstacle,
    pub f: &'a Features,
    pub s: &'a ClothState<'s>,
    pub x0: &'a [Vec3],
    pub x1: &'a [Vec3],
    /// Corner points at (start, end) pose, world.
    pub pts: &'a [(Vec3, Vec3)],
    /// Segments at (start, end) pose, world.
    pub segs: &'a [([Vec3; 2], [Vec3; 2])],
    pub point_hash: &'a SpatialHash,
    pub point_boxes: &'a [Aabb],
    pub segment_hash: &'a SpatialHash,
    pub segment_boxes: &'a [Aabb],
}

impl Sweep<'_, '_> {
    /// Features whose boxes overlap `b`, each once, in index order.
    pub fn near(hash: &SpatialHash, boxes: &[Aabb], b: &Aabb) -> Vec<usize> {
        let mut out: Vec<usize> = Vec::new();
        hash.query(b, |i| {
            if boxes[i as usize].overlaps(b) {
                out.push(i as usize);
            }
        });
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Contact distance of a cloth face or edge: the feature radius plus its thickest vertex.
    pub fn eta(&self, verts: &[u32]) -> f64 {
        self.f.radius
            + verts
                .iter()
                .map(|&v| self.s.thickness[v as usize])
                .fold(0.0, f64::max)
    }

    /// Whether every vertex of a cloth face or edge is kinematic (nothing to answer).
    pub fn kinematic(&self, verts: &[u32]) -> bool {
        verts.iter().all(|&v| self.s.inv_mass[v as usize] <= 0.0)
    }

    /// Whether feature `k` (points first, then segments) owns a contact of world normal
    /// `world_normal` (see [`in_cone`]; features without cones own every normal).
    pub fn cone_ok(&self, k: usize, world_normal: Vec3) -> bool {
        self.f
            .cones
            .get(k)
            .is_none_or(|&c| in_cone(c, self.o.pose.rotation.inverse() * world_normal))
    }
}
