//! URDF loading: parse with `urdf-rs`, build the kinematic tree, and collect per-link collision
//! geometry (optionally falling back to visual geometry) with meshes resolved and loaded.

use super::kinematics::{JointKind, JointSpec, Kinematics, TreeError, MAX_LENGTH};
use super::resolve::{resolve_uri, ResolveError, SearchPaths};
use super::{Geometry, Robot};
use crate::mesh::{load_mesh, MeshError, TriMeshData};
use crate::{Pose, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How to load a URDF.
#[derive(Debug, Clone)]
pub struct UrdfOptions {
    /// Use a link's `<visual>` geometry when it has no `<collision>` element.
    pub visual_fallback: bool,
    /// Extra directories searched for `package://` URIs (a package or a folder of packages).
    pub search_paths: Vec<PathBuf>,
    /// Also search `ROS_PACKAGE_PATH` and `AMENT_PREFIX_PATH`.
    pub use_ros_env: bool,
}

impl Default for UrdfOptions {
    fn default() -> Self {
        Self {
            visual_fallback: false,
            search_paths: Vec::new(),
            use_ros_env: true,
        }
    }
}

/// Why a robot description could not be loaded; names the file, link or joint at fault.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    #[error("cannot read URDF {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("invalid URDF {origin}: {message}")]
    Parse { origin: String, message: String },
    #[error("URDF {origin}: {source}")]
    Tree {
        origin: String,
        #[source]
        source: TreeError,
    },
    #[error("link `{link}`: mesh `{uri}` not found; tried: {}", display_paths(.tried))]
    MeshNotFound {
        link: String,
        uri: String,
        tried: Vec<PathBuf>,
    },
    #[error("link `{link}`: mesh `{uri}` escapes its package directory")]
    PackageEscape { link: String, uri: String },
    #[error("link `{link}`: {message}")]
    UnsupportedUri { link: String, message: String },
    #[error("link `{link}`: {source}")]
    Mesh {
        link: String,
        #[source]
        source: MeshError,
    },
    #[error("link `{link}`: invalid geometry: {message}")]
    BadGeometry { link: String, message: String },
}

