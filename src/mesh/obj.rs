//! Wavefront OBJ via `tobj`, triangulating polygons; materials are not read.

use super::data::TriMeshData;
use super::error::MeshError;
use crate::Vec3;
use std::path::Path;

pub(super) fn parse_obj(path: &Path, bytes: &[u8]) -> Result<TriMeshData, MeshError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::BufReader::new(bytes);
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|source| MeshError::Obj {
        path: path.to_path_buf(),
        source,
    })?;
    let count: u64 = models.iter().map(|m| m.mesh.indices.len() as u64 / 3).sum();
    if count > super::limits::MAX_TRIANGLES as u64 {
        return Err(MeshError::TooManyTriangles {
            path: path.to_path_buf(),
            count,
        });
    }
    let mut mesh = TriMeshData::default();
    for model in &models {
        let m = &model.mesh;
        if m.positions.len() % 3 != 0 || m.indices.len() % 3 != 0 {
            return Err(MeshError::RaggedObj {
                path: path.to_path_buf(),
                object: model.name.clone(),
            });
        }
        let part = TriMeshData {
            vertices: m
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
                .collect(),
            indices: m
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        };
        // Validate per object before offsetting so an error names the real index.
        super::data::validate_indices(path, &part)?;
        mesh.append(&part);
    }
    Ok(mesh)
}
