//! Shared by the targets (not a target itself).
use firmware_core::blob::{FORMAT_VERSION, MAGIC, OLDEST_FORMAT_VERSION};
use firmware_core::crc::crc32;

/// `content` (header bytes 10.. onward: model, rows, flags, serial length, physics
/// words, output unit, then the body) behind a valid magic, version and length, and
/// followed by its CRC: a blob whose header fields and content, not its checksum,
/// decide whether it validates. The version is the one that goes with the flags'
/// term-table bit (5 with a table of discovered terms, else 4), so the checks behind it
/// are reached either way.
pub fn wrap(content: &[u8]) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    let terms = content.get(2).is_some_and(|f| f & 2 != 0);
    let version = if terms { FORMAT_VERSION } else { OLDEST_FORMAT_VERSION };
    b.extend_from_slice(&version.to_le_bytes());
    let n = (10 + content.len() + 4).min(usize::from(u16::MAX)) as u16;
    b.extend_from_slice(&n.to_le_bytes());
    b.extend_from_slice(&(!n).to_le_bytes());
    b.extend_from_slice(content);
    let c = crc32(&b);
    b.extend_from_slice(&c.to_le_bytes());
    b
}
