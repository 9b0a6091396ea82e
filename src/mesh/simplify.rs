//! Vertex-clustering simplification: snap vertices to a uniform grid, merge each cell into the
//! mean of its vertices, and drop triangles that collapse. Crude but robust on any triangle
//! soup, and enough to cap the cost of dense robot meshes used as collision obstacles.

use super::data::TriMeshData;
use crate::Vec3;
use std::collections::{HashMap, HashSet};

fn cluster(mesh: &TriMeshData, lo: Vec3, cell: f64) -> TriMeshData {
    let mut cell_of: HashMap<[i64; 3], u32> = HashMap::new();
    let mut sums: Vec<(Vec3, f64)> = Vec::new();
    let remap: Vec<u32> = mesh
        .vertices
        .iter()
        .map(|&v| {
            let key = ((v - lo) / cell).floor().to_array().map(|c| c as i64);
            let id = *cell_of.entry(key).or_insert_with(|| {
                sums.push((Vec3::ZERO, 0.0));
                (sums.len() - 1) as u32
            });
            sums[id as usize].0 += v;
            sums[id as usize].1 += 1.0;
            id
        })
        .collect();
    let mut seen = HashSet::new();
    let indices = mesh
        .indices
        .iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .filter(|&[a, b, c]| a != b && b != c && a != c)
        .filter(|t| {
            let mut key = *t;
            key.sort_unstable();
            seen.insert(key)
        })
        .collect();
    TriMeshData {
        vertices: sums.into_iter().map(|(s, n)| s / n).collect(),
        indices,
    }
}

/// Reduces `mesh` to at most `target_triangles` triangles using the finest grid that meets
/// the budget (binary search over the grid resolution). Unused vertices are kept so indices
/// stay valid; meshes already within budget are returned unchanged.
pub fn simplify(mesh: &TriMeshData, target_triangles: usize) -> TriMeshData {
    let Some((lo, hi)) = mesh.aabb() else {
        return mesh.clone();
    };
    if mesh.indices.len() <= target_triangles {
        return mesh.clone();
    }
    let extent = (hi - lo).max_element();
    if extent.is_nan() || extent <= 0.0 {
        return TriMeshData {
            vertices: mesh.vertices.clone(),
            indices: Vec::new(),
        };
    }
    // Resolution = cells along the longest axis. One cell collapses everything.
    let (mut ok, mut too_fine) = (1u32, 1u32 << 16);
    let mut best = cluster(mesh, lo, extent);
    while too_fine - ok > 1 {
        let mid = ok + (too_fine - ok) / 2;
        let candidate = cluster(mesh, lo, extent / mid as f64);
        if candidate.indices.len() <= target_triangles {
            ok = mid;
            best = candidate;
        } else {
            too_fine = mid;
        }
    }
    best
}
