//! STL (binary and ASCII). Binary files are parsed here so the triangle count in the header can
//! be checked against the file size before anything is allocated; ASCII goes through `stl_io`.

use super::data::TriMeshData;
use super::error::MeshError;
use crate::Vec3;
use std::collections::HashMap;
use std::path::Path;

const HEADER: usize = 84;
const RECORD: usize = 50;

pub(super) fn parse_stl(path: &Path, bytes: &[u8]) -> Result<TriMeshData, MeshError> {
    let claimed = (bytes.len() >= HEADER)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let exact_binary =
        claimed.is_some_and(|n| HEADER as u64 + n * RECORD as u64 == bytes.len() as u64);
    let looks_ascii = bytes
        .iter()
        .skip_while(|b| b.is_ascii_whitespace())
        .take(5)
        .copied()
        .eq(*b"solid");
    if looks_ascii && !exact_binary {
        return parse_ascii(path, bytes);
    }
    let Some(n) = claimed else {
        return Err(MeshError::StlHeader {
            path: path.to_path_buf(),
            len: bytes.len(),
        });
    };
    let needed = HEADER as u64 + n * RECORD as u64;
    if needed > bytes.len() as u64 {
        return Err(MeshError::StlTruncated {
            path: path.to_path_buf(),
            claimed: n,
            needed,
            len: bytes.len(),
        });
    }
    if n > super::limits::MAX_TRIANGLES as u64 {
        return Err(MeshError::TooManyTriangles {
            path: path.to_path_buf(),
            count: n,
        });
    }
    let n = n as usize;
    let mut mesh = TriMeshData {
        vertices: Vec::with_capacity(n.min(1 << 20)),
        indices: Vec::with_capacity(n),
    };
    // STL stores each triangle's corners separately; merge bit-identical corners so the
    // mesh is connected (needed for sound trimesh collision and volume).
    let mut seen: HashMap<[u32; 3], u32> = HashMap::new();
    for t in 0..n {
        let rec = &bytes[HEADER + t * RECORD..HEADER + (t + 1) * RECORD];
        let mut tri = [0u32; 3];
        for (k, slot) in tri.iter_mut().enumerate() {
            let off = 12 + 12 * k;
            let bits: [u32; 3] = std::array::from_fn(|c| {
                let o = off + 4 * c;
                u32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]])
            });
            *slot = *seen.entry(bits).or_insert_with(|| {
                let v = bits.map(|b| f32::from_bits(b) as f64);
                mesh.vertices.push(Vec3::from(v));
                (mesh.vertices.len() - 1) as u32
            });
        }
        mesh.indices.push(tri);
    }
    Ok(mesh)
}

fn parse_ascii(path: &Path, bytes: &[u8]) -> Result<TriMeshData, MeshError> {
    let mut cursor = std::io::Cursor::new(bytes);
    let indexed = stl_io::read_stl(&mut cursor).map_err(|source| MeshError::AsciiStl {
        path: path.to_path_buf(),
        source,
    })?;
    let vertices = indexed
        .vertices
        .iter()
        .map(|v| Vec3::new(v.0[0] as f64, v.0[1] as f64, v.0[2] as f64))
        .collect();
    if indexed.faces.len() > super::limits::MAX_TRIANGLES {
        return Err(MeshError::TooManyTriangles {
            path: path.to_path_buf(),
            count: indexed.faces.len() as u64,
        });
    }
    let mut indices = Vec::with_capacity(indexed.faces.len());
    let too_many = || MeshError::TooManyVertices {
        path: path.to_path_buf(),
        vertices: indexed.vertices.len(),
    };
    for f in &indexed.faces {
        let [a, b, c] = f.vertices;
        let conv = |i: usize| u32::try_from(i).map_err(|_| too_many());
        indices.push([conv(a)?, conv(b)?, conv(c)?]);
    }
    Ok(TriMeshData { vertices, indices })
}