fn display_paths(paths: &[PathBuf]) -> String {
    if paths.is_empty() {
        return "(no candidate directories)".into();
    }
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

fn to_pose(p: &urdf_rs::Pose) -> Pose {
    Pose::from_xyz_rpy(p.xyz.0, p.rpy.0)
}

impl Robot {
    /// Loads a URDF file; relative and `package://` mesh paths are also looked up around it.
    pub fn from_urdf_file(path: &Path, options: &UrdfOptions) -> Result<Robot, RobotError> {
        let bytes = std::fs::read(path).map_err(|source| RobotError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let text = String::from_utf8(bytes).map_err(|e| RobotError::Parse {
            origin: path.display().to_string(),
            message: format!("not UTF-8: {e}"),
        })?;
        let dir = path.parent().map(|d| {
            if d.as_os_str().is_empty() {
                Path::new(".")
            } else {
                d
            }
        });
        build(&text, &path.display().to_string(), dir, options)
    }

    /// Loads a URDF from a string (e.g. the `/robot_description` parameter; trailing NUL bytes
    /// are ignored). `base_dir` plays the role of the URDF's folder for mesh lookup.
    pub fn from_urdf_str(
        xml: &str,
        base_dir: Option<&Path>,
        options: &UrdfOptions,
    ) -> Result<Robot, RobotError> {
        build(xml, "<string>", base_dir, options)
    }
}

fn build(
    xml: &str,
    origin: &str,
    dir: Option<&Path>,
    options: &UrdfOptions,
) -> Result<Robot, RobotError> {
    let xml = xml.trim_end_matches(['\0', ' ', '\n', '\r', '\t']);
    let urdf = urdf_rs::read_from_string(xml).map_err(|e| RobotError::Parse {
        origin: origin.to_string(),
        message: e.to_string(),
    })?;
    let links: Vec<String> = urdf.links.iter().map(|l| l.name.clone()).collect();
    let specs = urdf
        .joints
        .iter()
        .map(|j| JointSpec {
            name: j.name.clone(),
            kind: match j.joint_type {
                urdf_rs::JointType::Fixed => JointKind::Fixed,
                urdf_rs::JointType::Revolute => JointKind::Revolute,
                urdf_rs::JointType::Continuous => JointKind::Continuous,
                urdf_rs::JointType::Prismatic => JointKind::Prismatic,
                // A ball joint's rotation is a free pose, like a floating joint's.
                urdf_rs::JointType::Floating | urdf_rs::JointType::Spherical => JointKind::Floating,
                urdf_rs::JointType::Planar => JointKind::Planar,
            },
            parent: j.parent.link.clone(),
            child: j.child.link.clone(),
            origin: to_pose(&j.origin),
            axis: Vec3::from(j.axis.xyz.0),
            lower: j.limit.lower,
            upper: j.limit.upper,
            velocity: j.limit.velocity,
            mimic: j.mimic.as_ref().map(|m| {
                (
                    m.joint.clone(),
                    m.multiplier.unwrap_or(1.0),
                    m.offset.unwrap_or(0.0),
                )
            }),
        })
        .collect();
    let kinematics = Kinematics::new(links, specs).map_err(|source| RobotError::Tree {
        origin: origin.to_string(),
        source,
    })?;
    let search = if options.use_ros_env {
        SearchPaths::from_env(options.search_paths.clone())
    } else {
        SearchPaths {
            extra: options.search_paths.clone(),
            ..Default::default()
        }
    };
    let mut cache: HashMap<(PathBuf, [u64; 3]), Arc<TriMeshData>> = HashMap::new();
    let mut collision = Vec::with_capacity(urdf.links.len());
    for link in &urdf.links {
        let elems: Vec<(&urdf_rs::Pose, &urdf_rs::Geometry)> = if !link.collision.is_empty() {
            link.collision
                .iter()
                .map(|c| (&c.origin, &c.geometry))
                .collect()
        } else if options.visual_fallback {
            link.visual
                .iter()
                .map(|v| (&v.origin, &v.geometry))
                .collect()
        } else {
            Vec::new()
        };
        let mut shapes = Vec::with_capacity(elems.len());
        for (o, g) in elems {
            let pose = to_pose(o);
            if !pose.is_finite() || pose.translation.length() > MAX_LENGTH {
                return Err(RobotError::BadGeometry {
                    link: link.name.clone(),
                    message: format!("origin is not finite or farther than {MAX_LENGTH:e} m"),
                });
            }
            let geometry = convert_geometry(&link.name, g, dir, &search, &mut cache)?;
            shapes.push((pose, geometry));
        }
        collision.push(shapes);
    }
    Ok(Robot {
        name: urdf.name,
        kinematics,
        collision,
    })
}

fn positive(link: &str, what: &str, v: f64) -> Result<f64, RobotError> {
    if v.is_finite() && v > 0.0 && v <= MAX_LENGTH {
        Ok(v)
    } else {
        Err(RobotError::BadGeometry {
            link: link.to_string(),
            message: format!("{what} must be positive and at most {MAX_LENGTH:e} m, got {v}"),
        })
    }
}

fn convert_geometry(
    link: &str,
    g: &urdf_rs::Geometry,
    dir: Option<&Path>,
    search: &SearchPaths,
    cache: &mut HashMap<(PathBuf, [u64; 3]), Arc<TriMeshData>>,
) -> Result<Geometry, RobotError> {
    Ok(match g {
        urdf_rs::Geometry::Box { size } => {
            for (axis, v) in ["x", "y", "z"].iter().zip(size.0) {
                positive(link, &format!("box size {axis}"), v)?;
            }
            Geometry::Box {
                half_extents: Vec3::from(size.0) * 0.5,
            }
        }
        urdf_rs::Geometry::Sphere { radius } => Geometry::Sphere {
            radius: positive(link, "sphere radius", *radius)?,
        },
        urdf_rs::Geometry::Cylinder { radius, length } => Geometry::Cylinder {
            radius: positive(link, "cylinder radius", *radius)?,
            length: positive(link, "cylinder length", *length)?,
        },
        urdf_rs::Geometry::Capsule { radius, length } => Geometry::Capsule {
            radius: positive(link, "capsule radius", *radius)?,
            length: positive(link, "capsule length", *length)?,
        },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let path = resolve_uri(filename, dir, search).map_err(|e| match e {
                ResolveError::NotFound(tried) => RobotError::MeshNotFound {
                    link: link.to_string(),
                    uri: filename.clone(),
                    tried,
                },
                ResolveError::Escape => RobotError::PackageEscape {
                    link: link.to_string(),
                    uri: filename.clone(),
                },
                ResolveError::Unsupported(message) => RobotError::UnsupportedUri {
                    link: link.to_string(),
                    message,
                },
            })?;
            let scale = Vec3::from(scale.as_ref().map(|s| s.0).unwrap_or([1.0; 3]));
            let key = (path.clone(), scale.to_array().map(f64::to_bits));
            if let Some(m) = cache.get(&key) {
                return Ok(Geometry::Mesh(m.clone()));
            }
            let mesh = Arc::new(load_mesh(&path, scale).map_err(|source| RobotError::Mesh {
                link: link.to_string(),
                source,
            })?);
            cache.insert(key, mesh.clone());
            Geometry::Mesh(mesh)
        }
    })
}
