//! Bag errors; each names the file or topic at fault.

use std::path::PathBuf;

/// Everything that can go wrong writing or reading a bag.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("cannot create bag {path}: {source}")]
    Create {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot read bag {path}: {source}")]
    Open {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path} is not an MCAP file (bad magic bytes; rosbag2 .db3 files are not supported)")]
    NotMcap { path: PathBuf },
    #[error("MCAP error in {path}: {source}")]
    Mcap {
        path: PathBuf,
        source: mcap::McapError,
    },
    #[error("cannot write bag {path}: {source}")]
    Finish {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "topic {topic:?} in {path}: already added as {existing}, now requested as {requested}"
    )]
    TopicConflict {
        path: PathBuf,
        topic: String,
        existing: String,
        requested: String,
    },
    #[error("type {type_name} in {path}: a {distro} definition differs from the one already in the bag; one bag holds one layout per type")]
    MixedLayouts {
        path: PathBuf,
        type_name: String,
        distro: String,
    },
    #[error("type {type_name} has no schema definition (implement RosMessage::definition)")]
    NoDefinition { type_name: String },
    #[error("invalid offered_qos_profiles for topic {topic:?}: {reason}")]
    InvalidQos { topic: String, reason: String },
    #[error("topic id {0} was not issued by this bag writer")]
    UnknownTopicId(usize),
    #[error("topic {topic:?} records {expected}, got a {got}")]
    WrongMessageType {
        topic: String,
        expected: String,
        got: String,
    },
    #[error("topic {topic:?} was added with the {distro} layout but the message has another (Marker.distro)")]
    LayoutMismatch { topic: String, distro: String },
    #[error("cannot serialise a message for topic {topic:?}: {source}")]
    Encode {
        topic: String,
        source: cdr_encoding::Error,
    },
    #[error("{path} has no messages on topic {topic:?} (topics with messages: {available})")]
    NoSuchTopic {
        path: PathBuf,
        topic: String,
        available: String,
    },
    #[error("topic {topic:?} in {path} has type {found} (encoding {encoding}), expected {expected} (cdr)")]
    TopicType {
        path: PathBuf,
        topic: String,
        found: String,
        encoding: String,
        expected: String,
    },
}
