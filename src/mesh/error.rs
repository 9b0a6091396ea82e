//! [`MeshError`]: why a mesh file could not be used, naming the file. Its own file so the
//! parsers (stl, obj, dae) and the dispatch in `mod.rs` share it without a cycle.

use crate::Vec3;
use std::path::PathBuf;

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
    /// Well-formed XML that is not usable Collada geometry; `geometry` is the `<geometry id>`
    /// being read, when the fault is inside one.
    #[error("mesh {path}: Collada{}", geometry.as_ref().map(|g| format!(" geometry `{g}`")).unwrap_or_default())]
    Collada {
        path: PathBuf,
        geometry: Option<String>,
        #[source]
        source: super::dae_error::DaeError,
    },
    #[error("mesh {path}: OBJ object `{object}` has a ragged position or index array")]
    RaggedObj { path: PathBuf, object: String },
    #[error("mesh {path}: binary STL is {len} bytes, shorter than its 84-byte header")]
    StlHeader { path: PathBuf, len: usize },
    #[error(
        "mesh {path}: binary STL header claims {claimed} triangles ({needed} bytes) but the file \
         has only {len} bytes"
    )]
    StlTruncated {
        path: PathBuf,
        claimed: u64,
        needed: u64,
        len: usize,
    },
    #[error("mesh {path}: {count} triangles, more than the {max} a mesh may have (simplify it)", max = super::limits::MAX_TRIANGLES)]
    TooManyTriangles { path: PathBuf, count: u64 },
    #[error("mesh {path}: {vertices} vertices are too many for u32 indices")]
    TooManyVertices { path: PathBuf, vertices: usize },
    /// A Collada file that is not well-formed XML (the parser's error is the source).
    #[error("mesh {path}: Collada")]
    Xml {
        path: PathBuf,
        #[source]
        source: super::xml::XmlError,
    },
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
    #[error("mesh {path}: vertex {index} is {value:e} m from the origin on one axis, beyond the {max:e} m allowed", max = super::limits::MAX_COORDINATE)]
    TooFar {
        path: PathBuf,
        index: usize,
        value: f64,
    },
    #[error("mesh {path}: scale [{:?}, {:?}, {:?}] must be finite, with every component between {min:e} and {max:e} in size", scale.x, scale.y, scale.z, min = super::limits::MIN_SCALE, max = super::limits::MAX_SCALE)]
    BadScale { path: PathBuf, scale: Vec3 },
}
