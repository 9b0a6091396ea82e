//! Collada (.dae) geometry: `<triangles>`, `<polylist>` and `<polygons>` primitives placed by
//! the visual scene's node transforms, converted to metres (`<unit meter>`) and to Z-up
//! (`<up_axis>`), the convention of URDF link frames.

use super::dae_error::DaeError;
use super::data::TriMeshData;
use super::error::MeshError;
use super::xml::{self, Element};
use crate::Vec3;
use glam::{DMat4, DQuat};
use std::collections::HashMap;
use std::path::Path;

/// `instance_node` references can form cycles; stop following them beyond this depth.
const MAX_NODE_DEPTH: usize = 64;
/// Most node visits of a scene: nodes that instance each other twice per level reach 2^30
/// visits at depth 30, with or without geometry.
const MAX_NODE_VISITS: usize = 1_000_000;

pub(super) fn parse_dae(path: &Path, bytes: &[u8]) -> Result<TriMeshData, MeshError> {
    let root = xml::parse(bytes).map_err(|source| MeshError::Xml {
        path: path.to_path_buf(),
        source,
    })?;
    if root.name != "COLLADA" {
        return Err(collada(
            path,
            None,
            DaeError::Root {
                found: root.name.clone(),
            },
        ));
    }
    let (meter, up) = asset_units(&root).map_err(|e| collada(path, None, e))?;

    let mut geometry_elems = Vec::new();
    root.descendants_named("geometry", &mut geometry_elems);
    let mut geometries: HashMap<&str, TriMeshData> = HashMap::new();
    let mut all = TriMeshData::default();
    for g in &geometry_elems {
        let Some(mesh) = g.child("mesh") else {
            continue;
        };
        let id = g.attr("id").unwrap_or("");
        let data = read_mesh(mesh).map_err(|e| collada(path, Some(id), e))?;
        if all.indices.len() + data.indices.len() > super::limits::MAX_TRIANGLES {
            let max = super::limits::MAX_TRIANGLES;
            return Err(collada(path, Some(id), DaeError::TooManyTriangles { max }));
        }
        all.append(&data);
        geometries.insert(id, data);
    }

    let mut node_lib = Vec::new();
    root.descendants_named("node", &mut node_lib);
    let nodes: HashMap<&str, &Element> = node_lib
        .iter()
        .filter_map(|n| n.attr("id").map(|id| (id, *n)))
        .collect();

    let mut scene_mesh = TriMeshData::default();
    if let Some(scene) = visual_scene(&root) {
        let mut ctx = SceneCtx {
            geometries: &geometries,
            nodes: &nodes,
            out: &mut scene_mesh,
            visits: 0,
        };
        for node in scene.children_named("node") {
            ctx.visit(node, DMat4::IDENTITY, 0)
                .map_err(|e| collada(path, None, e))?;
        }
    }
    // Files without a scene (or whose scene instantiates nothing) still carry usable geometry.
    let mut mesh = if scene_mesh.indices.is_empty() {
        all
    } else {
        scene_mesh
    };
    let to_z_up = match up {
        UpAxis::Z => DQuat::IDENTITY,
        UpAxis::Y => DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2),
        UpAxis::X => DQuat::from_rotation_y(-std::f64::consts::FRAC_PI_2),
    };
    for v in &mut mesh.vertices {
        *v = to_z_up * (*v * meter);
    }
    Ok(mesh)
}

#[derive(Clone, Copy)]
enum UpAxis {
    X,
    Y,
    Z,
}

fn asset_units(root: &Element) -> Result<(f64, UpAxis), DaeError> {
    let Some(asset) = root.child("asset") else {
        return Ok((1.0, UpAxis::Y));
    };
    let meter = match asset.child("unit").and_then(|u| u.attr("meter")) {
        None => 1.0,
        Some(s) => match s.trim().parse::<f64>() {
            Ok(m) if m.is_finite() && m > 0.0 => m,
            _ => {
                return Err(DaeError::UnitMeter {
                    value: s.to_owned(),
                })
            }
        },
    };
    let up = match asset.child("up_axis").map(|u| u.text.trim()) {
        None | Some("Y_UP") => UpAxis::Y,
        Some("Z_UP") => UpAxis::Z,
        Some("X_UP") => UpAxis::X,
        Some(other) => {
            return Err(DaeError::UpAxis {
                value: other.to_owned(),
            })
        }
    };
    Ok((meter, up))
}

fn visual_scene(root: &Element) -> Option<&Element> {
    let mut scenes = Vec::new();
    root.descendants_named("visual_scene", &mut scenes);
    let wanted = root
        .child("scene")
        .and_then(|s| s.child("instance_visual_scene"))
        .and_then(|i| i.attr("url"))
        .map(|u| u.trim_start_matches('#'));
    match wanted {
        Some(id) => scenes
            .iter()
            .find(|s| s.attr("id") == Some(id))
            .or(scenes.first())
            .copied(),
        None => scenes.first().copied(),
    }
}

