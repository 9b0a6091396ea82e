//! Bag errors; each names the file or topic at fault.

use std::path::PathBuf;

/// Everything that can go wrong writing or reading a bag. The cause, if any, is the
/// `source()` (printed once by the command line), not repeated in the message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BagError {
    #[error("{path}: cannot create bag")]
    Create {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: cannot read bag")]
    Open {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Not a regular file, too large, unreadable (see `crate::input`).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    /// The file ends (or is damaged) before the first message of the topic asked for.
    #[error(
        "{path}: bag is truncated or damaged after {bytes} bytes, before any message was read"
    )]
    Truncated {
        path: PathBuf,
        bytes: usize,
        #[source]
        source: Option<mcap::McapError>,
    },
    /// A chunk whose records do not fit in it (checked before the reader allocates them).
    #[error("{path}: chunk {chunk} is damaged: {why}")]
    ChunkRecord {
        path: PathBuf,
        chunk: usize,
        why: String,
    },
    #[error("{path} is not an MCAP file (bad magic bytes; rosbag2 .db3 files are not supported)")]
    NotMcap { path: PathBuf },
    #[error("{path}: MCAP error")]
    Mcap {
        path: PathBuf,
        #[source]
        source: mcap::McapError,
    },
    #[error("{path}: cannot write bag")]
    Finish {
        path: PathBuf,
        #[source]
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
    #[error("invalid offered_qos_profiles for topic {topic:?}")]
    InvalidQos {
        topic: String,
        #[source]
        source: crate::ros::qos::QosError,
    },
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
    #[error("cannot serialise a message for topic {topic:?}")]
    Encode {
        topic: String,
        #[source]
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
