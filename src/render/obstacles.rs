//! The scene's own obstacles as the recorder wrote them (`<prefix>/obstacles`, one Marker per
//! message, see [`crate::ros::obstacles`]): the markers in force at a frame, turned into meshes;
//! planes are kept apart as (point, normal) so the picture frames the cloth, not an unbounded
//! plane, and each tile draws the plane as a square around what it frames.

use super::marker::MarkerHead;
use super::raster::Mesh;
use super::shapes::tessellate;
use crate::robot::Geometry;
use crate::ros::msg::Marker;
use crate::ros::obstacles::{OBSTACLE_COLOR, PLANE_NS};
use crate::{Pose, Vec3};
use std::collections::BTreeMap;

/// Colour of a plane's square.
const PLANE_COLOR: [f64; 3] = [0.80, 0.80, 0.76];
/// Cells per side of a plane's square: small cells keep the parts in front of the camera when
/// others are behind it (the rasteriser drops a triangle with a vertex behind the camera).
const PLANE_CELLS: usize = 24;

/// The obstacles of one frame: solids as meshes, planes as (point, unit normal).
#[derive(Debug, Clone, Default)]
pub struct Obstacles {
    pub meshes: Vec<Mesh>,
    pub planes: Vec<(Vec3, Vec3)>,
}

/// The markers in force at `t` (ns): per `(ns, id)` the last one at or before `t`, or the
/// first one written when all come later.
pub(super) fn at(series: &[(u64, MarkerHead)], t: u64) -> Obstacles {
    let first = series.first().map_or(0, |(s, _)| *s);
    let mut latest: BTreeMap<(&str, i32), &MarkerHead> = BTreeMap::new();
    for (s, m) in series {
        if *s <= t.max(first) {
            latest.insert((m.ns.as_str(), m.id), m);
        }
    }
    let mut out = Obstacles::default();
    for m in latest.into_values() {
        let o = &m.pose.orientation;
        let pose = Pose::new(
            Vec3::new(m.pose.position.x, m.pose.position.y, m.pose.position.z),
            glam::DQuat::from_xyzw(o.x, o.y, o.z, o.w).normalize(),
        );
        if !(pose.translation.is_finite() && pose.rotation.is_finite()) {
            continue;
        }
        if m.ns == PLANE_NS {
            out.planes
                .push((pose.translation, pose.transform_vector(Vec3::Z)));
            continue;
        }
        let s = Vec3::new(m.scale.x, m.scale.y, m.scale.z);
        let mut mesh = match m.r#type {
            Marker::SPHERE => tessellate(&Geometry::Sphere { radius: s.x / 2.0 }),
            Marker::CUBE => tessellate(&Geometry::Box {
                half_extents: s / 2.0,
            }),
            Marker::CYLINDER => tessellate(&Geometry::Cylinder {
                radius: s.x / 2.0,
                length: s.z,
            }),
            Marker::TRIANGLE_LIST => {
                let positions: Vec<Vec3> =
                    m.points.iter().map(|p| Vec3::new(p.x, p.y, p.z)).collect();
                let n = positions.len() / 3 * 3;
                Mesh {
                    triangles: (0..n as u32 / 3)
                        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
                        .collect(),
                    positions,
                    ..Mesh::default()
                }
            }
            _ => continue,
        };
        for p in &mut mesh.positions {
            *p = pose.transform_point(*p);
        }
        let c = [m.color.r, m.color.g, m.color.b].map(f64::from);
        let [r, g, b, _] = OBSTACLE_COLOR.map(f64::from);
        mesh.color = if c.iter().all(|c| *c <= 0.0) {
            [r, g, b]
        } else {
            c
        };
        mesh.smooth_normals();
        out.meshes.push(mesh);
    }
    out
}

/// A plane through `point` with normal `normal` as a square of side `4 r` centred below `c`
/// (the framed sphere's centre projected onto the plane).
pub(super) fn plane_square(point: Vec3, normal: Vec3, (c, r): (Vec3, f64)) -> Mesh {
    let n = normal.normalize_or(Vec3::Z);
    let centre = c - n * (c - point).dot(n);
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let half = 2.0 * r;
    let mut m = Mesh {
        color: PLANE_COLOR,
        ..Mesh::default()
    };
    let k = PLANE_CELLS;
    for i in 0..=k {
        for j in 0..=k {
            let a = -half + 2.0 * half * i as f64 / k as f64;
            let b = -half + 2.0 * half * j as f64 / k as f64;
            m.positions.push(centre + u * a + v * b);
            m.normals.push(n);
        }
    }
    let at = |i: usize, j: usize| (i * (k + 1) + j) as u32;
    for i in 0..k {
        for j in 0..k {
            m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    m
}
