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
