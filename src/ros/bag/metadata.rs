//! What a bag says about the run that wrote it: the MCAP metadata record `drape`, written by
//! `drape record` and read by `drape render` to draw a bag as the run saw it (the robot's
//! meshes found where the run found them, the scene's obstacles, each cloth in its colour).
//!
//! Keys (all optional; a bag from another recorder has none of them):
//! - `scene`: the scene file, absolute;
//! - `scene_name`: the scene's `name`;
//! - `package_paths`: JSON list of the folders the run searched for `package://` meshes besides
//!   the scene's own (`--package-path`), absolute;
//! - `cloth_pieces`: JSON list of `[name, triangles]`, the cloths in the order their triangles
//!   follow each other in every `/drape/mesh` marker.

use super::{BagBytes, BagError, BagWriter};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Name of the metadata record.
pub const RECORD_NAME: &str = "drape";

/// Most bytes of the record's values read back (a scene path, a name and a list of names).
const MAX_VALUE_BYTES: usize = 1 << 20;

/// The run a bag was recorded from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunInfo {
    /// The scene file (absolute).
    pub scene: Option<PathBuf>,
    /// The scene's `name`.
    pub scene_name: Option<String>,
    /// Folders searched for `package://` meshes besides the scene's own (absolute).
    pub package_paths: Vec<PathBuf>,
    /// Each cloth's name and triangle count, in marker order.
    pub cloth_pieces: Vec<(String, usize)>,
}

impl RunInfo {
    fn to_map(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        if let Some(s) = &self.scene {
            m.insert("scene".into(), s.to_string_lossy().into_owned());
        }
        if let Some(n) = &self.scene_name {
            m.insert("scene_name".into(), n.clone());
        }
        if !self.package_paths.is_empty() {
            let list = serde_json::to_string(&self.package_paths).unwrap_or_default();
            m.insert("package_paths".into(), list);
        }
        if !self.cloth_pieces.is_empty() {
            let list = serde_json::to_string(&self.cloth_pieces).unwrap_or_default();
            m.insert("cloth_pieces".into(), list);
        }
        m
    }

    /// The record's keys; a value that is too long or malformed is left out (the bag is not
    /// trusted: it only helps drawing).
    fn from_map(m: &BTreeMap<String, String>) -> RunInfo {
        let get = |k: &str| {
            m.get(k)
                .filter(|v| !v.is_empty() && v.len() <= MAX_VALUE_BYTES)
        };
        RunInfo {
            scene: get("scene").map(PathBuf::from).filter(|p| p.is_absolute()),
            scene_name: get("scene_name").cloned(),
            package_paths: get("package_paths")
                .and_then(|v| serde_json::from_str::<Vec<PathBuf>>(v).ok())
                .unwrap_or_default()
                .into_iter()
                .filter(|p| p.is_absolute())
                .collect(),
            cloth_pieces: get("cloth_pieces")
                .and_then(|v| serde_json::from_str(v).ok())
                .unwrap_or_default(),
        }
    }
}

impl BagWriter {
    /// Writes `info` as the `drape` metadata record.
    pub fn write_run_info(&mut self, info: &RunInfo) -> Result<(), BagError> {
        self.write_metadata(RECORD_NAME, info.to_map())
    }
}

impl BagBytes {
    /// The `drape` metadata record, if the bag has one (a damaged file is read up to the
    /// damage).
    pub fn run_info(&self) -> Option<RunInfo> {
        let options = mcap::read::Options::IgnoreEndMagic.into();
        let reader = mcap::read::LinearReader::new_with_options(self.bytes(), options).ok()?;
        for record in reader {
            match record {
                Ok(mcap::records::Record::Metadata(m)) if m.name == RECORD_NAME => {
                    return Some(RunInfo::from_map(&m.metadata));
                }
                Ok(_) => {}
                Err(_) => break,
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::msg::RosString;
    use crate::ros::Distro;

    #[test]
    fn run_info_reads_back_and_a_bag_without_it_has_none() {
        let dir = tempfile::tempdir().expect("tempdir");
        let info = RunInfo {
            scene: Some(PathBuf::from("/scenes/cape.yaml")),
            scene_name: Some("cape".into()),
            package_paths: vec![PathBuf::from("/ws/src")],
            cloth_pieces: vec![("a".into(), 8), ("b\t\"x\"".into(), 2)],
        };
        for (name, with) in [("with.mcap", true), ("without.mcap", false)] {
            let path = dir.path().join(name);
            let mut w = BagWriter::create(&path).expect("bag");
            if with {
                w.write_run_info(&info).expect("metadata");
            }
            let t = w
                .add_topic::<RosString>("/x", Distro::Jazzy, None)
                .expect("topic");
            w.write(t, 1, &RosString { data: "x".into() })
                .expect("message");
            w.finish().expect("finish");
            let read = BagBytes::read(&path).expect("read").run_info();
            assert_eq!(read, with.then(|| info.clone()));
        }
    }

    #[test]
    fn a_relative_scene_path_is_not_taken() {
        let m = BTreeMap::from([("scene".to_string(), "rel/cape.yaml".to_string())]);
        assert_eq!(RunInfo::from_map(&m).scene, None);
    }
}
