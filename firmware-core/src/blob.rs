//! The coefficient blob flashed beside the firmware, validated and read in place.
//!
//! Format version 5: a fixed little-endian layout of f32 words behind a 16-byte header,
//! CRC-32 last. Every time constant is in seconds; the blob holds no sample period (the
//! firmware is told its own when it makes the compensator). [`BlobView::new`] checks a blob where it lies (flash) and the
//! compensator reads the tables from those bytes: no copy of the tables on the stack or
//! in RAM. [`Blob`] is the owned form the host builds, encodes and decodes with the same
//! layout code.
//!
//! | bytes | content |
//! |---|---|
//! | 0..4 | magic `ATCB` |
//! | 4..6 | format version (u16): 5 with a table of discovered terms, else 4 ([`FORMAT_VERSION`], [`OLDEST_FORMAT_VERSION`]) |
//! | 6..8 | total length n, CRC included (u16) |
//! | 8..10 | `!n` (u16): a length that disagrees with its complement is corruption, not truncation |
//! | 10 | model: 1 polynomial, 2 piecewise-linear |
//! | 11 | rows: polynomial terms (order + 1, 2..=6) or breakpoints (2..=16) |
//! | 12 | flags: bit 0 clamp, bit 1 a table of discovered terms follows (format 5; other bits 0) |
//! | 13 | serial length s (0..=64) |
//! | 14 | physics section words (0, or [`PHYSICS_WORDS`]) |
//! | 15 | output unit ([`OutputUnit`] code 0..=7) |
//! | 16.. | serial (printable ASCII), zero-padded to a multiple of 4 bytes |
//! | | run id: 16 bytes, the host-fit run that made the blob (all zero: none) |
//! | | T0, t_min, t_max, update step (4 f32, C) |
//! | | breakpoints (f32 each; piecewise-linear only) |
//! | | rows x 12 coefficients (f32, [`crate::model::COEFF_NAMES`] order) |
//! | | physics section (f32 words, [`Physics::to_words`] order) |
//! | | discovered terms (format 5 only): a head word `[count 1..=8, 0, 0, 0]`, then `count` entries of [`TERM_BYTES`] |
//! | n-4..n | CRC-32 (IEEE) of bytes 0..n-4 |
//!
//! A term entry ([`crate::terms`]), 12 bytes: the output axis it enters (u8: 0 x, 1 y,
//! 2 z), its three factor codes (u8 each, [`crate::terms::Factor`]: canonical order,
//! 0 after the last factor), the decay's time constant TAU (f32, s; 0 when the term has
//! no `decay(power_on,TAU)`) and the coefficient (f32, output units per the term's
//! units: `U_axis += coefficient * term`).
//!
//! [`BlobView::new`] checks, in order: (1) the slice holds a header and a checksum and
//! the declared length (when it agrees with its complement) is the slice's length
//! ([`Error::Truncated`], [`Error::TrailingBytes`]); (2) the CRC over everything
//! ([`Error::CrcMismatch`]): any flipped bit, the version's included, reads as
//! corruption; (3) magic and version ([`Error::BadMagic`],
//! [`Error::UnsupportedVersion`]); (4) the header against the layout
//! ([`Error::TableSize`], [`Error::Malformed`], [`Error::TooManyTerms`]; built without
//! the `terms` feature, a blob with a term table is refused here,
//! [`Error::TermsNotBuiltIn`]); (5) the
//! content: finite values, range, increasing breakpoints, physics ranges, each term
//! ([`Error::TermAxis`], [`Error::TermFactors`], [`Error::TermTimeConstant`],
//! [`Error::NonFinite`]) and no term twice on an axis ([`Error::DuplicateTerm`]), K(T0)
//! invertible.
//!
//! Versions: format 5 is format 4 with the table of discovered terms. A blob without
//! terms is written as format 4, byte for byte what format 4 wrote, so firmware of
//! format 4 keeps reading every blob that does not need the table; this firmware reads
//! both (a format-5 blob without a table, or a format-4 one with the flag, is
//! [`Error::Malformed`]: each blob has one encoding). Version 3 has the same header (its
//! time constants are per-sample constants for one sample period, byte 15 is 0 and there
//! is no run id): it passes the CRC and is refused as `UnsupportedVersion(3)`. Versions 1
//! and 2 also end with the CRC-32 of everything before it, but have no length field
//! (bytes 6..10 are content, which matches its own complement with probability 2^-16).
//! So when the length pair disagrees, the CRC is taken over the whole slice: a version-2
//! blob passes it and is refused as `UnsupportedVersion(2)`, while a current blob with a
//! flipped length bit fails it (`CrcMismatch`).
#![deny(clippy::arithmetic_side_effects)]
use crate::crc::crc32;
use crate::error::Error;
use crate::model::{invert, Coeffs, N_COEFFS};
use crate::temperature::{
    eval_table, validate_source, Calibration, CoeffRow, ModelKind, Physics, Source, Table,
    TempModel, MAX_BREAKPOINTS, MAX_POLY_ORDER, PHYSICS_WORDS,
};
#[cfg(feature = "terms")]
use crate::terms::RawTerm;
use crate::terms::{validate_entries, Axis, Tau, Term, TermEntry, TermList, MAX_TERMS};

