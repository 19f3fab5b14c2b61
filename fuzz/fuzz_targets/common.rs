//! Shared by the targets (not a target itself).
use firmware_core::blob::{FORMAT_VERSION, MAGIC};
use firmware_core::crc::crc32;

/// `content` behind a valid header and followed by its CRC: a blob whose content checks,
/// not its checksum, decide whether it decodes.
pub fn wrap(content: &[u8]) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    b.extend_from_slice(content);
    let c = crc32(&b);
    b.extend_from_slice(&c.to_le_bytes());
    b
}
