//! URDF loading: parse with `urdf-rs`, build the kinematic tree, and collect per-link collision
//! geometry (optionally falling back to visual geometry) with meshes resolved and loaded.

use super::kinematics::{JointKind, JointSpec, Kinematics, TreeError, MAX_LENGTH};
use super::resolve::{allowed_roots, resolve_uri, ResolveError, SearchPaths};
use super::{Geometry, Robot, ShapeSource};
use crate::input::{InputError, InputKind};
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
    /// Folders meshes may also come from besides the URDF's package tree and the search paths
    /// (the scene's folder and its `mesh_paths`); see [`super::resolve`].
    pub mesh_roots: Vec<PathBuf>,
    /// Leave out a mesh that is not found instead of failing (listed in
    /// [`Robot::missing_meshes`]): for drawing a recorded robot, where the rest still helps.
    pub skip_missing_meshes: bool,
}

impl Default for UrdfOptions {
    fn default() -> Self {
        Self {
            visual_fallback: false,
            search_paths: Vec::new(),
            use_ros_env: true,
            mesh_roots: Vec::new(),
            skip_missing_meshes: false,
        }
    }
}

/// Deepest element nesting accepted in a URDF (real ones nest about five deep); checked by a
/// streaming pass before the recursive parser sees the text.
pub const MAX_XML_DEPTH: usize = 64;

/// Why a robot description could not be loaded; names the file, link or joint at fault.
/// The cause, if any, is the `source()`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RobotError {
    /// The URDF file could not be read (missing, not a regular file, too large, not UTF-8).
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{origin}: not a valid URDF")]
    Parse {
        origin: String,
        #[source]
        source: urdf_rs::UrdfError,
    },
    #[error("{origin}: not well-formed XML")]
    Xml {
        origin: String,
        #[source]
        source: quick_xml::Error,
    },
    #[error("{origin}: XML nested deeper than {max} elements")]
    TooDeep { origin: String, max: usize },
    #[error("{origin}: root element is <{found}>, expected <robot>")]
    Root { origin: String, found: String },
    #[error("{origin}: invalid kinematic tree")]
    Tree {
        origin: String,
        #[source]
        source: TreeError,
    },
    #[error("{origin}: joint `{joint}`: mimic {what} must be finite and at most {max:e} in size (got {value:e})")]
    BadMimic {
        origin: String,
        joint: String,
        what: &'static str,
        value: f64,
        max: f64,
    },
    /// A `<limit>` attribute that is not finite, out of order or negative where it cannot be.
    #[error("{origin}: joint `{joint}`: <limit {attribute}=\"{value:?}\">: {why}")]
    BadLimit {
        origin: String,
        joint: String,
        attribute: &'static str,
        value: f64,
        why: &'static str,
    },
    #[error("link `{link}`: mesh `{uri}` not found; tried: {}", display_paths(.tried))]
    MeshNotFound {
        link: String,
        uri: String,
        tried: Vec<PathBuf>,
    },
    #[error("link `{link}`: mesh `{uri}` escapes its package directory")]
    PackageEscape { link: String, uri: String },
    #[error("link `{link}`: mesh `{uri}`: unsupported URI")]
    UnsupportedUri { link: String, uri: String },
    /// The mesh resolved (through `..` or a symlink) outside the folders meshes may come from.
    #[error("link `{link}`: mesh `{uri}` is outside the allowed folders")]
    MeshOutside {
        link: String,
        uri: String,
        #[source]
        source: Box<InputError>,
    },
    #[error("link `{link}`: mesh {}", .path.display())]
    Mesh {
        link: String,
        path: PathBuf,
        #[source]
        source: Box<MeshError>,
    },
    #[error("link `{link}`: {what} must be positive and at most {MAX_LENGTH:e} m (got {value})")]
    BadGeometry {
        link: String,
        what: String,
        value: f64,
    },
    #[error("link `{link}`: collision origin is not finite or farther than {MAX_LENGTH:e} m")]
    BadOrigin { link: String },
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

