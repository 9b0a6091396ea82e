//! The welded garment's own crossings: a garment sewn through itself (a seam pulled across a
//! panel, a strap folded through the body while the seams closed) keeps every crossing for the
//! whole run, since self-collision keeps layers apart but cannot pull one back through another.
//! So the build refuses it, naming the seam nearest the first crossing.

use crate::collide::broad::{cell_size, collect_pairs, Aabb, PairScratch, SpatialHash};
use crate::collide::narrow;
use crate::Vec3;

/// Pairs of triangles sharing no vertex that intersect at `x` (triangle indices, ascending).
pub(super) fn crossings(x: &[Vec3], triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let corners = |t: &[u32; 3]| t.map(|i| x[i as usize]);
    let boxes: Vec<Aabb> = (triangles.iter())
        .map(|t| Aabb::from_points(&corners(t), 0.0))
        .collect();
    let mut hash = SpatialHash::default();
    hash.build(cell_size(&boxes, 0.0), &boxes);
    let mut pairs = Vec::new();
    let shares = |a: &[u32; 3], b: &[u32; 3]| a.iter().any(|v| b.contains(v));
    collect_pairs(
        &hash,
        &boxes,
        &boxes,
        &mut PairScratch::default(),
        |a, b| a < b && !shares(&triangles[a as usize], &triangles[b as usize]),
        &mut pairs,
    );
    pairs.retain(|&(a, b)| {
        narrow::triangles_intersect(
            corners(&triangles[a as usize]),
            corners(&triangles[b as usize]),
        )
    });
    pairs.sort_unstable();
    pairs
}

/// The seam (by name) with a vertex nearest to `p`, and that distance.
pub(super) fn nearest_seam<'a>(
    x: &[Vec3],
    seams: &'a [(String, Vec<u32>)],
    p: Vec3,
) -> Option<(&'a str, f64)> {
    seams
        .iter()
        .filter_map(|(name, verts)| {
            let d = (verts.iter())
                .map(|&v| x[v as usize].distance(p))
                .min_by(f64::total_cmp)?;
            Some((name.as_str(), d))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_triangles_are_found_and_touching_ones_are_not() {
        // A horizontal triangle, one piercing it, one above it, one sharing its vertex.
        let x = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.2, 0.2, -0.5),
            Vec3::new(0.2, 0.2, 0.5),
            Vec3::new(0.3, 0.25, 0.5),
            Vec3::new(0.2, 0.2, 1.0),
            Vec3::new(0.3, 0.2, 1.0),
            Vec3::new(0.2, 0.3, 1.0),
            Vec3::new(-0.5, -0.5, 0.3),
            Vec3::new(-0.5, 0.5, 0.3),
        ];
        let tris = [[0, 1, 2], [3, 4, 5], [6, 7, 8], [0, 9, 10]];
        assert_eq!(crossings(&x, &tris), vec![(0, 1)]);
    }
}
