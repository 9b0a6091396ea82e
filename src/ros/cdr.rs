//! CDR payloads as rosbag2 and DDS carry them: a 4-byte encapsulation header, then the body.
//!
//! Alignment in CDR is relative to the start of the body (after the header), which is
//! why the body is serialised on its own and prefixed.

use byteorder::{BigEndian, LittleEndian};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Encapsulation header for little-endian plain CDR (`CDR_LE`).
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Why a CDR payload could not be decoded.
#[derive(Debug, thiserror::Error)]
pub enum CdrError {
    #[error("payload of {0} bytes is shorter than the 4-byte CDR header")]
    TooShort(usize),
    #[error("unsupported CDR encapsulation {0:#04x}{1:02x} (expected plain CDR)")]
    Encapsulation(u8, u8),
    #[error("CDR body: {0}")]
    Body(#[from] cdr_encoding::Error),
}

/// Writes header + little-endian body of `msg` into `out` (cleared first), reusing
/// its allocation. The serializer counts alignment from its own first byte, i.e. from
/// the start of the body.
pub fn encode_into<M: Serialize>(msg: &M, out: &mut Vec<u8>) -> Result<(), cdr_encoding::Error> {
    out.clear();
    out.extend_from_slice(&CDR_LE_HEADER);
    cdr_encoding::to_writer::<M, LittleEndian, _>(&mut *out, msg)
}

/// Header + little-endian body of `msg`.
pub fn encode<M: Serialize>(msg: &M) -> Result<Vec<u8>, cdr_encoding::Error> {
    let mut out = Vec::new();
    encode_into(msg, &mut out)?;
    Ok(out)
}

/// Decodes a payload with either byte order (the header says which).
pub fn decode<M: DeserializeOwned>(payload: &[u8]) -> Result<M, CdrError> {
    if payload.len() < 4 {
        return Err(CdrError::TooShort(payload.len()));
    }
    let body = &payload[4..];
    let (msg, _) = match (payload[0], payload[1]) {
        (0x00, 0x01) => cdr_encoding::from_bytes::<M, LittleEndian>(body)?,
        (0x00, 0x00) => cdr_encoding::from_bytes::<M, BigEndian>(body)?,
        (a, b) => return Err(CdrError::Encapsulation(a, b)),
    };
    Ok(msg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::msg::{Header, JointState, PointCloud2, Time};
    use proptest::prelude::*;

    #[test]
    fn rejects_short_and_foreign_payloads() {
        assert!(matches!(
            decode::<Time>(&[0, 1]),
            Err(CdrError::TooShort(2))
        ));
        // 0x0003 is PL_CDR_LE (parameter list), which ROS 2 does not use for messages.
        assert!(matches!(
            decode::<Time>(&[0, 3, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]),
            Err(CdrError::Encapsulation(0, 3))
        ));
        assert!(matches!(
            decode::<Time>(&[0, 1, 0, 0, 1, 0]),
            Err(CdrError::Body(_))
        ));
    }

    #[test]
    fn decodes_big_endian_payloads() {
        let be = [0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 2];
        assert_eq!(decode::<Time>(&be).unwrap(), Time { sec: 1, nanosec: 2 });
    }

    proptest! {
        #[test]
        fn joint_state_round_trips(
            frame in "[a-z_/]{0,12}",
            names in proptest::collection::vec("[a-z0-9_]{0,9}", 0..5),
            pos in proptest::collection::vec(-1e3f64..1e3, 0..5),
            vel in proptest::collection::vec(-1e3f64..1e3, 0..3),
            sec in any::<i32>(), nanosec in 0u32..1_000_000_000,
        ) {
            let js = JointState {
                header: Header::new(Time { sec, nanosec }, &frame),
                name: names, position: pos, velocity: vel, effort: vec![],
            };
            let bytes = encode(&js).unwrap();
            prop_assert_eq!(decode::<JointState>(&bytes).unwrap(), js);
        }

        #[test]
        fn cloud_bytes_round_trip(data in proptest::collection::vec(any::<u8>(), 0..200), dense: bool) {
            let cloud = PointCloud2 { width: data.len() as u32, data, is_dense: dense, ..PointCloud2::default() };
            let bytes = encode(&cloud).unwrap();
            prop_assert_eq!(decode::<PointCloud2>(&bytes).unwrap(), cloud);
        }
    }
}