struct SceneCtx<'a, 'b> {
    geometries: &'a HashMap<&'a str, TriMeshData>,
    nodes: &'a HashMap<&'a str, &'a Element>,
    out: &'b mut TriMeshData,
    visits: usize,
}

impl SceneCtx<'_, '_> {
    fn visit(&mut self, node: &Element, parent: DMat4, depth: usize) -> Result<(), DaeError> {
        if depth > MAX_NODE_DEPTH {
            return Err(DaeError::NodeDepth {
                max: MAX_NODE_DEPTH,
            });
        }
        self.visits += 1;
        if self.visits > MAX_NODE_VISITS {
            return Err(DaeError::TooManyNodes {
                max: MAX_NODE_VISITS,
            });
        }
        let mut m = parent;
        for c in &node.children {
            let local = match c.name.as_str() {
                "matrix" => {
                    let v = floats(&c.text)?;
                    if v.len() != 16 {
                        return Err(arity("matrix", v.len(), 16));
                    }
                    // Collada matrices are written row-major.
                    DMat4::from_cols_array(&v.try_into().unwrap_or([0.0; 16])).transpose()
                }
                "translate" => DMat4::from_translation(Vec3::from(vec3(&c.text, "translate")?)),
                "scale" => DMat4::from_scale(Vec3::from(vec3(&c.text, "scale")?)),
                "rotate" => {
                    let v = floats(&c.text)?;
                    if v.len() != 4 {
                        return Err(arity("rotate", v.len(), 4));
                    }
                    let axis = Vec3::new(v[0], v[1], v[2]);
                    if axis.length_squared() == 0.0 {
                        DMat4::IDENTITY
                    } else {
                        DMat4::from_axis_angle(axis.normalize(), v[3].to_radians())
                    }
                }
                _ => continue,
            };
            m *= local;
        }
        for c in &node.children {
            match c.name.as_str() {
                "instance_geometry" => {
                    let url = c.attr("url").unwrap_or("").trim_start_matches('#');
                    let g = self
                        .geometries
                        .get(url)
                        .ok_or_else(|| DaeError::UnknownGeometry {
                            url: url.to_owned(),
                        })?;
                    // Counted before copying: nodes that instance each other a few times per
                    // level multiply the triangles exponentially with the depth.
                    if self.out.indices.len() + g.indices.len() > super::limits::MAX_TRIANGLES {
                        return Err(DaeError::TooManyTriangles {
                            max: super::limits::MAX_TRIANGLES,
                        });
                    }
                    let mut placed = g.clone();
                    for v in &mut placed.vertices {
                        *v = m.transform_point3(*v);
                    }
                    if m.determinant() < 0.0 {
                        for t in &mut placed.indices {
                            t.swap(1, 2);
                        }
                    }
                    self.out.append(&placed);
                }
                "node" => self.visit(c, m, depth + 1)?,
                "instance_node" => {
                    let url = c.attr("url").unwrap_or("").trim_start_matches('#');
                    let n = *self.nodes.get(url).ok_or_else(|| DaeError::UnknownNode {
                        url: url.to_owned(),
                    })?;
                    self.visit(n, m, depth + 1)?;
                }
                _ => {}
            }
        }
        Ok(())
    }
}

fn collada(path: &Path, geometry: Option<&str>, source: DaeError) -> MeshError {
    MeshError::Collada {
        path: path.to_path_buf(),
        geometry: geometry.map(str::to_owned),
        source,
    }
}

fn arity(element: &'static str, found: usize, expected: usize) -> DaeError {
    DaeError::Arity {
        element,
        found,
        expected,
    }
}

fn floats(text: &str) -> Result<Vec<f64>, DaeError> {
    text.split_ascii_whitespace()
        .map(|t| {
            t.parse::<f64>().map_err(|_| DaeError::NotANumber {
                token: t.to_owned(),
            })
        })
        .collect()
}

fn vec3(text: &str, what: &'static str) -> Result<[f64; 3], DaeError> {
    let v = floats(text)?;
    <[f64; 3]>::try_from(v.as_slice()).map_err(|_| arity(what, v.len(), 3))
}

fn indices(text: &str) -> Result<Vec<usize>, DaeError> {
    text.split_ascii_whitespace()
        .map(|t| {
            t.parse::<usize>().map_err(|_| DaeError::NotAnIndex {
                token: t.to_owned(),
            })
        })
        .collect()
}

/// An attribute that must parse as a count or offset.
fn count_attr(attribute: &'static str, value: &str) -> Result<usize, DaeError> {
    value
        .trim()
        .parse::<usize>()
        .map_err(|_| DaeError::Attribute {
            attribute,
            value: value.to_owned(),
        })
}

