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
    /// code is unknown, the serial is not printable ASCII, or the version and the term
    /// table disagree (format 5 without a table, format 4 with one): a valid checksum over
    /// content no encoder of this version writes; on encoding, a serial that is not
    /// printable ASCII.
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
    /// term is out of its range (a negative lag or warm-up time constant, a play operator
    /// narrower than 0.01 C, an initial direction other than -1, 0, +1).
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
    /// The table of discovered terms holds more than
    /// [`crate::terms::MAX_TERMS`] entries.
    TooManyTerms,
    /// A discovered term's output axis is none of x, y, z.
    TermAxis,
    /// A discovered term's factors are no term of the vocabulary's MCU subset in
    /// canonical form: an unknown factor code, none or more than three factors, out of
    /// canonical order, `abs(a_i)` twice, two decays.
    TermFactors,
    /// A discovered term's decay time constant is not a positive, finite number of
    /// seconds, or a term without a decay gives one.
    TermTimeConstant,
    /// The same discovered term twice on one axis.
    DuplicateTerm,
    /// The calibration has discovered terms but the firmware was built without the
    /// `terms` feature (compensating without them would be silently wrong).
    TermsNotBuiltIn,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Truncated => f.write_str("blob truncated: shorter than its declared length"),
            Error::CrcMismatch => f.write_str("CRC-32 mismatch: blob corrupted"),
            Error::BadMagic => f.write_str("not a coefficient blob (bad magic)"),
            Error::UnsupportedVersion(v) => write!(
                f,
                "unsupported blob format version {v} (this firmware reads versions {} to {})",
                crate::format::OLDEST_FORMAT_VERSION,
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
            Error::TooManyTerms => write!(
                f,
                "more than {} discovered terms",
                crate::terms::MAX_TERMS
            ),
            Error::TermAxis => f.write_str("a discovered term's axis is none of x, y, z"),
            Error::TermFactors => {
                f.write_str("a discovered term's factors are no canonical term of the vocabulary")
            }
            Error::TermTimeConstant => f.write_str(
                "a discovered term's decay time constant is not a positive number of seconds, or given without a decay",
            ),
            Error::DuplicateTerm => f.write_str("a discovered term twice on one axis"),
            Error::TermsNotBuiltIn => {
                f.write_str("the blob has discovered terms; firmware built without `terms`")
            }
        }
    }
}

impl core::error::Error for Error {}
