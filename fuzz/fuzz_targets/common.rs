//! Shared by the targets (not a target itself).
use firmware_core::blob::{FORMAT_VERSION, MAGIC};
use firmware_core::crc::crc32;

/// `content` (header bytes 10.. onward: model, rows, flags, serial length, physics
/// words, output unit, then the body) behind a valid magic, version and length, and
/// followed by its CRC: a blob whose header fields and content, not its checksum,
/// decide whether it validates.
pub fn wrap(content: &[u8]) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    let n = (10 + content.len() + 4).min(usize::from(u16::MAX)) as u16;
    b.extend_from_slice(&n.to_le_bytes());
    b.extend_from_slice(&(!n).to_le_bytes());
    b.extend_from_slice(content);
    let c = crc32(&b);
    b.extend_from_slice(&c.to_le_bytes());
    b
}
