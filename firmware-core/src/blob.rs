//! The coefficient blob flashed beside the firmware: header, postcard content, CRC-32.
//!
//! Layout (all little-endian):
//!
//! | bytes | content |
//! |---|---|
//! | 0..4 | magic `ATCB` |
//! | 4..6 | format version (u16), currently [`FORMAT_VERSION`] (2: optional physics terms) |
//! | 6..n-4 | [`Blob`] encoded with postcard (serial, calibration) |
//! | n-4..n | CRC-32 (IEEE) of bytes 0..n-4 |
//!
//! Decoding checks, in order: length, magic, version, CRC, content, no trailing bytes,
//! table sizes, finite values, strictly increasing breakpoints, a valid range, and an
//! invertible K at T0. Encoding needs no allocator (it writes into a caller's buffer).
#![deny(clippy::arithmetic_side_effects)]
use crate::crc::crc32;
use crate::error::Error;
use crate::model::{invert, Coeffs};
use crate::temperature::{Calibration, TempModel};
use serde::{Deserialize, Serialize};

/// The four magic bytes a blob starts with.
pub const MAGIC: [u8; 4] = *b"ATCB";
/// The format version this firmware reads and writes.
pub const FORMAT_VERSION: u16 = 2;
/// Bytes before the content.
pub const HEADER_LEN: usize = 6;
/// Bytes of the trailing checksum.
pub const CRC_LEN: usize = 4;
/// The largest blob this version can produce (16 breakpoints, 32-byte serial).
pub const MAX_BLOB_LEN: usize = 1024;
/// Longest unit serial, bytes of UTF-8.
pub const MAX_SERIAL_LEN: usize = 32;

/// The decoded blob: which unit, and its calibration in f32.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Blob {
    /// The unit's serial number.
    pub serial: heapless::String<MAX_SERIAL_LEN>,
    /// Temperature model and its use.
    pub calibration: Calibration<f32>,
}

impl Blob {
    /// All checks a decoded blob passes, also applied before encoding.
    pub fn validate(&self) -> Result<(), Error> {
        self.calibration.validate()?;
        let c0 = Coeffs::from_array(&self.calibration.at_t0());
        invert(&c0.k).map(|_| ()).ok_or(Error::Singular)
    }

    /// Write the blob into `buf`, returning the number of bytes written.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        self.validate()?;
        let (header, rest) = buf
            .split_at_mut_checked(HEADER_LEN)
            .ok_or(Error::BufferTooSmall)?;
        header.copy_from_slice(&header_bytes());
        let content_len = postcard::to_slice(self, rest)
            .map_err(|_| Error::BufferTooSmall)?
            .len();
        let body_len = HEADER_LEN
            .checked_add(content_len)
            .ok_or(Error::BufferTooSmall)?;
        let total = body_len.checked_add(CRC_LEN).ok_or(Error::BufferTooSmall)?;
        let crc = crc32(buf.get(..body_len).ok_or(Error::BufferTooSmall)?);
        buf.get_mut(body_len..total)
            .ok_or(Error::BufferTooSmall)?
            .copy_from_slice(&crc.to_le_bytes());
        Ok(total)
    }

    /// Decode and check a blob.
    pub fn decode(bytes: &[u8]) -> Result<Blob, Error> {
        let min = HEADER_LEN + CRC_LEN;
        if bytes.len() <= min {
            return Err(Error::TooShort);
        }
        let (magic, rest) = bytes.split_at_checked(4).ok_or(Error::TooShort)?;
        if magic != MAGIC {
            return Err(Error::BadMagic);
        }
        let (ver, _) = rest.split_at_checked(2).ok_or(Error::TooShort)?;
        let version = u16::from_le_bytes([
            ver.first().copied().unwrap_or(0),
            ver.get(1).copied().unwrap_or(0),
        ]);
        if version != FORMAT_VERSION {
            return Err(Error::UnsupportedVersion(version));
        }
        let body_len = bytes.len().checked_sub(CRC_LEN).ok_or(Error::TooShort)?;
        let (body, stored) = bytes.split_at_checked(body_len).ok_or(Error::TooShort)?;
        let mut crc = [0u8; CRC_LEN];
        crc.copy_from_slice(stored);
        if crc32(body) != u32::from_le_bytes(crc) {
            return Err(Error::CrcMismatch);
        }
        let content = body.get(HEADER_LEN..).ok_or(Error::TooShort)?;
        let (blob, trailing): (Blob, &[u8]) =
            postcard::take_from_bytes(content).map_err(|_| Error::Malformed)?;
        if !trailing.is_empty() {
            return Err(Error::TrailingBytes);
        }
        blob.validate()?;
        Ok(blob)
    }
}

fn header_bytes() -> [u8; HEADER_LEN] {
    let [m0, m1, m2, m3] = MAGIC;
    let [v0, v1] = FORMAT_VERSION.to_le_bytes();
    [m0, m1, m2, m3, v0, v1]
}

/// The paper's Tables 1-2 (-40, +20, +70 C) as the paper's two-interval
/// piecewise-linear model: a known-good blob for examples and tests.
pub fn example_blob() -> Blob {
    #[rustfmt::skip]
    #[allow(clippy::excessive_precision)] // the paper's digits, as printed
    let rows: [[f32; 12]; 3] = [
        [-0.55074263, -0.54790681, -0.54832201, -0.00038930, 0.01602241, -0.01277214,
         -0.00074432, -0.01433019, -0.00023161, 0.01181219, 0.00057544, 0.00041269],
        [-0.55060863, -0.54854890, -0.54859224, -0.00051742, 0.01639328, -0.01322881,
         -0.00066841, -0.01466957, -0.00035441, 0.00449084, -0.00442299, -0.00347099],
        [-0.55140269, -0.54933059, -0.54979681, -0.00042829, 0.01652937, -0.01364519,
         -0.00068396, -0.01478830, -0.00027167, 0.00359778, -0.00643609, -0.00223732],
    ];
    let mut serial = heapless::String::new();
    // "PAPER-UNIT" is 10 bytes: always fits the 32-byte serial.
    let _ = serial.push_str("PAPER-UNIT");
    Blob {
        serial,
        calibration: Calibration {
            t0_c: 20.0,
            t_min_c: -40.0,
            t_max_c: 70.0,
            clamp: false,
            update_step_c: 0.1,
            model: TempModel::Pwl {
                breakpoints: [-40.0f32, 20.0, 70.0].into_iter().collect(),
                values: rows.into_iter().collect(),
            },
            physics: None,
        },
    }
}

/// [`example_blob`] encoded.
pub fn example_blob_bytes() -> heapless::Vec<u8, MAX_BLOB_LEN> {
    let mut buf = [0u8; MAX_BLOB_LEN];
    let n = example_blob().encode(&mut buf).unwrap_or(0);
    buf.get(..n).unwrap_or(&[]).iter().copied().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let b = example_blob();
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).unwrap();
        assert_eq!(Blob::decode(&buf[..n]).unwrap(), b);
    }

    #[test]
    fn encode_refuses_small_buffer_and_invalid_content() {
        let b = example_blob();
        let mut small = [0u8; 40];
        assert_eq!(b.encode(&mut small), Err(Error::BufferTooSmall));
        let mut bad = b.clone();
        bad.calibration.t_min_c = 100.0;
        let mut buf = [0u8; MAX_BLOB_LEN];
        assert_eq!(bad.encode(&mut buf), Err(Error::BadRange));
    }
}
