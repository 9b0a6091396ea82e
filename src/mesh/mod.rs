//! Triangle meshes loaded from the files robot descriptions reference (STL, OBJ, Collada).
//!
//! Everything here treats files as untrusted: sizes are checked before allocating, indices
//! and coordinates are validated, and every error names the file it came from.

mod dae;
mod obj;
mod simplify;
mod stl;
mod xml;

pub use simplify::simplify;

use crate::Vec3;
use std::path::{Path, PathBuf};

/// An indexed triangle mesh in f64, in the frame of the file after unit/up-axis conversion
/// and the caller's scale.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMeshData {
    pub vertices: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
}

/// Why a mesh file could not be used; always carries the file path.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A regular file, within the mesh size cap, is required (see `crate::input`).
    #[error(transparent)]
    Input(Box<crate::input::InputError>),
    #[error("mesh {path}: cannot read file")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("mesh {path}: unsupported extension (expected .stl, .obj or .dae)")]
    UnsupportedFormat { path: PathBuf },
    #[error("mesh {path}: {message}")]
    Malformed { path: PathBuf, message: String },
    #[error("mesh {path}: not a valid OBJ file")]
    Obj {
        path: PathBuf,
        #[source]
        source: tobj::LoadError,
    },
    #[error("mesh {path}: not a valid ASCII STL file")]
    AsciiStl {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("mesh {path}: contains no triangles")]
    Empty { path: PathBuf },
    #[error(
        "mesh {path}: triangle {triangle} references vertex {index} but there are only {count}"
    )]
    IndexOutOfRange {
        path: PathBuf,
        triangle: usize,
        index: u32,
        count: usize,
    },
    #[error("mesh {path}: vertex {index} has a non-finite coordinate")]
    NonFinite { path: PathBuf, index: usize },
    #[error("mesh {path}: scale {scale} must be finite and non-zero on every axis")]
    BadScale { path: PathBuf, scale: Vec3 },
}

impl MeshError {
    pub(crate) fn malformed(path: &Path, message: impl Into<String>) -> Self {
        MeshError::Malformed {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// Loads a mesh, dispatching on the (case-insensitive) extension, and multiplies every vertex
/// by `scale` component-wise. A scale with an odd number of negative components mirrors the
/// mesh, so triangle winding is flipped to keep outward normals outward.
///
/// The file is read through [`crate::input::read_bytes`] (regular files only, size cap). Callers
/// that take the path from outside check where it points first (see [`load_mesh_within`]).
pub fn load_mesh(path: &Path, scale: Vec3) -> Result<TriMeshData, MeshError> {
    if !scale.is_finite() || scale.x == 0.0 || scale.y == 0.0 || scale.z == 0.0 {
        return Err(MeshError::BadScale {
            path: path.to_path_buf(),
            scale,
        });
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let read = || {
        crate::input::read_bytes(path, crate::input::InputKind::Mesh).map_err(|e| match e {
            crate::input::InputError::Open { path, source, .. } => MeshError::Io { path, source },
            other => MeshError::Input(Box::new(other)),
        })
    };
    let mut mesh = match ext.as_str() {
        "stl" => stl::parse_stl(path, &read()?)?,
        "obj" => obj::parse_obj(path, &read()?)?,
        "dae" => dae::parse_dae(path, &read()?)?,
        _ => {
            return Err(MeshError::UnsupportedFormat {
                path: path.to_path_buf(),
            })
        }
    };
    for v in &mut mesh.vertices {
        *v *= scale;
    }
    if scale.x * scale.y * scale.z < 0.0 {
        for t in &mut mesh.indices {
            t.swap(1, 2);
        }
    }
    validate(path, &mesh)?;
    Ok(mesh)
}

/// [`load_mesh`] of a path from a scene file, after resolving it (symlinks, `..`) and checking
/// that it lies inside one of `roots` (see `crate::robot::resolve` for the rule).
pub fn load_mesh_within(
    path: &Path,
    scale: Vec3,
    roots: &[PathBuf],
) -> Result<TriMeshData, MeshError> {
    let resolved = crate::input::contained(path, roots).map_err(|e| match e {
        crate::input::InputError::Open { path, source, .. } => MeshError::Io { path, source },
        other => MeshError::Input(Box::new(other)),
    })?;
    load_mesh(&resolved, scale)
}

/// Checks the invariants every consumer relies on: at least one triangle, indices in range,
/// finite coordinates.
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