/// Positions of a `<mesh>`: the `POSITION` input of `<vertices>`, read through its accessor.
fn positions(mesh: &Element) -> Result<Vec<Vec3>, DaeError> {
    let vertices = mesh.child("vertices").ok_or(DaeError::Missing {
        what: "<mesh> without <vertices>",
    })?;
    let src_id = vertices
        .children_named("input")
        .find(|i| i.attr("semantic") == Some("POSITION"))
        .and_then(|i| i.attr("source"))
        .ok_or(DaeError::Missing {
            what: "<vertices> without a POSITION input",
        })?
        .trim_start_matches('#');
    let source = mesh
        .children_named("source")
        .find(|s| s.attr("id") == Some(src_id))
        .ok_or_else(|| DaeError::PositionSource {
            id: src_id.to_owned(),
        })?;
    let data = floats(
        &source
            .child("float_array")
            .ok_or(DaeError::Missing {
                what: "source without <float_array>",
            })?
            .text,
    )?;
    let accessor = source
        .child("technique_common")
        .and_then(|t| t.child("accessor"));
    let stride = match accessor.and_then(|a| a.attr("stride")) {
        None => 3,
        Some(s) => count_attr("accessor stride", s)?,
    };
    let offset = match accessor.and_then(|a| a.attr("offset")) {
        None => 0,
        Some(s) => count_attr("accessor offset", s)?,
    };
    if stride < 3 {
        return Err(DaeError::Stride { stride });
    }
    let count = match accessor.and_then(|a| a.attr("count")) {
        Some(s) => count_attr("accessor count", s)?,
        None => data.len().saturating_sub(offset) / stride,
    };
    let needed = count
        .checked_mul(stride)
        .and_then(|n| n.checked_add(offset))
        .ok_or(DaeError::AccessorOverflow { count, stride })?;
    if needed > data.len() + (stride - 3) {
        return Err(DaeError::AccessorShort {
            count,
            stride,
            numbers: data.len(),
        });
    }
    Ok((0..count)
        .map(|i| {
            let b = offset + i * stride;
            Vec3::new(data[b], data[b + 1], data[b + 2])
        })
        .collect())
}

/// Offset of the VERTEX input and the number of indices per corner in a primitive's `<p>`.
fn layout(prim: &Element) -> Result<(usize, usize), DaeError> {
    let mut vertex_offset = None;
    let mut max_offset = 0;
    for input in prim.children_named("input") {
        let off = match input.attr("offset") {
            Some(s) => count_attr("input offset", s)?,
            None => 0,
        };
        max_offset = max_offset.max(off);
        if input.attr("semantic") == Some("VERTEX") {
            vertex_offset = Some(off);
        }
    }
    let v = vertex_offset.ok_or_else(|| DaeError::NoVertexInput {
        primitive: prim.name.clone(),
    })?;
    Ok((v, max_offset + 1))
}

fn read_mesh(mesh: &Element) -> Result<TriMeshData, DaeError> {
    let vertices = positions(mesh)?;
    let n = vertices.len();
    let mut tris = Vec::new();
    let corner = |p: &[usize], stride: usize, voff: usize, k: usize| -> Result<u32, DaeError> {
        let i = *p.get(k * stride + voff).ok_or(DaeError::ShortIndexList)?;
        if i >= n {
            return Err(DaeError::IndexOutOfRange {
                index: i,
                positions: n,
            });
        }
        Ok(i as u32)
    };
    for prim in &mesh.children {
        match prim.name.as_str() {
            "triangles" | "polylist" | "polygons" => {}
            "lines" | "linestrips" => continue,
            other @ ("trifans" | "tristrips") => {
                return Err(DaeError::Unsupported {
                    primitive: other.to_owned(),
                })
            }
            _ => continue,
        }
        let (voff, stride) = layout(prim)?;
        // Polygons as corner counts, then fan-triangulated (exact for convex polygons).
        let mut polys: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
        match prim.name.as_str() {
            "triangles" => {
                let p = indices(prim.child("p").map(|p| p.text.as_str()).unwrap_or(""))?;
                let corners = p.len() / stride;
                polys.push((vec![3; corners / 3], p));
            }
            "polylist" => {
                let vcount = indices(prim.child("vcount").map(|v| v.text.as_str()).unwrap_or(""))?;
                let p = indices(prim.child("p").map(|p| p.text.as_str()).unwrap_or(""))?;
                polys.push((vcount, p));
            }
            _ => {
                for p in prim.children_named("p") {
                    let p = indices(&p.text)?;
                    let corners = p.len() / stride;
                    polys.push((vec![corners], p));
                }
            }
        }
        for (counts, p) in &polys {
            let mut base = 0usize;
            for &c in counts {
                if c >= 3 {
                    let first = corner(p, stride, voff, base)?;
                    for k in 1..c - 1 {
                        tris.push([
                            first,
                            corner(p, stride, voff, base + k)?,
                            corner(p, stride, voff, base + k + 1)?,
                        ]);
                    }
                }
                base = base.checked_add(c).ok_or(DaeError::VcountOverflow)?;
            }
        }
    }
    Ok(TriMeshData {
        vertices,
        indices: tris,
    })
}
