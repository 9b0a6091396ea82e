//! Query: exact count of intersecting non-adjacent triangle pairs (for metrics).

use super::collider::{shares_vertex, SelfCollider};
use crate::collide::broad::{cell_size, collect_pairs, Aabb};
use crate::collide::narrow;
use crate::Vec3;

impl SelfCollider {
    /// Exact count of intersecting non-adjacent triangle pairs at positions `x`.
    pub fn count_intersections(&mut self, x: &[Vec3]) -> usize {
        let tris = &self.triangles;
        self.iboxes.clear();
        self.iboxes.extend(tris.iter().map(|t| {
            Aabb::from_points(&[x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]], 0.0)
        }));
        let cell = cell_size(&self.iboxes, 0.0);
        self.hash.build(cell, &self.iboxes);
        collect_pairs(
            &self.hash,
            &self.iboxes,
            &self.iboxes,
            &mut self.stamp,
            |a, b| a < b && !shares_vertex(&tris[a as usize], &tris[b as usize]),
            &mut self.pairs,
        );
        let p = |t: [u32; 3]| t.map(|i| x[i as usize]);
        self.pairs
            .iter()
            .filter(|&&(a, b)| {
                narrow::triangles_intersect(p(tris[a as usize]), p(tris[b as usize]))
            })
            .count()
    }
}
