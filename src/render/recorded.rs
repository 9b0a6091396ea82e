//! The run a bag was recorded from, as its `drape` metadata names it ([`RunInfo`]): the scene's
//! name for the tiles' labels, the cloth pieces for their colours, and the scene file itself,
//! read again to find the robot's meshes where `drape record` found them and to draw the
//! scene's static obstacles when the bag does not carry them.
//!
//! The bag is trusted little with where meshes may come from: it names a scene file, read
//! through the input rules, whose folders are the ones it allows `drape record` (its folder, its
//! `mesh_paths`, its URDF's package); and the package folders the run searched, of which only
//! ROS packages count (a folder holding a `package.xml`, or a folder of such folders), so a bag
//! cannot open an arbitrary folder to its URDF. The user's `--package-path` and the ROS
//! environment are searched as well.

use super::marker::MarkerHead;
use crate::robot::UrdfOptions;
use crate::ros::bag::{BagBytes, RunInfo};
use crate::ros::msg::{Marker, Time};
use crate::scene::Scene;
use crate::Vec3;
use std::path::{Path, PathBuf};

/// What the bag says of its run, and the scene file read again when it still loads.
#[derive(Debug, Default)]
pub(super) struct Recorded {
    pub info: RunInfo,
    scene: Option<Scene>,
}

impl Recorded {
    /// Reads the bag's metadata and the scene it names; a scene that no longer loads is a
    /// warning (the bag is still drawn, without what the scene would add).
    pub fn of(bag: &BagBytes) -> Recorded {
        let info = bag.run_info().unwrap_or_default();
        let scene = info.scene.as_deref().and_then(|path| {
            Scene::load(path)
                .map_err(|e| {
                    log::warn!(
                        "{}: the scene it was recorded from is not read: {}",
                        bag.path().display(),
                        crate::input::error_line(&e)
                    )
                })
                .ok()
        });
        Recorded { info, scene }
    }

    /// The scene's name (or, for a bag without one, the bag's file name).
    pub fn name(&self, bag: &Path) -> String {
        self.info
            .scene_name
            .clone()
            .filter(|n| !n.is_empty())
            .or_else(|| self.scene.as_ref().map(|s| s.name.clone()))
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| {
                bag.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            })
    }

    /// How to load the bag's URDF so that its meshes are found as the run found them: the
    /// URDF's folder (from the scene, else the first `package_paths` entry) and the options.
    pub fn urdf_options(&self, package_paths: &[PathBuf]) -> (Option<PathBuf>, UrdfOptions) {
        let mut search = package_paths.to_vec();
        for p in &self.info.package_paths {
            if holds_ros_packages(p) && !search.contains(p) {
                search.push(p.clone());
            } else if !search.contains(p) {
                log::warn!(
                    "{}: not searched for the robot's meshes: not a ROS package folder (no package.xml in it or its subfolders)",
                    p.display()
                );
            }
        }
        let mut opts = UrdfOptions {
            search_paths: search,
            skip_missing_meshes: true,
            ..UrdfOptions::default()
        };
        let from_scene = self.scene.as_ref().and_then(|s| {
            let r = s.robot.as_ref()?;
            opts.visual_fallback = r.visual_fallback;
            opts.mesh_roots = s.mesh_roots();
            let urdf = s.base_dir.clone().unwrap_or_default().join(&r.urdf);
            urdf.parent().map(Path::to_path_buf)
        });
        let dir = from_scene.or_else(|| package_paths.first().cloned());
        (dir, opts)
    }

    /// The scene's static obstacles as the markers `drape record` writes for them (for a bag
    /// without them); one that cannot be built is left out with a warning.
    pub fn static_obstacles(&self, bag: &Path) -> Vec<(u64, MarkerHead)> {
        let Some(scene) = &self.scene else {
            return Vec::new();
        };
        let base = scene.base_dir.clone().unwrap_or_default();
        let roots = scene.mesh_roots();
        let mut built = Vec::new();
        for spec in &scene.obstacles {
            if spec.motion != crate::collide::MotionSpec::Static {
                continue;
            }
            let load = |path: &str| {
                crate::mesh::load_mesh_within(&base.join(path), Vec3::ONE, &roots)
                    .map(|m| (m.vertices, m.indices))
            };
            match spec.build(load) {
                Ok(o) => built.push(o),
                Err(e) => log::warn!(
                    "{}: obstacle `{}` of its scene is not drawn: {}",
                    bag.display(),
                    spec.name,
                    crate::input::error_line(&e)
                ),
            }
        }
        let markers = crate::ros::obstacles::scene_obstacle_markers(
            &built,
            crate::ros::Distro::Jazzy,
            Time::default(),
            "world",
        );
        markers.iter().map(|m| (0, head(m))).collect()
    }
}

/// Most entries of a folder looked through for packages.
const MAX_ENTRIES: usize = 4096;

/// True for a ROS package (an absolute folder holding a `package.xml`) or a folder of them.
fn holds_ros_packages(p: &Path) -> bool {
    let is_package = |d: &Path| d.join("package.xml").is_file();
    if !p.is_absolute() || !p.is_dir() {
        return false;
    }
    is_package(p)
        || std::fs::read_dir(p).is_ok_and(|entries| {
            entries
                .take(MAX_ENTRIES)
                .flatten()
                .any(|e| is_package(&e.path()))
        })
}

/// The part of a marker the renderer reads.
fn head(m: &Marker) -> MarkerHead {
    MarkerHead {
        header: m.header.clone(),
        ns: m.ns.clone(),
        id: m.id,
        r#type: m.r#type,
        action: m.action,
        pose: m.pose,
        scale: m.scale,
        color: m.color,
        lifetime: m.lifetime,
        frame_locked: m.frame_locked,
        points: m.points.clone(),
    }
}
