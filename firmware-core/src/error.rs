//! The one error type of the crate: why a blob or a calibration was refused.
use core::fmt;

/// Why a coefficient blob (or a calibration built on the host) cannot be used.
#[non_exhaustive]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The blob is shorter than its header plus checksum.
    TooShort,
    /// The blob does not start with the magic bytes `ATCB`.
    BadMagic,
    /// The blob's format version is not one this firmware reads.
    UnsupportedVersion(u16),
    /// The CRC-32 over the blob does not match the stored one.
    CrcMismatch,
    /// The content does not decode as a blob of this format version.
    Malformed,
    /// Bytes are left over after the content and before the checksum.
    TrailingBytes,
    /// A table size is outside its allowed range, or two tables disagree in size.
    TableSize,
    /// Piecewise-linear breakpoints are not strictly increasing.
    BreakpointsNotIncreasing,
    /// A value that must be finite is NaN or infinite.
    NonFinite,
    /// The valid temperature range is empty or the update step is negative.
    BadRange,
    /// The matrix K is singular (not invertible) at the reference temperature.
    Singular,
    /// The output buffer is too small for the encoded blob.
    BufferTooSmall,
    /// The calibration has in-flight physics terms but the firmware was built without
    /// the `physics` feature (compensating without them would be silently wrong).
    PhysicsNotBuiltIn,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::TooShort => f.write_str("blob too short for header and checksum"),
            Error::BadMagic => f.write_str("not a coefficient blob (bad magic)"),
            Error::UnsupportedVersion(v) => write!(f, "unsupported blob format version {v}"),
            Error::CrcMismatch => f.write_str("CRC-32 mismatch: blob corrupted"),
            Error::Malformed => f.write_str("blob content does not decode"),
            Error::TrailingBytes => f.write_str("unexpected bytes after the blob content"),
            Error::TableSize => f.write_str("temperature table size out of range or inconsistent"),
            Error::BreakpointsNotIncreasing => {
                f.write_str("breakpoints are not strictly increasing")
            }
            Error::NonFinite => f.write_str("a table value is NaN or infinite"),
            Error::BadRange => f.write_str("invalid temperature range or update step"),
            Error::Singular => f.write_str("matrix K is singular at the reference temperature"),
            Error::BufferTooSmall => f.write_str("output buffer too small"),
            Error::PhysicsNotBuiltIn => {
                f.write_str("the blob has physics terms; firmware built without `physics`")
            }
        }
    }
}

impl core::error::Error for Error {}
