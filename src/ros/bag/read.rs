//! Reading typed messages of one topic back from a rosbag2 MCAP file.

use super::BagError;
use crate::ros::cdr;
use crate::ros::msg::{JointState, RosMessage};
use serde::de::DeserializeOwned;
use std::path::Path;

const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// The messages of one topic, in file order, with what had to be skipped.
#[derive(Debug)]
pub struct TopicRead<M> {
    /// `(log_time_ns, message)`.
    pub messages: Vec<(u64, M)>,
    /// Messages on the topic whose CDR payload did not decode.
    pub skipped: usize,
    /// Set when the file ends early or is corrupt after some records (e.g. a recorder
    /// killed before finishing); the messages before that point are kept.
    pub truncated: Option<mcap::McapError>,
}

/// A bag read into memory through the input rules (regular file under the bag cap), its magic
/// and its chunks' record lengths checked, ready to stream topics from ([`BagBytes::topic`]).
pub struct BagBytes {
    path: std::path::PathBuf,
    bytes: Vec<u8>,
}

impl BagBytes {
    pub fn read(path: &Path) -> Result<BagBytes, BagError> {
        let bytes = crate::input::read_bytes(path, crate::input::InputKind::JointsBag).map_err(
            |e| match e {
                crate::input::InputError::Open { path, source, .. } => {
                    BagError::Open { path, source }
                }
                other => BagError::Input(other),
            },
        )?;
        if !bytes.starts_with(MCAP_MAGIC) {
            return Err(BagError::NotMcap {
                path: path.to_path_buf(),
            });
        }
        super::lengths::check_chunks(path, &bytes)?;
        Ok(BagBytes {
            path: path.to_path_buf(),
            bytes,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub(super) fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The messages on `topic`, decoded one at a time as the iterator is advanced (nothing is
    /// collected), in file order.
    pub fn topic<M: RosMessage + DeserializeOwned>(
        &self,
        topic: &str,
    ) -> Result<TopicIter<'_, M>, BagError> {
        let options = mcap::read::Options::IgnoreEndMagic.into();
        let stream =
            mcap::MessageStream::new_with_options(&self.bytes, options).map_err(|source| {
                BagError::Mcap {
                    path: self.path.clone(),
                    source,
                }
            })?;
        Ok(TopicIter {
            bag: self,
            stream,
            topic: topic.to_string(),
            topics: Vec::new(),
            skipped: 0,
            truncated: None,
            done: false,
            _message: std::marker::PhantomData,
        })
    }
}

/// The messages of one topic of a [`BagBytes`], decoded as they are reached. A message whose
/// CDR does not decode is skipped and counted; damage after the first record ends the
/// iteration and is kept in [`TopicIter::truncated`]; damage before it, or the topic carrying
/// another type, is the iterator's one `Err`.
pub struct TopicIter<'a, M> {
    bag: &'a BagBytes,
    stream: mcap::MessageStream<'a>,
    topic: String,
    /// topic, type, encoding of every channel with a message so far.
    topics: Vec<(String, String, String)>,
    pub skipped: usize,
    pub truncated: Option<mcap::McapError>,
    done: bool,
    _message: std::marker::PhantomData<M>,
}

impl<M: RosMessage + DeserializeOwned> Iterator for TopicIter<'_, M> {
    type Item = Result<(u64, M), BagError>;

    fn next(&mut self) -> Option<Self::Item> {
        let path = &self.bag.path;
        while !self.done {
            let message = match self.stream.next()? {
                Ok(m) => m,
                Err(e) if self.topics.is_empty() => {
                    self.done = true;
                    return Some(Err(BagError::Truncated {
                        path: path.clone(),
                        bytes: self.bag.bytes.len(),
                        source: Some(e),
                    }));
                }
                Err(e) => {
                    self.truncated = Some(e);
                    self.done = true;
                    break;
                }
            };
            let channel = &message.channel;
            if !self.topics.iter().any(|t| t.0 == channel.topic) {
                let type_name = channel
                    .schema
                    .as_ref()
                    .map_or_else(String::new, |s| s.name.clone());
                self.topics.push((
                    channel.topic.clone(),
                    type_name,
                    channel.message_encoding.clone(),
                ));
            }
            if channel.topic != self.topic {
                continue;
            }
            let type_ok = channel
                .schema
                .as_ref()
                .is_some_and(|s| s.name == M::TYPE_NAME);
            if !type_ok || channel.message_encoding != "cdr" {
                self.done = true;
                return Some(Err(type_error::<M>(path, &self.topic, &self.topics)));
            }
            match cdr::decode::<M>(&message.data) {
                Ok(m) => return Some(Ok((message.log_time, m))),
                Err(e) => {
                    log::debug!(
                        "{}: skipping message {} on {}: {e}",
                        path.display(),
                        message.sequence,
                        self.topic
                    );
                    self.skipped += 1;
                }
            }
        }
        None
    }
}

/// Reads every `M` on `topic`. Fails on a missing or non-MCAP file, a missing topic or
/// one of another type; skips (and counts) individual messages that do not decode.
pub fn read_topic<M: RosMessage + DeserializeOwned>(
    path: impl AsRef<Path>,
    topic: &str,
) -> Result<TopicRead<M>, BagError> {
    let path = path.as_ref();
    let bag = BagBytes::read(path)?;
    let mut it = bag.topic::<M>(topic)?;
    let mut messages = Vec::new();
    for m in it.by_ref() {
        messages.push(m?);
    }
    let read = TopicRead {
        messages,
        skipped: it.skipped,
        truncated: it.truncated.take(),
    };
    let bytes = &bag.bytes;
    // A file cut at a record boundary reads without error but lacks its closing magic.
    if read.messages.is_empty() && read.skipped == 0 && !bytes.ends_with(MCAP_MAGIC) {
        return Err(BagError::Truncated {
            path: path.to_path_buf(),
            bytes: bytes.len(),
            source: read.truncated,
        });
    }
    let topics = &it.topics;
    if read.messages.is_empty() && read.skipped == 0 && !topics.iter().any(|t| t.0 == topic) {
        let mut available: Vec<&str> = topics.iter().map(|t| t.0.as_str()).collect();
        available.sort_unstable();
        return Err(BagError::NoSuchTopic {
            path: path.to_path_buf(),
            topic: topic.to_string(),
            available: if available.is_empty() {
                "none with messages".to_string()
            } else {
                available.join(", ")
            },
        });
    }
    Ok(read)
}

fn type_error<M: RosMessage>(
    path: &Path,
    topic: &str,
    topics: &[(String, String, String)],
) -> BagError {
    let (found, encoding) = topics
        .iter()
        .find(|t| t.0 == topic)
        .map(|t| (t.1.clone(), t.2.clone()))
        .unwrap_or_default();
    BagError::TopicType {
        path: path.to_path_buf(),
        topic: topic.to_string(),
        found: if found.is_empty() {
            "(no schema)".to_string()
        } else {
            found
        },
        encoding,
        expected: M::TYPE_NAME.to_string(),
    }
}

/// The `/joint_states` messages of a rosbag2 MCAP file as `(log_time_ns, JointState)`.
/// Undecodable messages are skipped and a truncated file is read up to the damage;
/// both are reported with `log::warn!`.
pub fn read_joint_states(path: impl AsRef<Path>) -> Result<Vec<(u64, JointState)>, BagError> {
    let path = path.as_ref();
    let read = read_topic::<JointState>(path, "/joint_states")?;
    if read.skipped > 0 {
        log::warn!(
            "{}: skipped {} malformed /joint_states messages",
            path.display(),
            read.skipped
        );
    }
    if let Some(source) = read.truncated {
        if read.messages.is_empty() {
            return Err(BagError::Truncated {
                path: path.to_path_buf(),
                bytes: std::fs::metadata(path).map_or(0, |m| m.len() as usize),
                source: Some(source),
            });
        }
        log::warn!(
            "{}: file is truncated or corrupt ({source}); read {} /joint_states messages before it",
            path.display(),
            read.messages.len()
        );
    }
    Ok(read.messages)
}
