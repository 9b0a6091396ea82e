//! [`BagWriter`]: a rosbag2-compatible MCAP file (profile `ros2`, `ros2msg` schemas,
//! `cdr` messages, zstd-compressed chunks).

use super::BagError;
use crate::ros::cdr;
use crate::ros::msg::{Distro, RosMessage};
use crate::ros::qos::{self, Durability, Reliability};
use mcap::write::NoSeek;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Handle of a topic added to one [`BagWriter`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TopicId(usize);

struct Topic {
    name: String,
    type_name: &'static str,
    distro: Distro,
    channel_id: u16,
    sequence: u32,
}

/// Writes a rosbag2 MCAP file that `ros2 bag play`, `rosbags` and Foxglove open.
///
/// The file is written front to back without seeking (each chunk is compressed in memory,
/// then written whole), so the target may also be a stream (`/dev/null`, a FIFO).
///
/// Call [`finish`](Self::finish) to see I/O errors; dropping an unfinished writer
/// finishes the file too, logging (not returning) any error.
pub struct BagWriter {
    path: PathBuf,
    writer: Option<mcap::Writer<NoSeek<BufWriter<File>>>>,
    topics: Vec<Topic>,
    /// type name -> (schema id, definition text)
    schemas: HashMap<&'static str, (u16, String)>,
    scratch: Vec<u8>,
}

impl BagWriter {
    /// Creates (truncates) `path`, conventionally ending in `.mcap`.
    pub fn create(path: impl AsRef<Path>) -> Result<BagWriter, BagError> {
        let path = path.as_ref().to_path_buf();
        let file = File::create(&path).map_err(|source| BagError::Create {
            path: path.clone(),
            source,
        })?;
        let options = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("drape ", env!("CARGO_PKG_VERSION")))
            .compression(Some(mcap::Compression::Zstd))
            .disable_seeking(true);
        let mcap_err = |source| BagError::Mcap {
            path: path.clone(),
            source,
        };
        let mut writer = options
            .create(NoSeek::new(BufWriter::new(file)))
            .map_err(mcap_err)?;
        // An empty serialized_metadata makes Jazzy's reader parse the QoS profiles in
        // the integer (version 8) form that Humble also reads; see `qos`.
        let metadata = mcap::records::Metadata {
            name: "rosbag2".to_string(),
            metadata: BTreeMap::from([("serialized_metadata".to_string(), String::new())]),
        };
        writer.write_metadata(&metadata).map_err(mcap_err)?;
        Ok(BagWriter {
            path,
            writer: Some(writer),
            topics: Vec::new(),
            schemas: HashMap::new(),
            scratch: Vec::new(),
        })
    }

    /// Path of the file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Adds `topic` carrying `M` in `distro`'s layout. `qos` is the rosbag2
    /// `offered_qos_profiles` YAML (see [`qos::offered_qos_profiles`]); `None` means a
    /// reliable, volatile publisher. Adding the same topic again with the same type and
    /// layout returns the existing id.
    pub fn add_topic<M: RosMessage>(
        &mut self,
        topic: &str,
        distro: Distro,
        qos: Option<&str>,
    ) -> Result<TopicId, BagError> {
        let definition = M::definition(distro);
        if definition.is_empty() {
            return Err(BagError::NoDefinition {
                type_name: M::TYPE_NAME.to_string(),
            });
        }
        if let Some(i) = self.topics.iter().position(|t| t.name == topic) {
            let existing = &self.topics[i];
            let same_layout = existing.distro == distro
                || self.schemas.get(M::TYPE_NAME).map(|s| &s.1) == Some(&definition);
            if existing.type_name == M::TYPE_NAME && same_layout {
                return Ok(TopicId(i));
            }
            return Err(BagError::TopicConflict {
                path: self.path.clone(),
                topic: topic.to_string(),
                existing: format!("{} ({})", existing.type_name, existing.distro),
                requested: format!("{} ({distro})", M::TYPE_NAME),
            });
        }
        let qos_yaml = match qos {
            Some(yaml) => {
                qos::validate(yaml).map_err(|source| BagError::InvalidQos {
                    topic: topic.to_string(),
                    source,
                })?;
                yaml.to_string()
            }
            None => qos::offered_qos_profiles(Reliability::Reliable, Durability::Volatile),
        };
        let path = self.path.clone();
        let writer = self.writer.as_mut().expect("writer present until finish");
        let schema_id = match self.schemas.get(M::TYPE_NAME) {
            Some((id, text)) if *text == definition => *id,
            Some(_) => {
                return Err(BagError::MixedLayouts {
                    path,
                    type_name: M::TYPE_NAME.to_string(),
                    distro: distro.to_string(),
                })
            }
            None => {
                let id = writer
                    .add_schema(M::TYPE_NAME, "ros2msg", definition.as_bytes())
                    .map_err(|source| BagError::Mcap {
                        path: path.clone(),
                        source,
                    })?;
                self.schemas.insert(M::TYPE_NAME, (id, definition));
                id
            }
        };
        let metadata = BTreeMap::from([("offered_qos_profiles".to_string(), qos_yaml)]);
        let channel_id = writer
            .add_channel(schema_id, topic, "cdr", &metadata)
            .map_err(|source| BagError::Mcap { path, source })?;
        self.topics.push(Topic {
            name: topic.to_string(),
            type_name: M::TYPE_NAME,
            distro,
            channel_id,
            sequence: 0,
        });
        Ok(TopicId(self.topics.len() - 1))
    }

    /// Records `msg` on `topic` at `log_time_ns` (also used as publish time).
    pub fn write<M: RosMessage>(
        &mut self,
        topic: TopicId,
        log_time_ns: u64,
        msg: &M,
    ) -> Result<(), BagError> {
        let t = self
            .topics
            .get_mut(topic.0)
            .ok_or(BagError::UnknownTopicId(topic.0))?;
        if t.type_name != M::TYPE_NAME {
            return Err(BagError::WrongMessageType {
                topic: t.name.clone(),
                expected: t.type_name.to_string(),
                got: M::TYPE_NAME.to_string(),
            });
        }
        if !msg.fits_layout(t.distro) {
            return Err(BagError::LayoutMismatch {
                topic: t.name.clone(),
                distro: t.distro.to_string(),
            });
        }
        cdr::encode_into(msg, &mut self.scratch).map_err(|source| BagError::Encode {
            topic: t.name.clone(),
            source,
        })?;
        let header = mcap::records::MessageHeader {
            channel_id: t.channel_id,
            sequence: t.sequence,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        t.sequence = t.sequence.wrapping_add(1);
        let writer = self.writer.as_mut().expect("writer present until finish");
        writer
            .write_to_known_channel(&header, &self.scratch)
            .map_err(|source| BagError::Mcap {
                path: self.path.clone(),
                source,
            })
    }

    /// Writes a metadata record `name` (key/value strings), e.g. [`super::RunInfo`].
    pub fn write_metadata(
        &mut self,
        name: &str,
        metadata: BTreeMap<String, String>,
    ) -> Result<(), BagError> {
        let writer = self.writer.as_mut().expect("writer present until finish");
        let record = mcap::records::Metadata {
            name: name.to_string(),
            metadata,
        };
        writer
            .write_metadata(&record)
            .map_err(|source| BagError::Mcap {
                path: self.path.clone(),
                source,
            })
    }

    /// Closes the current chunk and pushes it to the OS, so a crash loses at most
    /// what was written after this call (the file then lacks its summary; readers
    /// that scan, like [`super::read_topic`], still recover the messages).
    pub fn flush(&mut self) -> Result<(), BagError> {
        let writer = self.writer.as_mut().expect("writer present until finish");
        writer.flush().map_err(|source| BagError::Mcap {
            path: self.path.clone(),
            source,
        })
    }

    /// Writes the summary and footer and syncs the file to disk.
    pub fn finish(mut self) -> Result<(), BagError> {
        self.finish_inner()
    }

    fn finish_inner(&mut self) -> Result<(), BagError> {
        let Some(mut writer) = self.writer.take() else {
            return Ok(());
        };
        let path = self.path.clone();
        writer.finish().map_err(|source| BagError::Mcap {
            path: path.clone(),
            source,
        })?;
        let file = writer
            .into_inner()
            .into_inner()
            .into_inner()
            .map_err(|e| BagError::Finish {
                path: path.clone(),
                source: e.into_error(),
            })?;
        // A stream (a device or FIFO) has nothing to sync.
        if !file.metadata().is_ok_and(|m| m.is_file()) {
            return Ok(());
        }
        file.sync_all()
            .map_err(|source| BagError::Finish { path, source })
    }
}

impl Drop for BagWriter {
    fn drop(&mut self) {
        if self.writer.is_some() {
            if let Err(e) = self.finish_inner() {
                log::error!("finishing bag on drop: {e}");
            }
        }
    }
}
