//! Fixtures shared by the hierarchy's tests: a grid sheet, a seeded random stream, and the
//! pairs found by brute force and by the traversal.

use super::{Pairs, TopologyBvh};
use crate::Vec3;

/// A `n x n` grid of triangles over the unit square (rest shape), its edges sorted.
pub(super) fn grid(n: usize) -> (Vec<[u32; 3]>, Vec<[u32; 2]>, Vec<Vec3>) {
    let id = |i: usize, j: usize| (i * n + j) as u32;
    let mut tris = Vec::new();
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let edges: Vec<[u32; 2]> = crate::cloth::topology::unique_edges(&tris)
        .into_iter()
        .map(|(a, b)| [a, b])
        .collect();
    let h = 1.0 / (n - 1) as f64;
    let x = (0..n * n)
        .map(|k| Vec3::new((k / n) as f64 * h, (k % n) as f64 * h, 0.0))
        .collect();
    (tris, edges, x)
}

/// A seeded pseudo-random number in `[0, 1)` (a linear congruential stream).
pub(super) fn rnd(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
}

/// Every pair whose (Euclidean) box distance is below the margin, by brute force.
pub(super) fn brute(
    bvh: &TopologyBvh,
    tris: &[[u32; 3]],
    edges: &[[u32; 2]],
    n_v: usize,
) -> (Pairs, Pairs) {
    let mut vt = Vec::new();
    for v in 0..n_v as u32 {
        for t in 0..tris.len() as u32 {
            if !tris[t as usize].contains(&v) && bvh.vt_overlap(v, t) {
                vt.push((v, t));
            }
        }
    }
    let mut ee = Vec::new();
    for e in 0..edges.len() as u32 {
        for f in e + 1..edges.len() as u32 {
            let (a, b) = (edges[e as usize], edges[f as usize]);
            if !a.iter().any(|v| b.contains(v)) && bvh.ee_overlap(edges, e, f) {
                ee.push((e, f));
            }
        }
    }
    (vt, ee)
}

/// The pairs the traversal finds with cones culling below `cos`, every pair accepted.
pub(super) fn found(
    bvh: &mut TopologyBvh,
    tris: &[[u32; 3]],
    edges: &[[u32; 2]],
    cos: f64,
) -> (Pairs, Pairs) {
    let (mut vt, mut ee) = (Vec::new(), Vec::new());
    bvh.pairs_within(
        tris,
        edges,
        true,
        cos,
        |_, _| true,
        |_, _| true,
        &mut vt,
        &mut ee,
    );
    vt.sort_unstable();
    ee.sort_unstable();
    (vt, ee)
}
