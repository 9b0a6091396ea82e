//! [`TriMeshData`], the indexed triangle mesh every loader returns, and the invariants every
//! consumer relies on (checked by [`validate`]).

use super::error::MeshError;
use super::limits::MAX_COORDINATE;
use crate::Vec3;
use std::path::Path;

/// An indexed triangle mesh in f64, in the frame of the file after unit/up-axis conversion
/// and the caller's scale.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMeshData {
    pub vertices: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
}

/// Checks the invariants every consumer relies on: at least one triangle, indices in range,
/// finite coordinates within [`MAX_COORDINATE`].
pub fn validate(path: &Path, mesh: &TriMeshData) -> Result<(), MeshError> {
    if mesh.indices.is_empty() || mesh.vertices.is_empty() {
        return Err(MeshError::Empty {
            path: path.to_path_buf(),
        });
    }
    if let Some(index) = mesh.vertices.iter().position(|v| !v.is_finite()) {
        return Err(MeshError::NonFinite {
            path: path.to_path_buf(),
            index,
        });
    }
    let far = |v: &Vec3| v.abs().max_element() > MAX_COORDINATE;
    if let Some(index) = mesh.vertices.iter().position(far) {
        return Err(MeshError::TooFar {
            path: path.to_path_buf(),
            index,
            value: mesh.vertices[index].abs().max_element(),
        });
    }
    validate_indices(path, mesh)
}

pub(crate) fn validate_indices(path: &Path, mesh: &TriMeshData) -> Result<(), MeshError> {
    let count = mesh.vertices.len();
    for (triangle, tri) in mesh.indices.iter().enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= count) {
            return Err(MeshError::IndexOutOfRange {
                path: path.to_path_buf(),
                triangle,
                index,
                count,
            });
        }
    }
    Ok(())
}

impl TriMeshData {
    /// Axis-aligned bounds `(min, max)`; `None` for a mesh without vertices.
    pub fn aabb(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.vertices.first()?;
        Some(
            self.vertices
                .iter()
                .fold((first, first), |(lo, hi), &v| (lo.min(v), hi.max(v))),
        )
    }

    /// Signed volume (divergence theorem); positive for a closed mesh with outward winding.
    pub fn signed_volume(&self) -> f64 {
        self.indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Appends `other`, offsetting its indices.
    pub fn append(&mut self, other: &TriMeshData) {
        let offset = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|i| i + offset)));
    }
}

/// Convex hull of the mesh's vertices (via parry, in f32), e.g. to replace a detailed visual
/// mesh by a cheap collision proxy. Returns `None` for degenerate (flat or tiny) inputs.
pub fn convex_hull(mesh: &TriMeshData) -> Option<TriMeshData> {
    use parry3d::math::Vector as PVec;
    let points: Vec<PVec> = mesh
        .vertices
        .iter()
        .map(|v| PVec::new(v.x as f32, v.y as f32, v.z as f32))
        .collect();
    if points.len() < 4 {
        return None;
    }
    let (verts, indices) = parry3d::transformation::try_convex_hull(&points).ok()?;
    if indices.is_empty() {
        return None;
    }
    Some(TriMeshData {
        vertices: verts
            .iter()
            .map(|p| Vec3::new(p.x as f64, p.y as f64, p.z as f64))
            .collect(),
        indices,
    })
}
