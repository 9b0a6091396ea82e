//! Record lengths inside an MCAP file's chunks, checked before the mcap reader sees them.
//!
//! The reader allocates a chunk record's declared length before it has decompressed it, so a
//! few bytes declaring a 2^40-byte record would make it allocate a terabyte. Each chunk is
//! walked here first, decompressing as a stream into nothing: every record's length must fit in
//! what remains of the chunk's declared uncompressed size, the chunk must hold those bytes, and
//! no record may be larger than [`MAX_RECORD`]. Memory stays bounded by the decoder's window.

use super::BagError;
use std::io::Read;
use std::path::Path;

/// Largest record a chunk may end inside of: the reader allocates a record whole before it
/// finds the chunk cut, so a cut record larger than this is refused here instead.
pub const MAX_CUT_RECORD: u64 = 16 << 20;

/// Largest record accepted inside a chunk (a message of a quarter gigabyte: far above a cloth
/// mesh or a point cloud, and what the reader may then hold at once).
pub const MAX_RECORD: u64 = 256 << 20;

/// Checks every chunk of `bytes` (an MCAP file), also a last chunk cut short. Damage that is
/// not a length (a decoding error, a chunk that ends early) is left to the message reader,
/// which keeps the messages before it and reports the file as truncated.
pub(super) fn check_chunks(path: &Path, bytes: &[u8]) -> Result<(), BagError> {
    const CHUNK: u8 = 0x06;
    let u64_at = |b: &[u8], at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
    };
    let mut pos = 8usize; // after the magic
    let mut chunk = 0usize;
    while let (Some(&opcode), Some(len)) = (bytes.get(pos), u64_at(bytes, pos + 1)) {
        let body_start = pos + 9;
        let body_end = usize::try_from(len)
            .ok()
            .and_then(|l| body_start.checked_add(l))
            .unwrap_or(usize::MAX);
        let body = &bytes[body_start.min(bytes.len())..body_end.min(bytes.len())];
        if opcode == CHUNK {
            check_chunk(body, chunk, path)?;
            chunk += 1;
        }
        pos = body_end;
    }
    Ok(())
}

/// One chunk record's body (possibly cut short): its header, then its records.
fn check_chunk(body: &[u8], chunk: usize, path: &Path) -> Result<(), BagError> {
    let bad = |why: String| BagError::ChunkRecord {
        path: path.to_path_buf(),
        chunk,
        why,
    };
    let field = |at: usize, n: usize| body.get(at..at + n);
    let Some(size) = field(16, 8)
        .and_then(|b| b.try_into().ok())
        .map(u64::from_le_bytes)
    else {
        return Ok(());
    };
    let Some(name_len) = field(28, 4)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes)
    else {
        return Ok(());
    };
    let name_end = 32 + name_len as usize;
    let Some(name) = body.get(32..name_end) else {
        return Ok(());
    };
    let Some(records_len) = field(name_end, 8)
        .and_then(|b| b.try_into().ok())
        .map(u64::from_le_bytes)
    else {
        return Ok(());
    };
    let start = name_end + 8;
    let end = usize::try_from(records_len)
        .ok()
        .and_then(|l| start.checked_add(l))
        .unwrap_or(usize::MAX)
        .min(body.len());
    let data = body.get(start..end).unwrap_or_default();
    match name {
        b"" => walk(&mut &data[..], size, bad),
        b"zstd" => match zstd::stream::read::Decoder::with_buffer(data) {
            Ok(mut dec) => walk(&mut dec, size, bad),
            Err(_) => Ok(()),
        },
        // The reader refuses compressions it does not know with an error of its own.
        _ => Ok(()),
    }
}

/// Walks the records of one chunk's content (`size` bytes declared), stopping quietly where
/// the content ends or stops decoding (inside a record: only if that record is small).
fn walk(
    content: &mut impl Read,
    size: u64,
    bad: impl Fn(String) -> BagError,
) -> Result<(), BagError> {
    let mut remaining = size;
    let mut index = 0usize;
    while remaining >= 9 {
        let mut head = [0u8; 9];
        if content.read_exact(&mut head).is_err() {
            return Ok(());
        }
        remaining -= 9;
        let opcode = head[0];
        let len = u64::from_le_bytes([
            head[1], head[2], head[3], head[4], head[5], head[6], head[7], head[8],
        ]);
        if len > remaining {
            return Err(bad(format!(
                "record {index} (opcode {opcode:#04x}) declares {len} bytes, but only {remaining} of the chunk's declared size remain"
            )));
        }
        if len > MAX_RECORD {
            return Err(bad(format!(
                "record {index} (opcode {opcode:#04x}) declares {len} bytes, more than the {MAX_RECORD} allowed"
            )));
        }
        let present: u64 =
            std::io::copy(&mut content.take(len), &mut std::io::sink()).unwrap_or_default();
        if present < len {
            if len > MAX_CUT_RECORD {
                return Err(bad(format!(
                    "record {index} (opcode {opcode:#04x}) declares {len} bytes, but the chunk ends after {present} of them"
                )));
            }
            return Ok(());
        }
        remaining -= len;
        index += 1;
    }
    Ok(())
}