pub use crate::format::{FORMAT_VERSION, OLDEST_FORMAT_VERSION};

/// The four magic bytes a blob starts with.
pub const MAGIC: [u8; 4] = *b"ATCB";
/// Bytes of the header.
pub const HEADER_LEN: usize = 16;
/// Bytes of the trailing checksum.
pub const CRC_LEN: usize = 4;
/// The largest blob this version can produce (16 breakpoints, 64-byte serial, physics,
/// 8 discovered terms).
pub const MAX_BLOB_LEN: usize = 1128;
/// Bytes of one entry of the table of discovered terms.
pub const TERM_BYTES: usize = 12;
/// Bytes of the term table's head word (the count and three zero bytes).
pub const TERMS_HEAD_BYTES: usize = 4;
/// Bytes of the run id.
pub const RUN_ID_LEN: usize = 16;
/// Longest unit serial, bytes of printable ASCII (a recording's own unit names, such as
/// "CATS-tag (real recording, see README.md)", fit).
pub const MAX_SERIAL_LEN: usize = 64;

const MODEL_POLY: u8 = 1;
const MODEL_PWL: u8 = 2;
const FLAG_CLAMP: u8 = 1;
const FLAG_TERMS: u8 = 2;
const ROW_BYTES: usize = 4 * N_COEFFS;
const SCALAR_BYTES: usize = 16;
const PHYSICS_BYTES: usize = 4 * PHYSICS_WORDS;

/// The unit of the outputs the blob's K and U0 are in (the recording's `output_unit`):
/// byte 15 of the header.
#[repr(u8)]
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OutputUnit {
    /// Not stated.
    #[default]
    Unstated = 0,
    /// Volts.
    Volt = 1,
    /// Millivolts.
    MilliVolt = 2,
    /// Metres per second squared.
    MetrePerSecond2 = 3,
    /// Standard gravity, g.
    G = 4,
    /// Thousandths of g.
    MilliG = 5,
    /// Counts of a digital sensor.
    Counts = 6,
    /// A unit the recording format does not list (the recording names it).
    Other = 7,
}

impl OutputUnit {
    /// The unit of a code (byte 15); `None` for a code above 7.
    pub const fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            0 => OutputUnit::Unstated,
            1 => OutputUnit::Volt,
            2 => OutputUnit::MilliVolt,
            3 => OutputUnit::MetrePerSecond2,
            4 => OutputUnit::G,
            5 => OutputUnit::MilliG,
            6 => OutputUnit::Counts,
            7 => OutputUnit::Other,
            _ => return None,
        })
    }

    /// The code written in byte 15.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// As a recording's `output_unit` writes it (`unstated`, `other` for the two that
    /// are none of its values).
    pub const fn label(self) -> &'static str {
        match self {
            OutputUnit::Unstated => "unstated",
            OutputUnit::Volt => "V",
            OutputUnit::MilliVolt => "mV",
            OutputUnit::MetrePerSecond2 => "m/s2",
            OutputUnit::G => "g",
            OutputUnit::MilliG => "mg",
            OutputUnit::Counts => "counts",
            OutputUnit::Other => "other",
        }
    }

    /// The unit of a recording's `output_unit` value (recording-format.md: `V`, `mV`,
    /// `m/s2` or `m/s^2`, `g`, `mg`, `counts`); any other label is [`OutputUnit::Other`].
    pub fn from_label(label: &str) -> Self {
        match label {
            "V" => OutputUnit::Volt,
            "mV" => OutputUnit::MilliVolt,
            "m/s2" | "m/s^2" => OutputUnit::MetrePerSecond2,
            "g" => OutputUnit::G,
            "mg" => OutputUnit::MilliG,
            "counts" => OutputUnit::Counts,
            _ => OutputUnit::Other,
        }
    }
}

/// The id of the host-fit run that made a blob (16 bytes; all zero: none), so a blob
/// found on a unit leads back to the run's record.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunId(pub [u8; RUN_ID_LEN]);

impl RunId {
    /// No run id.
    pub const NONE: RunId = RunId([0; RUN_ID_LEN]);

    /// Whether this is no run id (all zero).
    pub fn is_none(&self) -> bool {
        self.0.iter().all(|b| *b == 0)
    }
}

impl core::fmt::Display for RunId {
    /// 32 lowercase hex digits.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for b in self.0 {
            write!(f, "{b:02x}")?;
        }
        Ok(())
    }
}