/// Largest joint limit accepted (rad or m for positions, per second for velocities, N or N m
/// for efforts); larger ones are typos or attacks, not robots.
pub const MAX_LIMIT: f64 = 1e6;

/// Every joint's `<limit>`: finite, at most [`MAX_LIMIT`] in size, `lower <= upper`, velocity
/// and effort not negative. The parser fills an absent `<limit>` with zeros, which passes.
fn check_limits(urdf: &urdf_rs::Robot, origin: &str) -> Result<(), RobotError> {
    for j in &urdf.joints {
        let l = &j.limit;
        let bad = |attribute, value, why| RobotError::BadLimit {
            origin: origin.to_string(),
            joint: j.name.clone(),
            attribute,
            value,
            why,
        };
        for (attribute, value) in [
            ("lower", l.lower),
            ("upper", l.upper),
            ("velocity", l.velocity),
            ("effort", l.effort),
        ] {
            if !value.is_finite() {
                return Err(bad(attribute, value, "must be a finite number"));
            }
            if value.abs() > MAX_LIMIT {
                return Err(bad(attribute, value, "is larger than 1e6 in size"));
            }
        }
        if l.lower > l.upper {
            return Err(bad("lower", l.lower, "is above upper"));
        }
        if l.velocity < 0.0 {
            return Err(bad("velocity", l.velocity, "must not be negative"));
        }
        if l.effort < 0.0 {
            return Err(bad("effort", l.effort, "must not be negative"));
        }
    }
    Ok(())
}

/// A streaming pass over the XML: nesting depth at most [`MAX_XML_DEPTH`] and a `<robot>` root,
/// so the recursive parser behind `urdf-rs` can neither overflow the stack nor accept a
/// misspelled document.
fn prescan(xml: &str, origin: &str) -> Result<(), RobotError> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut depth = 0usize;
    let mut root: Option<String> = None;
    loop {
        let event = reader.read_event().map_err(|source| RobotError::Xml {
            origin: origin.to_string(),
            source,
        })?;
        let start = match &event {
            Event::Start(e) | Event::Empty(e) => Some(e.local_name().as_ref().to_vec()),
            _ => None,
        };
        if let Some(name) = start {
            if root.is_none() {
                let name = String::from_utf8_lossy(&name).into_owned();
                if name != "robot" {
                    return Err(RobotError::Root {
                        origin: origin.to_string(),
                        found: name,
                    });
                }
                root = Some(name);
            }
        }
        match event {
            Event::Start(_) => {
                depth += 1;
                if depth > MAX_XML_DEPTH {
                    return Err(RobotError::TooDeep {
                        origin: origin.to_string(),
                        max: MAX_XML_DEPTH,
                    });
                }
            }
            Event::End(_) => depth = depth.saturating_sub(1),
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(())
}

fn to_pose(p: &urdf_rs::Pose) -> Pose {
    Pose::from_xyz_rpy(p.xyz.0, p.rpy.0)
}

impl Robot {
    /// Loads a URDF file; relative and `package://` mesh paths are also looked up around it.
    pub fn from_urdf_file(path: &Path, options: &UrdfOptions) -> Result<Robot, RobotError> {
        let text = crate::input::read_text(path, InputKind::Urdf)?;
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

    /// [`Robot::from_urdf_str`] with the name errors should start with (e.g. the file the text
    /// was read from).
    pub fn from_urdf_named(
        xml: &str,
        origin: &str,
        base_dir: Option<&Path>,
        options: &UrdfOptions,
    ) -> Result<Robot, RobotError> {
        build(xml, origin, base_dir, options)
    }
}

fn build(
    xml: &str,
    origin: &str,
    dir: Option<&Path>,
    options: &UrdfOptions,
) -> Result<Robot, RobotError> {
    let xml = crate::input::strip_bom(xml).trim_end_matches(['\0', ' ', '\n', '\r', '\t']);
    prescan(xml, origin)?;
    let urdf = urdf_rs::read_from_string(xml).map_err(|source| RobotError::Parse {
        origin: origin.to_string(),
        source,
    })?;
    check_mimics(&urdf, origin)?;
    check_limits(&urdf, origin)?;
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
    let mut missing_meshes = Vec::new();
    let mut collision = Vec::with_capacity(urdf.links.len());
    let mut sources = Vec::with_capacity(urdf.links.len());
    for link in &urdf.links {
        sources.push(match (link.collision.is_empty(), link.visual.is_empty()) {
            (false, _) => ShapeSource::Collision,
            (true, false) if options.visual_fallback => ShapeSource::VisualFallback,
            (true, false) => ShapeSource::SkippedVisualOnly,
            (true, true) => ShapeSource::SkippedNoGeometry,
        });
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
                return Err(RobotError::BadOrigin {
                    link: link.name.clone(),
                });
            }
            match convert_geometry(&link.name, g, dir, &search, options, &mut cache) {
                Ok(geometry) => shapes.push((pose, geometry)),
                Err(RobotError::MeshNotFound { uri, .. }) if options.skip_missing_meshes => {
                    missing_meshes.push(uri);
                }
                Err(e) => return Err(e),
            }
        }
        collision.push(shapes);
    }
    Ok(Robot {
        name: urdf.name,
        kinematics,
        collision,
        sources,
        missing_meshes,
    })
}

