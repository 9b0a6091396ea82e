//! Triangle meshes loaded from the files robot descriptions reference (STL, OBJ, Collada).
//!
//! Everything here treats files as untrusted: sizes are checked before allocating, indices
//! and coordinates are validated, and every error names the file it came from.

mod dae;
mod dae_error;
mod data;
mod error;
mod limits;
mod obj;
mod simplify;
mod stl;
mod xml;

pub use dae_error::DaeError;
pub use data::{convex_hull, validate, TriMeshData};
pub use error::MeshError;
pub use limits::{MAX_COORDINATE, MAX_SCALE, MAX_TRIANGLES, MIN_SCALE};
pub use simplify::simplify;
pub use xml::XmlError;

use crate::Vec3;
use std::path::{Path, PathBuf};

/// Loads a mesh, dispatching on the (case-insensitive) extension, and multiplies every vertex
/// by `scale` component-wise. A scale with an odd number of negative components mirrors the
/// mesh, so triangle winding is flipped to keep outward normals outward. Each scale component
/// must be finite with a magnitude in [`MIN_SCALE`]..=[`MAX_SCALE`], and every scaled vertex
/// within [`MAX_COORDINATE`] of the origin on each axis.
///
/// The file is read through [`crate::input::read_bytes`] (regular files only, size cap). Callers
/// that take the path from outside check where it points first (see [`load_mesh_within`]).
pub fn load_mesh(path: &Path, scale: Vec3) -> Result<TriMeshData, MeshError> {
    let in_range = |c: f64| (MIN_SCALE..=MAX_SCALE).contains(&c.abs());
    if !(in_range(scale.x) && in_range(scale.y) && in_range(scale.z)) {
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