/// Where everything lies in a blob of a given shape: the one definition of the layout,
/// used by the encoder and by [`BlobView`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    run_id: usize,
    scalars: usize,
    breakpoints: usize,
    table: usize,
    physics: usize,
    /// The term table's head word (where the CRC lies when there is no table).
    terms: usize,
    crc: usize,
}

impl Layout {
    /// `serial`: bytes of serial; `rows`: table rows; `physics`: whether the section is
    /// there; `terms`: entries of the term table (0: no table). The sizes are bounded by
    /// the header's u8 fields and [`MAX_TERMS`], so nothing overflows.
    const fn new(
        kind: ModelKind,
        rows: usize,
        serial: usize,
        physics: bool,
        terms: usize,
    ) -> Layout {
        let padded = serial.saturating_add(3) & !3;
        let run_id = HEADER_LEN.saturating_add(padded);
        let scalars = run_id.saturating_add(RUN_ID_LEN);
        let breakpoints = scalars.saturating_add(SCALAR_BYTES);
        let bp_bytes = match kind {
            ModelKind::Poly => 0,
            ModelKind::Pwl => rows.saturating_mul(4),
        };
        let table = breakpoints.saturating_add(bp_bytes);
        let physics_at = table.saturating_add(rows.saturating_mul(ROW_BYTES));
        let terms_at = physics_at.saturating_add(if physics { PHYSICS_BYTES } else { 0 });
        let crc = if terms > 0 {
            terms_at
                .saturating_add(TERMS_HEAD_BYTES)
                .saturating_add(terms.saturating_mul(TERM_BYTES))
        } else {
            terms_at
        };
        Layout {
            run_id,
            scalars,
            breakpoints,
            table,
            physics: physics_at,
            terms: terms_at,
            crc,
        }
    }

    const fn total(&self) -> usize {
        self.crc.saturating_add(CRC_LEN)
    }
}

// Size contracts, checked when the crate compiles.
const _: () = {
    // the header is the 16 bytes the table above documents, and keeps the f32 words
    // that follow 4-byte aligned relative to the blob's start
    assert!(HEADER_LEN == 16 && HEADER_LEN % 4 == 0);
    // the length fields are u16
    assert!(MAX_BLOB_LEN <= u16::MAX as usize);
    // the largest blob of either kind fits MAX_BLOB_LEN, so every valid blob re-encodes
    let pwl = Layout::new(
        ModelKind::Pwl,
        MAX_BREAKPOINTS,
        MAX_SERIAL_LEN,
        true,
        MAX_TERMS,
    );
    let poly = Layout::new(
        ModelKind::Poly,
        MAX_POLY_ORDER.saturating_add(1),
        MAX_SERIAL_LEN,
        true,
        MAX_TERMS,
    );
    assert!(pwl.total() <= MAX_BLOB_LEN && poly.total() <= MAX_BLOB_LEN);
    // the term count fits the head's byte, and an entry keeps the words aligned
    assert!(MAX_TERMS <= 255 && TERM_BYTES % 4 == 0 && TERMS_HEAD_BYTES == 4);
    // the row and word counts fit the header's u8 fields
    assert!(MAX_BREAKPOINTS <= 255);
    assert!(PHYSICS_WORDS <= 255);
};

fn u16_at(bytes: &[u8], off: usize) -> Option<u16> {
    bytes
        .get(off..)
        .and_then(|s| s.first_chunk::<2>())
        .map(|b| u16::from_le_bytes(*b))
}

/// The little-endian f32 at `off` (alignment-free); NaN past the end (never after
/// validation), so a bug would show, not read as a plausible zero.
#[inline]
fn f32_at(bytes: &[u8], off: usize) -> f32 {
    match bytes.get(off..).and_then(|s| s.first_chunk::<4>()) {
        Some(b) => f32::from_le_bytes(*b),
        None => f32::NAN,
    }
}

/// A blob validated in place: it borrows the bytes (in flash) and reads every value
/// from them on demand. Obtained only from [`BlobView::new`] or
/// [`BlobView::from_region`], so holding one means the blob passed every check.
#[derive(Clone, Copy, Debug)]
pub struct BlobView<'a> {
    bytes: &'a [u8],
    /// Where the physics section starts (0: none; validated to hold [`PHYSICS_BYTES`]).
    /// An offset, not a reference: the view stays 32 bytes on a 64-bit host, which keeps
    /// the C interface's compensator within its 256 bytes there too.
    physics: u16,
    kind: ModelKind,
    rows: u8,
    clamp: bool,
    /// Entries of the term table (0: none; only with the `terms` feature, as every field
    /// and method of the table: a firmware without it refuses a table, and links none of
    /// its code).
    #[cfg(feature = "terms")]
    n_terms: u8,
    scalars: u16,
    breakpoints: u16,
    table: u16,
    /// The term table's head word (the CRC's offset when there is none): where the f32
    /// words that [`Source::all_finite`] checks end.
    #[cfg(feature = "terms")]
    terms: u16,
}