/// Largest mimic multiplier and offset accepted: a mimic maps a joint range of a few radians
/// or metres onto another; beyond this it is a typo or an attack on f64 headroom.
pub const MAX_MIMIC: f64 = 1e3;

/// Mimic multipliers and offsets must be finite and plausible (`nan` would record NaN joint
/// states and `/tf` rotations).
fn check_mimics(urdf: &urdf_rs::Robot, origin: &str) -> Result<(), RobotError> {
    for j in &urdf.joints {
        let Some(m) = &j.mimic else { continue };
        for (what, v) in [("multiplier", m.multiplier), ("offset", m.offset)] {
            if let Some(value) = v {
                if !value.is_finite() || value.abs() > MAX_MIMIC {
                    return Err(RobotError::BadMimic {
                        origin: origin.to_string(),
                        joint: j.name.clone(),
                        what,
                        value,
                        max: MAX_MIMIC,
                    });
                }
            }
        }
    }
    Ok(())
}

fn positive(link: &str, what: &str, v: f64) -> Result<f64, RobotError> {
    if v.is_finite() && v > 0.0 && v <= MAX_LENGTH {
        Ok(v)
    } else {
        Err(RobotError::BadGeometry {
            link: link.to_string(),
            what: what.to_string(),
            value: v,
        })
    }
}

fn convert_geometry(
    link: &str,
    g: &urdf_rs::Geometry,
    dir: Option<&Path>,
    search: &SearchPaths,
    options: &UrdfOptions,
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
                ResolveError::Unsupported(_) => RobotError::UnsupportedUri {
                    link: link.to_string(),
                    uri: filename.clone(),
                },
            })?;
            // Resolved (symlinks, `..`) and checked against the allowed folders before opening.
            let roots = allowed_roots(filename, dir, search, &options.mesh_roots);
            let path = crate::input::contained(&path, &roots).map_err(|source| {
                RobotError::MeshOutside {
                    link: link.to_string(),
                    uri: filename.clone(),
                    source: Box::new(source),
                }
            })?;
            let scale = Vec3::from(scale.as_ref().map(|s| s.0).unwrap_or([1.0; 3]));
            let key = (path.clone(), scale.to_array().map(f64::to_bits));
            if let Some(m) = cache.get(&key) {
                return Ok(Geometry::Mesh(m.clone()));
            }
            let mesh = Arc::new(load_mesh(&path, scale).map_err(|source| RobotError::Mesh {
                link: link.to_string(),
                path: path.clone(),
                source: Box::new(source),
            })?);
            cache.insert(key, mesh.clone());
            Geometry::Mesh(mesh)
        }
    })
}
