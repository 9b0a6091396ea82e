//! What a URDF became: links with their collision shapes (or why a link has none) and joints
//! with their limits. `drape check` prints it so a user sees which links the cloth can touch
//! before running a scene (a link without `<collision>` is not an obstacle, silently otherwise).

use super::kinematics::JointKind;
use super::{Geometry, Robot, ShapeSource};
use std::fmt;

/// A printable description of a loaded [`Robot`]; counts are public for tests and tools.
#[derive(Debug, Clone)]
pub struct RobotSummary {
    pub name: String,
    pub links: Vec<LinkSummary>,
    pub joints: Vec<JointSummary>,
}

#[derive(Debug, Clone)]
pub struct LinkSummary {
    pub name: String,
    pub source: ShapeSource,
    /// One line per shape, e.g. `capsule r 0.030 length 0.200` or `mesh 1212 triangles`.
    pub shapes: Vec<String>,
    /// Triangles over the link's mesh shapes.
    pub mesh_triangles: usize,
}

#[derive(Debug, Clone)]
pub struct JointSummary {
    pub name: String,
    pub kind: JointKind,
    pub parent: String,
    pub child: String,
    pub limits: Option<(f64, f64)>,
    pub velocity_limit: Option<f64>,
    /// The joint this one mimics, if any.
    pub mimics: Option<String>,
}

impl RobotSummary {
    pub fn of(robot: &Robot) -> Self {
        let k = robot.kinematics();
        let names = k.links();
        let links = names
            .iter()
            .zip(robot.collision_shapes())
            .zip(robot.shape_sources())
            .map(|((name, shapes), &source)| LinkSummary {
                name: name.clone(),
                source,
                shapes: shapes.iter().map(|(_, g)| describe(g)).collect(),
                mesh_triangles: shapes
                    .iter()
                    .map(|(_, g)| match g {
                        Geometry::Mesh(m) => m.indices.len(),
                        _ => 0,
                    })
                    .sum(),
            })
            .collect();
        let joints = k
            .joints()
            .iter()
            .map(|j| JointSummary {
                name: j.name.clone(),
                kind: j.kind,
                parent: names[j.parent_link].clone(),
                child: names[j.child_link].clone(),
                limits: j.limits,
                velocity_limit: j.velocity_limit,
                mimics: j.mimic.as_ref().map(|m| k.joints()[m.joint].name.clone()),
            })
            .collect();
        RobotSummary {
            name: robot.name.clone(),
            links,
            joints,
        }
    }

    /// Links that are obstacles (have at least one shape).
    pub fn obstacle_links(&self) -> usize {
        self.links.iter().filter(|l| !l.shapes.is_empty()).count()
    }

    pub fn shapes(&self) -> usize {
        self.links.iter().map(|l| l.shapes.len()).sum()
    }

    pub fn mesh_triangles(&self) -> usize {
        self.links.iter().map(|l| l.mesh_triangles).sum()
    }
}

fn describe(g: &Geometry) -> String {
    match g {
        Geometry::Sphere { radius } => format!("sphere r {radius:.3}"),
        Geometry::Box { half_extents: h } => {
            format!("box {:.3} x {:.3} x {:.3}", 2.0 * h.x, 2.0 * h.y, 2.0 * h.z)
        }
        Geometry::Cylinder { radius, length } => {
            format!("cylinder r {radius:.3} length {length:.3}")
        }
        Geometry::Capsule { radius, length } => format!("capsule r {radius:.3} length {length:.3}"),
        Geometry::Mesh(m) => format!(
            "mesh {} triangles, {} vertices",
            m.indices.len(),
            m.vertices.len()
        ),
    }
}

impl fmt::Display for RobotSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let actuated = self.joints.iter().filter(|j| j.kind.is_scalar()).count();
        writeln!(
            f,
            "robot '{}': {} links ({} obstacles, {} shapes, {} mesh triangles), {} joints ({} \
             with a position)",
            self.name,
            self.links.len(),
            self.obstacle_links(),
            self.shapes(),
            self.mesh_triangles(),
            self.joints.len(),
            actuated
        )?;
        for l in &self.links {
            match l.source {
                ShapeSource::Collision | ShapeSource::VisualFallback => {
                    let from = if l.source == ShapeSource::VisualFallback {
                        " (from <visual>: visual_fallback)"
                    } else {
                        ""
                    };
                    writeln!(f, "  link {}{from}: {}", l.name, l.shapes.join("; "))?;
                }
                ShapeSource::SkippedVisualOnly => writeln!(
                    f,
                    "  link {}: skipped, no <collision> (it has <visual>; robot.visual_fallback: \
                     true would use it)",
                    l.name
                )?,
                ShapeSource::SkippedNoGeometry => {
                    writeln!(f, "  link {}: skipped, no geometry (a frame)", l.name)?
                }
            }
        }
        for j in &self.joints {
            let kind = format!("{:?}", j.kind).to_lowercase();
            write!(
                f,
                "  joint {} ({kind}): {} -> {}",
                j.name, j.parent, j.child
            )?;
            if let Some((lo, hi)) = j.limits {
                write!(f, ", limits [{lo:.3}, {hi:.3}]")?;
            }
            if let Some(v) = j.velocity_limit {
                write!(f, ", velocity limit {v:.3}")?;
            }
            if let Some(m) = &j.mimics {
                write!(f, ", mimics {m}")?;
            }
            writeln!(f)?;
        }
        Ok(())
    }
}