impl<'a> BlobView<'a> {
    /// Validate the blob `bytes` (exactly one blob) where it lies.
    pub fn new(bytes: &'a [u8]) -> Result<Self, Error> {
        let n = bytes.len();
        if n < HEADER_LEN.saturating_add(CRC_LEN) {
            return Err(Error::Truncated);
        }
        if let Some(declared) = declared_len(bytes) {
            if declared > n {
                return Err(Error::Truncated);
            }
            if declared < n {
                return Err(Error::TrailingBytes);
            }
        }
        // n >= HEADER_LEN + CRC_LEN, so the split is in range
        let (body, stored) = bytes.split_at(n.saturating_sub(CRC_LEN));
        let stored = stored.first_chunk::<4>().map(|b| u32::from_le_bytes(*b));
        if stored != Some(crc32(body)) {
            return Err(Error::CrcMismatch);
        }
        if bytes.get(..4) != Some(&MAGIC[..]) {
            return Err(Error::BadMagic);
        }
        let version = u16_at(bytes, 4).unwrap_or(0);
        if !(OLDEST_FORMAT_VERSION..=FORMAT_VERSION).contains(&version) {
            return Err(Error::UnsupportedVersion(version));
        }
        // a firmware without `terms` neither validates nor applies a table it cannot
        // compensate: a blob with one (format 5) is refused when it is opened, and no code
        // of the table is linked (its flash budget)
        if cfg!(not(feature = "terms")) && version == FORMAT_VERSION {
            return Err(Error::TermsNotBuiltIn);
        }
        // A current-version blob with a valid CRC must declare its own length.
        if declared_len(bytes) != Some(n) {
            return Err(Error::Malformed);
        }
        let view = Self::parse_header(bytes, version)?;
        validate_source(&view)?;
        let c0 = Coeffs::from_array(&eval_table(&view, view.t0_c(), view.t0_c()));
        invert(&c0.k).ok_or(Error::Singular)?;
        Ok(view)
    }

    /// Validate the blob at the start of a larger region (a flash sector, say): its
    /// header's length decides where it ends; the rest of the region is ignored.
    pub fn from_region(region: &'a [u8]) -> Result<Self, Error> {
        match declared_len(region) {
            Some(n) if n <= region.len() => Self::new(region.get(..n).unwrap_or(region)),
            _ => Self::new(region),
        }
    }

    /// The header's fields against the layout (CRC, magic and version already checked).
    fn parse_header(bytes: &'a [u8], version: u16) -> Result<Self, Error> {
        let h = bytes.first_chunk::<HEADER_LEN>().ok_or(Error::Truncated)?;
        let [_, _, _, _, _, _, _, _, _, _, model, rows, flags, serial, physics, unit] = *h;
        let kind = match model {
            MODEL_POLY => ModelKind::Poly,
            MODEL_PWL => ModelKind::Pwl,
            _ => return Err(Error::Malformed),
        };
        let max_rows = match kind {
            ModelKind::Poly => MAX_POLY_ORDER.saturating_add(1),
            ModelKind::Pwl => MAX_BREAKPOINTS,
        };
        if usize::from(rows) < 2 || usize::from(rows) > max_rows {
            return Err(Error::TableSize);
        }
        let has_physics = match usize::from(physics) {
            0 => false,
            PHYSICS_WORDS => true,
            _ => return Err(Error::Malformed),
        };
        // format 5 is written only with a term table, format 4 never has one (and a
        // firmware without `terms` refused format 5 when it read the version)
        let has_terms = cfg!(feature = "terms") && version == FORMAT_VERSION;
        let terms_flag = if has_terms { FLAG_TERMS } else { 0 };
        if flags & !FLAG_CLAMP != terms_flag
            || OutputUnit::from_code(unit).is_none()
            || usize::from(serial) > MAX_SERIAL_LEN
        {
            return Err(Error::Malformed);
        }
        let (rows_n, serial_n) = (usize::from(rows), usize::from(serial));
        let n_terms = if has_terms {
            let base = Layout::new(kind, rows_n, serial_n, has_physics, 0);
            terms_head(bytes, base.terms)?
        } else {
            0
        };
        let l = Layout::new(kind, rows_n, serial_n, has_physics, usize::from(n_terms));
        if l.total() != bytes.len() {
            return Err(Error::Malformed);
        }
        let serial_end = HEADER_LEN.saturating_add(usize::from(serial));
        let text = bytes.get(HEADER_LEN..serial_end).ok_or(Error::Malformed)?;
        let padding = bytes.get(serial_end..l.run_id).ok_or(Error::Malformed)?;
        if !text.iter().all(|&b| serial_byte(b)) || padding.iter().any(|&b| b != 0) {
            return Err(Error::Malformed);
        }
        // every offset is below the total length, itself below MAX_BLOB_LEN (u16)
        let off = |v: usize| u16::try_from(v).map_err(|_| Error::Malformed);
        let physics = if has_physics {
            let section = bytes.get(l.physics..).ok_or(Error::Malformed)?;
            let _ = section
                .first_chunk::<PHYSICS_BYTES>()
                .ok_or(Error::Malformed)?;
            // after the header and the table, never 0
            off(l.physics)?
        } else {
            0
        };
        Ok(BlobView {
            bytes,
            physics,
            kind,
            rows,
            clamp: flags & FLAG_CLAMP != 0,
            #[cfg(feature = "terms")]
            n_terms,
            scalars: off(l.scalars)?,
            breakpoints: off(l.breakpoints)?,
            table: off(l.table)?,
            #[cfg(feature = "terms")]
            terms: off(l.terms)?,
        })
    }

