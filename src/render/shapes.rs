//! The robot's collision shapes as triangle meshes, posed per frame from `/tf`.

use super::raster::Mesh;
use crate::robot::{Geometry, Robot, RobotError, UrdfOptions};
use crate::{Pose, Vec3};
use std::collections::HashMap;
use std::f64::consts::TAU;
use std::path::Path;

/// Shapes per link, in link coordinates.
#[derive(Debug, Clone)]
pub struct RobotShapes {
    /// (link name, shape mesh in the link frame), the root link's under its own name.
    links: Vec<(String, Mesh)>,
    /// Mesh URIs not found (their shapes are left out).
    pub missing: Vec<String>,
}

const ROBOT_COLOR: [f64; 3] = [0.45, 0.55, 0.68];

impl RobotShapes {
    /// From URDF text (`/robot_description`); relative meshes are resolved against `dir` (the
    /// URDF's folder), `package://` ones as `opts` says (see [`crate::robot::resolve`]).
    pub fn from_urdf(
        urdf: &str,
        dir: Option<&Path>,
        opts: &UrdfOptions,
    ) -> Result<RobotShapes, RobotError> {
        let robot = Robot::from_urdf_str(urdf, dir, opts)?;
        let names = robot.link_names().to_vec();
        let mut links = Vec::new();
        for (l, shapes) in robot.collision_shapes().iter().enumerate() {
            for (pose, g) in shapes {
                let mut m = tessellate(g);
                for p in &mut m.positions {
                    *p = pose.transform_point(*p);
                }
                m.color = ROBOT_COLOR;
                m.smooth_normals();
                if let Some(name) = names.get(l) {
                    links.push((name.clone(), m));
                }
            }
        }
        let mut missing: Vec<String> = Vec::new();
        for uri in robot.missing_meshes() {
            if !missing.contains(uri) {
                missing.push(uri.clone());
            }
        }
        Ok(RobotShapes { links, missing })
    }

    /// The shapes at the link poses (root frame); links without a pose are at the origin
    /// (the root link).
    pub fn meshes(&self, poses: &HashMap<String, Pose>) -> Vec<Mesh> {
        self.links
            .iter()
            .map(|(name, m)| {
                let pose = poses.get(name).copied().unwrap_or(Pose::IDENTITY);
                let mut out = m.clone();
                for p in &mut out.positions {
                    *p = pose.transform_point(*p);
                }
                out.smooth_normals();
                out
            })
            .collect()
    }
}

/// A shape as triangles: boxes with flat faces (split vertices), round shapes with 24 segments.
/// Cylinders and capsules run along local z, as in URDF.
pub(super) fn tessellate(g: &Geometry) -> Mesh {
    let mut m = Mesh::default();
    match g {
        Geometry::Box { half_extents: h } => {
            for axis in 0..3 {
                for sign in [-1.0, 1.0] {
                    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                    let base = m.positions.len() as u32;
                    for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                        let mut p = [0.0; 3];
                        p[axis] = sign * h[axis];
                        p[u] = a * h[u];
                        p[v] = b * h[v];
                        m.positions.push(Vec3::from(p));
                    }
                    m.triangles.push([base, base + 1, base + 2]);
                    m.triangles.push([base, base + 2, base + 3]);
                }
            }
        }
        Geometry::Sphere { radius } => lathe(&mut m, 12, |s| {
            let a = std::f64::consts::PI * s;
            (radius * a.sin(), -radius * a.cos())
        }),
        Geometry::Cylinder { radius, length } => {
            let (r, h) = (*radius, length / 2.0);
            lathe(&mut m, 3, |s| match (s * 3.0).round() as i32 {
                0 => (0.0, -h),
                1 => (r, -h),
                2 => (r, h),
                _ => (0.0, h),
            })
        }
        Geometry::Capsule { radius, length } => {
            let (r, h) = (*radius, length / 2.0);
            lathe(&mut m, 12, |s| {
                let a = std::f64::consts::PI * s;
                let z = -r * a.cos();
                (r * a.sin(), if s < 0.5 { z - h } else { z + h })
            })
        }
        Geometry::Mesh(data) => {
            m.positions = data.vertices.clone();
            m.triangles = data.indices.clone();
        }
    }
    m
}

/// A surface of revolution about z from a profile `s in [0, 1] -> (radius, z)` sampled at
/// `rings + 1` points.
fn lathe(m: &mut Mesh, rings: usize, profile: impl Fn(f64) -> (f64, f64)) {
    const SEG: usize = 24;
    for i in 0..=rings {
        let (r, z) = profile(i as f64 / rings as f64);
        for j in 0..SEG {
            let a = TAU * j as f64 / SEG as f64;
            m.positions.push(Vec3::new(r * a.cos(), r * a.sin(), z));
        }
    }
    for i in 0..rings {
        for j in 0..SEG {
            let (a, b) = ((i * SEG + j) as u32, (i * SEG + (j + 1) % SEG) as u32);
            let (c, d) = (a + SEG as u32, b + SEG as u32);
            m.triangles.push([a, b, d]);
            m.triangles.push([a, d, c]);
        }
    }
}
