//! The one error type of the crate: why a blob or a calibration was refused.
use core::fmt;

/// Why a coefficient blob (or a calibration built on the host) cannot be used.
#[non_exhaustive]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The blob ends before the length its header declares (or before a header and
    /// checksum fit): cut short in transfer or flashing, not corrupted.
    Truncated,
    /// The CRC-32 over the blob does not match the stored one: corrupted (any flipped
    /// bit, the version's included, reads as this).
    CrcMismatch,
    /// The blob does not start with the magic bytes `ATCB`.
    BadMagic,
    /// The blob has a valid checksum but a format version this firmware does not read
    /// (an older blob: re-export it with the current host-fit).
    UnsupportedVersion(u16),
    /// The header and the layout disagree, reserved bytes are not zero, the output-unit
    /// code is unknown, or the serial is not printable ASCII (a valid checksum over content no encoder of this version
    /// writes; on encoding: a serial that is not printable ASCII).
    Malformed,
    /// Bytes follow the length the header declares.
    TrailingBytes,
    /// A table size is outside its allowed range, or two tables disagree in size.
    TableSize,
    /// Piecewise-linear breakpoints are not strictly increasing.
    BreakpointsNotIncreasing,
    /// A value that must be finite is NaN or infinite.
    NonFinite,
    /// The valid temperature range is empty, the update step is negative, or a physics
    /// term is out of its range (a negative time constant or threshold, an initial
    /// direction other than -1, 0, +1).
    BadRange,
    /// The matrix K is singular (not invertible) at the reference temperature.
    Singular,
    /// The output buffer is too small for the encoded blob.
    BufferTooSmall,
    /// The calibration has in-flight physics terms but the firmware was built without
    /// the `physics` feature (compensating without them would be silently wrong).
    PhysicsNotBuiltIn,
    /// The sample period given to the compensator is not a positive, finite number of
    /// seconds.
    BadSamplePeriod,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Truncated => f.write_str("blob truncated: shorter than its declared length"),
            Error::CrcMismatch => f.write_str("CRC-32 mismatch: blob corrupted"),
            Error::BadMagic => f.write_str("not a coefficient blob (bad magic)"),
            Error::UnsupportedVersion(v) => write!(
                f,
                "unsupported blob format version {v} (this firmware reads version {})",
                crate::format::FORMAT_VERSION
            ),
            Error::Malformed => f.write_str("blob header and layout disagree"),
            Error::TrailingBytes => f.write_str("unexpected bytes after the blob's declared end"),
            Error::TableSize => f.write_str("temperature table size out of range or inconsistent"),
            Error::BreakpointsNotIncreasing => {
                f.write_str("breakpoints are not strictly increasing")
            }
            Error::NonFinite => f.write_str("a table value is NaN or infinite"),
            Error::BadRange => {
                f.write_str("invalid temperature range, update step or physics term")
            }
            Error::Singular => f.write_str("matrix K is singular at the reference temperature"),
            Error::BufferTooSmall => f.write_str("output buffer too small"),
            Error::PhysicsNotBuiltIn => {
                f.write_str("the blob has physics terms; firmware built without `physics`")
            }
            Error::BadSamplePeriod => {
                f.write_str("the sample period is not a positive, finite number of seconds")
            }
        }
    }
}

impl core::error::Error for Error {}