    /// The format version of the blob (4, or 5 with a term table).
    pub fn version(&self) -> u16 {
        u16_at(self.bytes, 4).unwrap_or(0)
    }

    /// The offset of term entry `j`.
    #[cfg(feature = "terms")]
    fn term_at(&self, j: usize) -> usize {
        usize::from(self.terms)
            .saturating_add(TERMS_HEAD_BYTES)
            .saturating_add(j.saturating_mul(TERM_BYTES))
    }

    /// The blob's bytes.
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// The unit of the outputs K and U0 are in (validated: a known code).
    pub fn output_unit(&self) -> OutputUnit {
        self.bytes
            .get(15)
            .and_then(|c| OutputUnit::from_code(*c))
            .unwrap_or_default()
    }

    /// The id of the host-fit run that made the blob (all zero: none).
    pub fn run_id(&self) -> RunId {
        let at = usize::from(self.scalars).saturating_sub(RUN_ID_LEN);
        self.bytes
            .get(at..)
            .and_then(|s| s.first_chunk::<RUN_ID_LEN>())
            .map_or(RunId::NONE, |b| RunId(*b))
    }

    /// The unit's serial number: printable ASCII, so no UTF-8 decoder is linked.
    pub fn serial(&self) -> &'a [u8] {
        let len = self.bytes.get(13).copied().map_or(0, usize::from);
        self.bytes
            .get(HEADER_LEN..HEADER_LEN.saturating_add(len))
            .unwrap_or(&[])
    }

    fn scalar(&self, k: usize) -> f32 {
        f32_at(
            self.bytes,
            usize::from(self.scalars).saturating_add(k.saturating_mul(4)),
        )
    }

    /// The owned form (the host's: heapless tables, about 1 KiB).
    pub fn to_blob(&self) -> Blob {
        let mut serial = heapless::String::new();
        // the serial was checked: at most MAX_SERIAL_LEN bytes of printable ASCII
        let _ = serial.push_str(core::str::from_utf8(self.serial()).unwrap_or(""));
        let rows = 0..self.rows();
        let model = match self.kind {
            ModelKind::Poly => TempModel::Poly {
                terms: rows.map(|j| self.row(j)).collect(),
            },
            ModelKind::Pwl => TempModel::Pwl {
                breakpoints: rows.clone().map(|j| self.breakpoint(j)).collect(),
                values: rows.map(|j| self.row(j)).collect(),
            },
        };
        Blob {
            serial,
            output_unit: self.output_unit(),
            run_id: self.run_id(),
            calibration: Calibration {
                t0_c: self.t0_c(),
                t_min_c: self.t_min_c(),
                t_max_c: self.t_max_c(),
                clamp: self.clamp,
                update_step_c: self.update_step_c(),
                model,
                physics: self.physics(),
            },
            terms: (0..self.term_count())
                .filter_map(|j| self.term_raw(j).entry().ok())
                .collect(),
        }
    }
}

/// The number of entries the term table's head word at `at` declares: 1..=[`MAX_TERMS`]
/// ([`Error::Malformed`] for 0, for non-zero reserved bytes or no word there;
/// [`Error::TooManyTerms`] above the maximum).
fn terms_head(bytes: &[u8], at: usize) -> Result<u8, Error> {
    let head = bytes
        .get(at..)
        .and_then(|s| s.first_chunk::<TERMS_HEAD_BYTES>())
        .ok_or(Error::Malformed)?;
    let [count, r0, r1, r2] = *head;
    if count == 0 || (r0 | r1 | r2) != 0 {
        return Err(Error::Malformed);
    }
    if usize::from(count) > MAX_TERMS {
        return Err(Error::TooManyTerms);
    }
    Ok(count)
}

/// A serial is printable ASCII (a unit name).
fn serial_byte(b: u8) -> bool {
    (0x20..0x7F).contains(&b)
}

/// The total length the header declares, when it agrees with its complement.
fn declared_len(bytes: &[u8]) -> Option<usize> {
    let (n, inv) = (u16_at(bytes, 6)?, u16_at(bytes, 8)?);
    (n == !inv).then_some(usize::from(n))
}

impl Table for BlobView<'_> {
    type Real = f32;
    #[inline]
    fn kind(&self) -> ModelKind {
        self.kind
    }
    #[inline]
    fn rows(&self) -> usize {
        usize::from(self.rows)
    }
    #[inline]
    fn breakpoint(&self, j: usize) -> f32 {
        if j >= self.rows() {
            return f32::NAN;
        }
        f32_at(
            self.bytes,
            usize::from(self.breakpoints).saturating_add(j.saturating_mul(4)),
        )
    }
    #[inline]
    fn row(&self, j: usize) -> CoeffRow<f32> {
        let off = usize::from(self.table).saturating_add(j.saturating_mul(ROW_BYTES));
        // one bounds check per row; the 12 reads at constant offsets need none
        match self
            .bytes
            .get(off..)
            .and_then(|s| s.first_chunk::<ROW_BYTES>())
        {
            Some(r) if j < self.rows() => {
                core::array::from_fn(|i| f32_at(r, 4usize.saturating_mul(i)))
            }
            _ => [f32::NAN; N_COEFFS],
        }
    }
}

impl Source for BlobView<'_> {
    type Real = f32;
    type Table = Self;
    #[inline]
    fn table(&self) -> &Self {
        self
    }
    #[inline]
    fn t0_c(&self) -> f32 {
        self.scalar(0)
    }
    #[inline]
    fn t_min_c(&self) -> f32 {
        self.scalar(1)
    }
    #[inline]
    fn t_max_c(&self) -> f32 {
        self.scalar(2)
    }
    #[inline]
    fn clamp(&self) -> bool {
        self.clamp
    }
    #[inline]
    fn update_step_c(&self) -> f32 {
        self.scalar(3)
    }
    #[inline]
    fn has_physics(&self) -> bool {
        self.physics != 0
    }
    #[inline]
    fn physics(&self) -> Option<Physics<f32>> {
        if self.physics == 0 {
            return None;
        }
        // validated to be there: the checks cannot fail, and cost a compare per sample
        let p = self
            .bytes
            .get(usize::from(self.physics)..)?
            .first_chunk::<PHYSICS_BYTES>()?;
        Some(Physics::from_word_fn(|i| {
            f32_at(p, 4usize.saturating_mul(i))
        }))
    }
    /// Every f32 word of the blob, scalars to physics section, in one pass over the
    /// bytes (an exponent of all ones is an infinity or a NaN); the term table's words
    /// are checked entry by entry ([`RawTerm::entry`]).
    fn all_finite(&self) -> bool {
        #[cfg(feature = "terms")]
        let end = usize::from(self.terms);
        #[cfg(not(feature = "terms"))]
        let end = self.bytes.len().saturating_sub(CRC_LEN);
        let words = self
            .bytes
            .get(usize::from(self.scalars)..end)
            .unwrap_or(&[]);
        words.chunks_exact(4).all(|w| {
            let bits = u32::from_le_bytes([
                w.first().copied().unwrap_or(0xFF),
                w.get(1).copied().unwrap_or(0xFF),
                w.get(2).copied().unwrap_or(0xFF),
                w.get(3).copied().unwrap_or(0xFF),
            ]);
            bits & 0x7F80_0000 != 0x7F80_0000
        })
    }
    /// (Without the `terms` feature the default, 0: such a firmware refuses a table when
    /// it opens the blob.)
    #[cfg(feature = "terms")]
    #[inline]
    fn term_count(&self) -> usize {
        usize::from(self.n_terms)
    }
    /// Entry `j` read where it lies ([`RawTerm::none`] past the table).
    #[cfg(feature = "terms")]
    #[inline]
    fn term_raw(&self, j: usize) -> RawTerm<f32> {
        let at = self.term_at(j);
        match self
            .bytes
            .get(at..)
            .and_then(|s| s.first_chunk::<TERM_BYTES>())
        {
            Some(&[axis, c0, c1, c2, ..]) if j < self.term_count() => RawTerm {
                axis,
                codes: [c0, c1, c2],
                tau_s: f32_at(self.bytes, at.saturating_add(4)),
                coefficient: f32_at(self.bytes, at.saturating_add(8)),
            },
            _ => RawTerm::none(),
        }
    }
    /// The axis and codes of entry `j`: one word, what every sample reads.
    #[cfg(feature = "terms")]
    #[inline]
    fn term_shape(&self, j: usize) -> (u8, [u8; 3]) {
        match self
            .bytes
            .get(self.term_at(j)..)
            .and_then(|s| s.first_chunk::<4>())
        {
            Some(&[axis, c0, c1, c2]) if j < self.term_count() => (axis, [c0, c1, c2]),
            _ => (u8::MAX, [0; 3]),
        }
    }
}

/// The owned blob: which unit, and its calibration in f32 (the host's form; the
/// firmware reads a [`BlobView`] instead).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Blob {
    /// The unit's serial number.
    pub serial: heapless::String<MAX_SERIAL_LEN>,
    /// The unit of the outputs K and U0 are in.
    pub output_unit: OutputUnit,
    /// The host-fit run that made the blob ([`RunId::NONE`]: none).
    pub run_id: RunId,
    /// Temperature model and its use.
    pub calibration: Calibration<f32>,
    /// The discovered terms of the unit's state (empty: none; a blob with terms is
    /// format 5). Compensate with them: [`crate::compensate::Compensator::with_terms`].
    pub terms: TermList<f32>,
}

impl Blob {
    /// All checks a decoded blob passes, also applied before encoding.
    pub fn validate(&self) -> Result<(), Error> {
        if !self.serial.bytes().all(serial_byte) {
            return Err(Error::Malformed);
        }
        self.calibration.validate()?;
        validate_entries(&self.terms)?;
        let c0 = Coeffs::from_array(&self.calibration.at_t0());
        invert(&c0.k).map(|_| ()).ok_or(Error::Singular)
    }

    /// The format version the blob is written in: 5 with discovered terms, else 4.
    pub fn version(&self) -> u16 {
        if self.terms.is_empty() {
            OLDEST_FORMAT_VERSION
        } else {
            FORMAT_VERSION
        }
    }

    /// Write the blob into `buf` (format [`Blob::version`]), returning the number of
    /// bytes written. No allocator: the caller's buffer, [`MAX_BLOB_LEN`] always suffices.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        self.validate()?;
        let cal = &self.calibration;
        let (kind, rows) = (cal.model.kind(), cal.model.rows());
        let serial = self.serial.as_bytes();
        let n_terms = self.terms.len();
        let l = Layout::new(kind, rows, serial.len(), cal.physics.is_some(), n_terms);
        let n = l.total();
        let out = buf.get_mut(..n).ok_or(Error::BufferTooSmall)?;
        out.fill(0);
        let n16 = u16::try_from(n).map_err(|_| Error::BufferTooSmall)?;
        let [m0, m1, m2, m3] = MAGIC;
        let [v0, v1] = self.version().to_le_bytes();
        let [n0, n1] = n16.to_le_bytes();
        let [i0, i1] = (!n16).to_le_bytes();
        let model = match kind {
            ModelKind::Poly => MODEL_POLY,
            ModelKind::Pwl => MODEL_PWL,
        };
        // validated: rows <= 16, serial <= MAX_SERIAL_LEN bytes, physics words = PHYSICS_WORDS
        let small = |v: usize| u8::try_from(v).map_err(|_| Error::TableSize);
        let physics_words = if cal.physics.is_some() {
            PHYSICS_WORDS
        } else {
            0
        };
        let header = [
            m0,
            m1,
            m2,
            m3,
            v0,
            v1,
            n0,
            n1,
            i0,
            i1,
            model,
            small(rows)?,
            (if cal.clamp { FLAG_CLAMP } else { 0 }) | (if n_terms > 0 { FLAG_TERMS } else { 0 }),
            small(serial.len())?,
            small(physics_words)?,
            self.output_unit.code(),
        ];
        let mut w = Writer { out, at: 0 };
        w.bytes(&header)?;
        w.bytes(serial)?;
        w.at = l.run_id;
        w.bytes(&self.run_id.0)?;
        for v in [cal.t0_c, cal.t_min_c, cal.t_max_c, cal.update_step_c] {
            w.f32(v)?;
        }
        for j in 0..rows {
            if kind == ModelKind::Pwl {
                w.at = l.breakpoints.saturating_add(j.saturating_mul(4));
                w.f32(cal.model.breakpoint(j))?;
            }
            w.at = l.table.saturating_add(j.saturating_mul(ROW_BYTES));
            for v in cal.model.row(j) {
                w.f32(v)?;
            }
        }
        w.at = l.physics;
        if let Some(p) = &cal.physics {
            for v in p.to_words() {
                w.f32(v)?;
            }
        }
        w.at = l.terms;
        if n_terms > 0 {
            w.bytes(&[small(n_terms)?, 0, 0, 0])?;
            for e in &self.terms {
                let r = e.raw();
                let [c0, c1, c2] = r.codes;
                w.bytes(&[r.axis, c0, c1, c2])?;
                w.f32(r.tau_s)?;
                w.f32(r.coefficient)?;
            }
        }
        let body = w.out.get(..l.crc).ok_or(Error::BufferTooSmall)?;
        let crc = crc32(body);
        w.at = l.crc;
        w.bytes(&crc.to_le_bytes())?;
        Ok(n)
    }

    /// Validate and read a blob into the owned form ([`BlobView::new`], then
    /// [`BlobView::to_blob`]).
    pub fn decode(bytes: &[u8]) -> Result<Blob, Error> {
        BlobView::new(bytes).map(|v| v.to_blob())
    }
}

struct Writer<'b> {
    out: &'b mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) -> Result<(), Error> {
        let end = self.at.checked_add(b.len()).ok_or(Error::BufferTooSmall)?;
        self.out
            .get_mut(self.at..end)
            .ok_or(Error::BufferTooSmall)?
            .copy_from_slice(b);
        self.at = end;
        Ok(())
    }
    fn f32(&mut self, v: f32) -> Result<(), Error> {
        self.bytes(&v.to_le_bytes())
    }
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
    // "PAPER-UNIT" is 10 bytes: always fits the serial.
    let _ = serial.push_str("PAPER-UNIT");
    Blob {
        serial,
        output_unit: OutputUnit::Volt,
        run_id: RunId::NONE,
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
        terms: TermList::new(),
    }
}

/// Discovered terms of every kind of factor, a full table of [`MAX_TERMS`], each of a
/// plausible size (about 0.1-0.3 mg on the paper unit): the terms half of the examples,
/// benchmarks and tests (set it as `terms` of [`example_blob`]).
pub fn example_terms() -> TermList<f32> {
    use crate::terms::Factor::*;
    let tau = |s: f32| Tau::from_seconds(s);
    let list: [(Axis, &[crate::terms::Factor], Option<Tau>, f32); MAX_TERMS] = [
        (Axis::Z, &[Ax, Ay], None, 1.5e-4),
        (Axis::X, &[Ax, Ax, Ax], None, -8e-5),
        (Axis::Y, &[Az, Az, DT], None, 2e-6),
        (Axis::X, &[AbsAy], None, 6e-5),
        (Axis::Y, &[Ay, DTdt], None, 4e-5),
        (Axis::Z, &[DT, DecayPowerOn], tau(1200.0), -3e-6),
        (Axis::X, &[DecayPowerOn], tau(25.0), 1.2e-4),
        (Axis::Z, &[Ax, AbsAx, Az], None, 5e-5),
    ];
    list.iter()
        .filter_map(|(axis, f, t, c)| {
            Term::new(f, *t).ok().map(|term| TermEntry {
                axis: *axis,
                term,
                coefficient: *c,
            })
        })
        .collect()
}

/// In-flight terms of every kind, each of a plausible size: the physics half of the
/// examples, benchmarks and tests (set it as `calibration.physics` of [`example_blob`]).
pub fn example_physics() -> Physics<f32> {
    Physics {
        lag_tau_s: 100.0,
        rate: [0.02, 0.0, -0.01],
        rate_tau_s: 10.0,
        hysteresis: [1e-4, 0.0, 0.0],
        hysteresis_threshold_c: 0.5,
        hysteresis_initial: 1.0,
        k2: [1e-4, 0.0, 0.0],
        asymmetry: [0.0, 1e-4, 0.0],
        warmup: [2e-4, 0.0, 0.0],
        warmup_tau_s: 1000.0,
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
        assert_eq!(n, 220);
        assert_eq!(Blob::decode(&buf[..n]).unwrap(), b);
        let v = BlobView::new(&buf[..n]).unwrap();
        assert_eq!(v.serial(), b"PAPER-UNIT");
        assert_eq!(v.output_unit(), OutputUnit::Volt);
        assert!(v.run_id().is_none());
        assert_eq!(BlobView::from_region(&buf).unwrap().bytes().len(), n);
    }

    #[test]
    fn output_units_and_run_ids() {
        for code in 0..=7u8 {
            let u = OutputUnit::from_code(code).unwrap();
            assert_eq!(u.code(), code);
            if !matches!(u, OutputUnit::Unstated | OutputUnit::Other) {
                assert_eq!(OutputUnit::from_label(u.label()), u);
            }
        }
        assert_eq!(OutputUnit::from_code(8), None);
        assert_eq!(OutputUnit::from_label("m/s^2"), OutputUnit::MetrePerSecond2);
        assert_eq!(OutputUnit::from_label("furlongs"), OutputUnit::Other);
        let id = RunId(core::array::from_fn(|i| (i * 17) as u8));
        assert_eq!(id.to_string(), "00112233445566778899aabbccddeeff");
        assert!(!id.is_none() && RunId::NONE.is_none());
        let mut b = example_blob();
        b.run_id = id;
        b.output_unit = OutputUnit::MetrePerSecond2;
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).unwrap();
        let v = BlobView::new(&buf[..n]).unwrap();
        assert_eq!(
            (v.run_id(), v.output_unit()),
            (id, OutputUnit::MetrePerSecond2)
        );
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
