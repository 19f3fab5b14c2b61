//! firmware-core from C: the coefficient blob validated in place, the compensator in
//! storage the caller provides, status codes, no panics across the boundary.
//!
//! The header `include/firmware_core.h` is generated from this file by cbindgen and
//! committed; the `header_is_current` test fails when it is stale. This is the one
//! crate of the workspace with `unsafe`: raw pointers from C become references here,
//! each conversion justified where it is made.
//!
//! ```c
//! #include "firmware_core.h"
//! static fc_blob blob; static fc_compensator comp;
//! if (fc_blob_open(&blob, unit_blob, unit_blob_len) != FC_OK) { /* refuse to run */ }
//! /* the MCU samples at 100 Hz: the sample period, s */
//! if (fc_compensator_init(&comp, &blob, FC_METHOD_CONSTANTS, 0.01f) != FC_OK) { /* ... */ }
//! uint32_t status = fc_compensate(&comp, volts, temp_c, accel_g);
//! /* a sample 0.25 s after the previous one (a gap) */
//! status = fc_compensate_dt(&comp, volts, temp_c, 0.25f, accel_g);
//! /* the discovered terms the blob carries (compensated by fc_compensate too) */
//! uint32_t n; fc_term term;
//! fc_blob_term_count(&blob, &n);
//! for (uint32_t i = 0; i < n; i++) fc_blob_term(&blob, i, &term);
//! ```
#![no_std]
#![deny(unsafe_code)]

use core::mem::{align_of, size_of};
use firmware_core::blob::{BlobView, RUN_ID_LEN};
use firmware_core::compensate::{Compensator, ErrorModel, FlashCompensator, Method, Status};
use firmware_core::temperature::Source;
use firmware_core::terms::{Factor, MAX_TERMS};
use firmware_core::Error;

/// Bytes of an [`fc_blob`].
pub const FC_BLOB_SIZE: usize = 48;
/// Bytes of an [`fc_compensator`]: the compensator state budget.
pub const FC_COMPENSATOR_SIZE: usize = 256;
/// Alignment of both storage types, bytes.
pub const FC_ALIGN: usize = 8;

/// Success.
pub const FC_OK: i32 = 0;
/// A pointer argument was NULL.
pub const FC_ERR_NULL: i32 = 1;
/// The method is not one of `FC_METHOD_*`.
pub const FC_ERR_BAD_METHOD: i32 = 2;
/// The storage was not initialised by `fc_blob_open` / `fc_compensator_init`.
pub const FC_ERR_NOT_INITIALISED: i32 = 3;
/// An index past the end of a table (`fc_blob_term`).
pub const FC_ERR_INDEX: i32 = 4;
/// The blob ends before its declared length (cut short), or is shorter than a header.
pub const FC_ERR_TRUNCATED: i32 = 10;
/// CRC-32 mismatch: the blob is corrupted.
pub const FC_ERR_CRC: i32 = 11;
/// Not a coefficient blob (bad magic).
pub const FC_ERR_BAD_MAGIC: i32 = 12;
/// A valid blob of a format version this firmware does not read (an older blob).
pub const FC_ERR_UNSUPPORTED_VERSION: i32 = 13;
/// Header and layout disagree, or reserved bytes are set.
pub const FC_ERR_MALFORMED: i32 = 14;
/// Bytes after the blob's declared end.
pub const FC_ERR_TRAILING_BYTES: i32 = 15;
/// A table size out of range.
pub const FC_ERR_TABLE_SIZE: i32 = 16;
/// Breakpoints not strictly increasing.
pub const FC_ERR_BREAKPOINTS: i32 = 17;
/// A value is NaN or infinite.
pub const FC_ERR_NON_FINITE: i32 = 18;
/// Empty temperature range, negative update step, or a physics term out of range.
pub const FC_ERR_BAD_RANGE: i32 = 19;
/// K is singular at the reference temperature.
pub const FC_ERR_SINGULAR: i32 = 20;
/// The blob has physics terms; the library was built without them.
pub const FC_ERR_PHYSICS_NOT_BUILT_IN: i32 = 21;
/// The sample period is not a positive, finite number of seconds.
pub const FC_ERR_BAD_SAMPLE_PERIOD: i32 = 22;
/// The table of discovered terms holds more than `FC_MAX_TERMS` entries.
pub const FC_ERR_TOO_MANY_TERMS: i32 = 23;
/// A discovered term's axis is none of x, y, z.
pub const FC_ERR_TERM_AXIS: i32 = 24;
/// A discovered term's factors are no canonical term of the vocabulary.
pub const FC_ERR_TERM_FACTORS: i32 = 25;
/// A discovered term's decay time constant is not positive (or given without a decay).
pub const FC_ERR_TERM_TIME_CONSTANT: i32 = 26;
/// The same discovered term twice on one axis.
pub const FC_ERR_DUPLICATE_TERM: i32 = 27;
/// The blob has discovered terms; the library was built without them.
pub const FC_ERR_TERMS_NOT_BUILT_IN: i32 = 28;
/// Any other refusal (a newer firmware-core error).
pub const FC_ERR_OTHER: i32 = 99;

/// Method 1: coefficients at the current temperature.
pub const FC_METHOD_CONSTANTS: u32 = 0;
/// Method 2, the full temperature-error model.
pub const FC_METHOD_RESULT_FULL: u32 = 1;
/// Method 2, the simplified (diagonal) temperature-error model.
pub const FC_METHOD_RESULT_SIMPLIFIED: u32 = 2;

/// Sample status bit: temperature outside the valid range (extrapolated or clamped).
pub const FC_STATUS_TEMP_OUT_OF_RANGE: u32 = 1;
/// Sample status bit: the temperature was clamped to the valid range.
pub const FC_STATUS_TEMP_CLAMPED: u32 = 2;
/// Sample status bit: the temperature was not finite; the last good one was used.
pub const FC_STATUS_TEMP_NON_FINITE: u32 = 4;
/// Sample status bit: a voltage was not finite; the acceleration is NaN.
pub const FC_STATUS_INPUT_NON_FINITE: u32 = 8;
/// Sample status bit: K(T) singular at the new temperature; the last matrices were kept.
pub const FC_STATUS_SINGULAR: u32 = 16;
/// Sample status bit: the result overflowed; the acceleration is NaN.
pub const FC_STATUS_OUTPUT_NON_FINITE: u32 = 32;
/// Sample status bit: the time step of `fc_compensate_dt` was negative or not finite; it
/// was taken as 0.
pub const FC_STATUS_BAD_TIME_STEP: u32 = 64;
/// Sample status bit: a NULL or uninitialised argument; nothing was computed.
pub const FC_STATUS_BAD_ARGUMENT: u32 = 0x80;

/// Output unit code (byte 15 of the blob): not stated.
pub const FC_UNIT_UNSTATED: u8 = 0;
/// Output unit code: V.
pub const FC_UNIT_V: u8 = 1;
/// Output unit code: mV.
pub const FC_UNIT_MV: u8 = 2;
/// Output unit code: m/s2.
pub const FC_UNIT_M_S2: u8 = 3;
/// Output unit code: g.
pub const FC_UNIT_G: u8 = 4;
/// Output unit code: mg.
pub const FC_UNIT_MG: u8 = 5;
/// Output unit code: counts.
pub const FC_UNIT_COUNTS: u8 = 6;
/// Output unit code: a unit the recording format does not list.
pub const FC_UNIT_OTHER: u8 = 7;
/// Bytes of a blob's run id.
pub const FC_RUN_ID_LEN: usize = 16;

/// The most discovered terms a blob carries.
pub const FC_MAX_TERMS: u32 = 8;
/// A discovered term's factor code: no factor (after the last).
pub const FC_FACTOR_NONE: u8 = 0;
/// Factor code: `a_x`, g.
pub const FC_FACTOR_AX: u8 = 1;
/// Factor code: `abs(a_x)`.
pub const FC_FACTOR_ABS_AX: u8 = 2;
/// Factor code: `a_y`, g.
pub const FC_FACTOR_AY: u8 = 3;
/// Factor code: `abs(a_y)`.
pub const FC_FACTOR_ABS_AY: u8 = 4;
/// Factor code: `a_z`, g.
pub const FC_FACTOR_AZ: u8 = 5;
/// Factor code: `abs(a_z)`.
pub const FC_FACTOR_ABS_AZ: u8 = 6;
/// Factor code: `dT`, the sensor temperature minus T0, C.
pub const FC_FACTOR_DT: u8 = 7;
/// Factor code: `dTdt`, the sensor temperature's rate, C/min.
pub const FC_FACTOR_DTDT: u8 = 8;
/// Factor code: `decay(power_on,TAU)`, TAU the term's `tau_s`.
pub const FC_FACTOR_DECAY_POWER_ON: u8 = 9;

/// One discovered term of a blob, as the blob stores it: `U[axis] += coefficient *
/// product of the factors`.
#[allow(non_camel_case_types)]
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct fc_term {
    /// The output axis the term enters: 0 x, 1 y, 2 z.
    pub axis: u8,
    /// The factor codes (`FC_FACTOR_*`), canonical order, `FC_FACTOR_NONE` after the last.
    pub factors: [u8; 3],
    /// The decay's time constant, s (0 when there is no `FC_FACTOR_DECAY_POWER_ON`).
    pub tau_s: f32,
    /// The coefficient, output units per the term's units.
    pub coefficient: f32,
}

/// Storage for a validated blob (a view of the bytes in flash). Opaque: fill it with
/// `fc_blob_open`.
#[allow(non_camel_case_types)]
#[repr(C)]
pub struct fc_blob {
    _opaque: [u64; 6],
}

/// Storage for a compensator (its cached matrices and filter state). Opaque: fill it
/// with `fc_compensator_init`.
#[allow(non_camel_case_types)]
#[repr(C)]
pub struct fc_compensator {
    _opaque: [u64; 32],
}

/// Marks storage that holds an initialised value (garbage rarely matches).
const TAG_BLOB: u32 = 0x424C_4F42;
const TAG_COMP: u32 = 0x434F_4D50;

#[repr(C)]
struct BlobSlot {
    tag: u32,
    view: BlobView<'static>,
}

#[repr(C)]
struct CompSlot {
    tag: u32,
    comp: FlashCompensator<'static>,
}

// The status bits are firmware-core's, and the bad-argument bit is none of them.
const _: () = {
    assert!(FC_STATUS_TEMP_OUT_OF_RANGE == Status::TEMP_OUT_OF_RANGE.bits() as u32);
    assert!(FC_STATUS_TEMP_CLAMPED == Status::TEMP_CLAMPED.bits() as u32);
    assert!(FC_STATUS_TEMP_NON_FINITE == Status::TEMP_NON_FINITE.bits() as u32);
    assert!(FC_STATUS_INPUT_NON_FINITE == Status::INPUT_NON_FINITE.bits() as u32);
    assert!(FC_STATUS_SINGULAR == Status::SINGULAR.bits() as u32);
    assert!(FC_STATUS_OUTPUT_NON_FINITE == Status::OUTPUT_NON_FINITE.bits() as u32);
    assert!(FC_STATUS_BAD_TIME_STEP == Status::BAD_TIME_STEP.bits() as u32);
    assert!(FC_STATUS_BAD_ARGUMENT > 0x7F);
    assert!(FC_RUN_ID_LEN == RUN_ID_LEN);
};

// The factor codes and the table's bound are firmware-core's.
const _: () = {
    assert!(FC_MAX_TERMS as usize == MAX_TERMS);
    assert!(FC_FACTOR_AX == Factor::Ax.code() && FC_FACTOR_ABS_AX == Factor::AbsAx.code());
    assert!(FC_FACTOR_AY == Factor::Ay.code() && FC_FACTOR_ABS_AY == Factor::AbsAy.code());
    assert!(FC_FACTOR_AZ == Factor::Az.code() && FC_FACTOR_ABS_AZ == Factor::AbsAz.code());
    assert!(FC_FACTOR_DT == Factor::DT.code() && FC_FACTOR_DTDT == Factor::DTdt.code());
    assert!(FC_FACTOR_DECAY_POWER_ON == Factor::DecayPowerOn.code());
    assert!(size_of::<fc_term>() == 12);
};

// The unit codes are firmware-core's.
const _: () = {
    use firmware_core::blob::OutputUnit;
    assert!(FC_UNIT_UNSTATED == OutputUnit::Unstated.code());
    assert!(FC_UNIT_V == OutputUnit::Volt.code());
    assert!(FC_UNIT_MV == OutputUnit::MilliVolt.code());
    assert!(FC_UNIT_M_S2 == OutputUnit::MetrePerSecond2.code());
    assert!(FC_UNIT_G == OutputUnit::G.code());
    assert!(FC_UNIT_MG == OutputUnit::MilliG.code());
    assert!(FC_UNIT_COUNTS == OutputUnit::Counts.code());
    assert!(FC_UNIT_OTHER == OutputUnit::Other.code());
};

// Size contracts: what lives in the C storage fits it, on the MCU and on the host.
const _: () = {
    assert!(size_of::<fc_blob>() == FC_BLOB_SIZE && align_of::<fc_blob>() == FC_ALIGN);
    assert!(size_of::<fc_compensator>() == FC_COMPENSATOR_SIZE);
    assert!(align_of::<fc_compensator>() == FC_ALIGN);
    assert!(size_of::<BlobSlot>() <= FC_BLOB_SIZE && align_of::<BlobSlot>() <= FC_ALIGN);
    assert!(size_of::<CompSlot>() <= FC_COMPENSATOR_SIZE);
    assert!(align_of::<CompSlot>() <= FC_ALIGN);
    // the state itself stays within its 256-byte budget
    assert!(size_of::<FlashCompensator<'static>>() <= 256);
};

fn code(e: Error) -> i32 {
    match e {
        Error::Truncated => FC_ERR_TRUNCATED,
        Error::CrcMismatch => FC_ERR_CRC,
        Error::BadMagic => FC_ERR_BAD_MAGIC,
        Error::UnsupportedVersion(_) => FC_ERR_UNSUPPORTED_VERSION,
        Error::Malformed => FC_ERR_MALFORMED,
        Error::TrailingBytes => FC_ERR_TRAILING_BYTES,
        Error::TableSize => FC_ERR_TABLE_SIZE,
        Error::BreakpointsNotIncreasing => FC_ERR_BREAKPOINTS,
        Error::NonFinite => FC_ERR_NON_FINITE,
        Error::BadRange => FC_ERR_BAD_RANGE,
        Error::Singular => FC_ERR_SINGULAR,
        Error::PhysicsNotBuiltIn => FC_ERR_PHYSICS_NOT_BUILT_IN,
        Error::BadSamplePeriod => FC_ERR_BAD_SAMPLE_PERIOD,
        Error::TooManyTerms => FC_ERR_TOO_MANY_TERMS,
        Error::TermAxis => FC_ERR_TERM_AXIS,
        Error::TermFactors => FC_ERR_TERM_FACTORS,
        Error::TermTimeConstant => FC_ERR_TERM_TIME_CONSTANT,
        Error::DuplicateTerm => FC_ERR_DUPLICATE_TERM,
        Error::TermsNotBuiltIn => FC_ERR_TERMS_NOT_BUILT_IN,
        _ => FC_ERR_OTHER,
    }
}

fn method(m: u32) -> Option<Method> {
    match m {
        FC_METHOD_CONSTANTS => Some(Method::CorrectConstants),
        FC_METHOD_RESULT_FULL => Some(Method::CorrectResult(ErrorModel::Full)),
        FC_METHOD_RESULT_SIMPLIFIED => Some(Method::CorrectResult(ErrorModel::Simplified)),
        _ => None,
    }
}

/// Validate the blob `bytes[0..len]` where it lies and keep a view of it in `blob`.
///
/// Returns `FC_OK`, or the `FC_ERR_*` code saying why the blob is refused (then `blob`
/// is left uninitialised).
///
/// # Safety
/// `blob` is NULL or points to writable `fc_blob` storage; `bytes` is NULL or points to
/// `len` readable bytes that stay valid and unchanged for as long as `blob`, or any
/// compensator initialised from it, is used (a blob in flash does).
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_blob_open(blob: *mut fc_blob, bytes: *const u8, len: usize) -> i32 {
    if blob.is_null() || bytes.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: `bytes` is non-NULL and, by this function's contract, points to `len`
    // readable bytes that outlive every use of the view (so 'static for the view's
    // purposes) and are not written meanwhile.
    let bytes: &'static [u8] = unsafe { core::slice::from_raw_parts(bytes, len) };
    match BlobView::new(bytes) {
        Ok(view) => {
            let slot = BlobSlot {
                tag: TAG_BLOB,
                view,
            };
            // SAFETY: `blob` is non-NULL and points to writable `fc_blob` storage (the
            // contract); a `BlobSlot` fits its size and alignment (const asserts above).
            // `write` does not read or drop the old contents.
            unsafe { blob.cast::<BlobSlot>().write(slot) };
            FC_OK
        }
        Err(e) => code(e),
    }
}

/// The view in `blob`, if it was opened.
///
/// # Safety
/// `blob` is NULL or points to readable `fc_blob` storage.
#[allow(unsafe_code)]
unsafe fn view_of(blob: *const fc_blob) -> Option<BlobView<'static>> {
    if blob.is_null() {
        return None;
    }
    // SAFETY: non-NULL and readable `fc_blob` storage (the contract), 8-byte aligned
    // (the C type's alignment); the tag is the slot's first field (repr(C)), a plain u32
    // that any bit pattern is valid for.
    let tag = unsafe { blob.cast::<u32>().read() };
    if tag != TAG_BLOB {
        return None;
    }
    // SAFETY: the tag says `fc_blob_open` wrote a `BlobSlot` here (size and alignment
    // fit, const asserts), and the view is `Copy`: reading it leaves the storage as is.
    Some(unsafe { (*blob.cast::<BlobSlot>()).view })
}

/// Start a compensator in `comp` over the validated blob `blob`, with `method`
/// (`FC_METHOD_*`), for an MCU sampling every `sample_period_s` seconds (the period of
/// `fc_compensate`; the physics terms' time constants are in seconds in the blob); its
/// cache starts at T0, the physics terms at power-on.
///
/// Returns `FC_OK`, `FC_ERR_NULL`, `FC_ERR_NOT_INITIALISED` (blob not opened),
/// `FC_ERR_BAD_METHOD`, `FC_ERR_BAD_SAMPLE_PERIOD`, `FC_ERR_SINGULAR` or
/// `FC_ERR_PHYSICS_NOT_BUILT_IN`.
///
/// # Safety
/// `comp` is NULL or points to writable `fc_compensator` storage; `blob` is NULL or
/// points to `fc_blob` storage (opened by `fc_blob_open` for `FC_OK`).
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_compensator_init(
    comp: *mut fc_compensator,
    blob: *const fc_blob,
    method_id: u32,
    sample_period_s: f32,
) -> i32 {
    if comp.is_null() || blob.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: `blob` is non-NULL readable `fc_blob` storage (the contract).
    let Some(view) = (unsafe { view_of(blob) }) else {
        return FC_ERR_NOT_INITIALISED;
    };
    let Some(m) = method(method_id) else {
        return FC_ERR_BAD_METHOD;
    };
    match Compensator::from_blob(view, m, sample_period_s) {
        Ok(c) => {
            let slot = CompSlot {
                tag: TAG_COMP,
                comp: c,
            };
            // SAFETY: `comp` is non-NULL writable `fc_compensator` storage (the
            // contract); a `CompSlot` fits its size and alignment (const asserts).
            unsafe { comp.cast::<CompSlot>().write(slot) };
            FC_OK
        }
        Err(e) => code(e),
    }
}

/// The compensator in `comp`, if it was initialised.
///
/// # Safety
/// `comp` is NULL or points to readable and writable `fc_compensator` storage that no
/// other reference uses during the returned borrow.
#[allow(unsafe_code)]
unsafe fn comp_of<'c>(comp: *mut fc_compensator) -> Option<&'c mut FlashCompensator<'static>> {
    if comp.is_null() {
        return None;
    }
    // SAFETY: non-NULL, readable, 8-byte aligned storage (the contract); the tag is
    // the slot's first field, a u32 valid for any bit pattern.
    let tag = unsafe { comp.cast::<u32>().read() };
    if tag != TAG_COMP {
        return None;
    }
    // SAFETY: the tag says `fc_compensator_init` wrote a `CompSlot` here (size and
    // alignment fit); the storage is not aliased during the borrow (the contract).
    Some(unsafe { &mut (*comp.cast::<CompSlot>()).comp })
}

/// Switch the method of an initialised compensator at run time (recomputes its cache).
///
/// Returns `FC_OK`, `FC_ERR_NULL`, `FC_ERR_NOT_INITIALISED` or `FC_ERR_BAD_METHOD`.
///
/// # Safety
/// `comp` is NULL or points to `fc_compensator` storage, not used concurrently.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_set_method(comp: *mut fc_compensator, method_id: u32) -> i32 {
    if comp.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: non-NULL storage, not used concurrently (the contract).
    let Some(c) = (unsafe { comp_of(comp) }) else {
        return FC_ERR_NOT_INITIALISED;
    };
    match method(method_id) {
        Some(m) => {
            c.set_method(m);
            FC_OK
        }
        None => FC_ERR_BAD_METHOD,
    }
}

/// Compensate one sample, one sample period after the previous one: output voltages
/// `volts[3]` at sensor temperature `temp_c`, specific force in g written to
/// `accel_g[3]`. Fixed work per sample, as in Rust.
///
/// Returns the sample's `FC_STATUS_*` bits (0 = all good); `FC_STATUS_BAD_ARGUMENT`
/// when a pointer is NULL or `comp` was not initialised (then nothing is written).
///
/// # Safety
/// `comp` is NULL or points to `fc_compensator` storage, not used concurrently;
/// `volts` is NULL or points to 3 readable floats; `accel_g` is NULL or points to 3
/// writable floats.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_compensate(
    comp: *mut fc_compensator,
    volts: *const f32,
    temp_c: f32,
    accel_g: *mut f32,
) -> u32 {
    if volts.is_null() || accel_g.is_null() {
        return FC_STATUS_BAD_ARGUMENT;
    }
    // SAFETY: storage not used concurrently (the contract); NULL is handled.
    let Some(c) = (unsafe { comp_of(comp) }) else {
        return FC_STATUS_BAD_ARGUMENT;
    };
    // SAFETY: `volts` is non-NULL and points to 3 readable floats (a C float array,
    // 4-byte aligned).
    let u = unsafe { volts.cast::<[f32; 3]>().read() };
    let out = c.compensate(u, temp_c);
    // SAFETY: `accel_g` is non-NULL and points to 3 writable floats.
    unsafe { accel_g.cast::<[f32; 3]>().write(out.accel) };
    u32::from(out.status.bits())
}

/// Compensate one sample taken `dt_s` seconds after the previous one (or after
/// power-on): a temperature read at its own rate, a logger with gaps. A negative or
/// non-finite `dt_s` is taken as 0 and flagged `FC_STATUS_BAD_TIME_STEP`. Otherwise as
/// `fc_compensate`.
///
/// # Safety
/// As `fc_compensate`.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_compensate_dt(
    comp: *mut fc_compensator,
    volts: *const f32,
    temp_c: f32,
    dt_s: f32,
    accel_g: *mut f32,
) -> u32 {
    if volts.is_null() || accel_g.is_null() {
        return FC_STATUS_BAD_ARGUMENT;
    }
    // SAFETY: storage not used concurrently (the contract); NULL is handled.
    let Some(c) = (unsafe { comp_of(comp) }) else {
        return FC_STATUS_BAD_ARGUMENT;
    };
    // SAFETY: `volts` is non-NULL and points to 3 readable floats.
    let u = unsafe { volts.cast::<[f32; 3]>().read() };
    let out = c.compensate_dt(u, temp_c, dt_s);
    // SAFETY: `accel_g` is non-NULL and points to 3 writable floats.
    unsafe { accel_g.cast::<[f32; 3]>().write(out.accel) };
    u32::from(out.status.bits())
}

/// The sensor was powered on again `since_s` seconds before the next sample, while the
/// MCU kept the compensator (a power cycle of the sensor alone): the warm-up clock starts
/// again from the power-on; the lag, rate and hysteresis run on across the gap. (An MCU
/// that itself powered up calls `fc_compensator_init` instead.)
///
/// Returns `FC_OK`, `FC_ERR_NULL` or `FC_ERR_NOT_INITIALISED`.
///
/// # Safety
/// `comp` is NULL or points to `fc_compensator` storage, not used concurrently.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_power_on(comp: *mut fc_compensator, since_s: f32) -> i32 {
    if comp.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: non-NULL storage, not used concurrently (the contract).
    match unsafe { comp_of(comp) } {
        Some(c) => {
            c.power_on(since_s);
            FC_OK
        }
        None => FC_ERR_NOT_INITIALISED,
    }
}

/// Copy the id of the host-fit run that made the blob (16 bytes, all zero: none) to
/// `out[16]`.
///
/// Returns `FC_OK`, `FC_ERR_NULL` or `FC_ERR_NOT_INITIALISED` (blob not opened).
///
/// # Safety
/// `blob` is NULL or points to `fc_blob` storage; `out` is NULL or points to 16
/// writable bytes.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_blob_run_id(blob: *const fc_blob, out: *mut u8) -> i32 {
    if blob.is_null() || out.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: `blob` is non-NULL readable `fc_blob` storage (the contract).
    let Some(view) = (unsafe { view_of(blob) }) else {
        return FC_ERR_NOT_INITIALISED;
    };
    // SAFETY: `out` is non-NULL and points to 16 writable bytes (the contract).
    unsafe { out.cast::<[u8; RUN_ID_LEN]>().write(view.run_id().0) };
    FC_OK
}

/// Write the output unit of the blob's K and U0 (an `FC_UNIT_*` code) to `unit`.
///
/// Returns `FC_OK`, `FC_ERR_NULL` or `FC_ERR_NOT_INITIALISED` (blob not opened).
///
/// # Safety
/// `blob` is NULL or points to `fc_blob` storage; `unit` is NULL or points to a
/// writable byte.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_blob_output_unit(blob: *const fc_blob, unit: *mut u8) -> i32 {
    if blob.is_null() || unit.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: `blob` is non-NULL readable `fc_blob` storage (the contract).
    let Some(view) = (unsafe { view_of(blob) }) else {
        return FC_ERR_NOT_INITIALISED;
    };
    // SAFETY: `unit` is non-NULL and points to a writable byte (the contract).
    unsafe { unit.write(view.output_unit().code()) };
    FC_OK
}

/// Write the number of discovered terms the blob carries (0..=`FC_MAX_TERMS`) to
/// `count`.
///
/// Returns `FC_OK`, `FC_ERR_NULL` or `FC_ERR_NOT_INITIALISED` (blob not opened).
///
/// # Safety
/// `blob` is NULL or points to `fc_blob` storage; `count` is NULL or points to a
/// writable `uint32_t`.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_blob_term_count(blob: *const fc_blob, count: *mut u32) -> i32 {
    if blob.is_null() || count.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: `blob` is non-NULL readable `fc_blob` storage (the contract).
    let Some(view) = (unsafe { view_of(blob) }) else {
        return FC_ERR_NOT_INITIALISED;
    };
    let n = u32::try_from(view.term_count()).unwrap_or(u32::MAX);
    // SAFETY: `count` is non-NULL and points to a writable u32 (the contract).
    unsafe { count.write(n) };
    FC_OK
}

/// Copy discovered term `index` (0-based) of the blob to `term`, as the blob stores it
/// (validated when the blob was opened).
///
/// Returns `FC_OK`, `FC_ERR_NULL`, `FC_ERR_NOT_INITIALISED` (blob not opened) or
/// `FC_ERR_INDEX` (`index` at or past the count; then nothing is written).
///
/// # Safety
/// `blob` is NULL or points to `fc_blob` storage; `term` is NULL or points to writable
/// `fc_term` storage.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_blob_term(blob: *const fc_blob, index: u32, term: *mut fc_term) -> i32 {
    if blob.is_null() || term.is_null() {
        return FC_ERR_NULL;
    }
    // SAFETY: `blob` is non-NULL readable `fc_blob` storage (the contract).
    let Some(view) = (unsafe { view_of(blob) }) else {
        return FC_ERR_NOT_INITIALISED;
    };
    let j = usize::try_from(index).unwrap_or(usize::MAX);
    if j >= view.term_count() {
        return FC_ERR_INDEX;
    }
    let r = view.term_raw(j);
    let out = fc_term {
        axis: r.axis,
        factors: r.codes,
        tau_s: r.tau_s,
        coefficient: r.coefficient,
    };
    // SAFETY: `term` is non-NULL and points to writable `fc_term` storage (the contract).
    unsafe { term.write(out) };
    FC_OK
}

/// The format version a blob's header names (bytes 4..6), whatever its validity: to
/// report which version an `FC_ERR_UNSUPPORTED_VERSION` blob has. 0 when `bytes` is
/// NULL or shorter than 6 bytes.
///
/// # Safety
/// `bytes` is NULL or points to `len` readable bytes.
#[allow(unsafe_code)]
#[no_mangle]
pub unsafe extern "C" fn fc_blob_version(bytes: *const u8, len: usize) -> u16 {
    if bytes.is_null() {
        return 0;
    }
    // SAFETY: non-NULL, `len` readable bytes (the contract); only read here.
    let b = unsafe { core::slice::from_raw_parts(bytes, len) };
    match b.get(4..6) {
        Some([lo, hi]) => u16::from_le_bytes([*lo, *hi]),
        _ => 0,
    }
}

/// A panic cannot happen in firmware-core (no panicking code paths, clippy-denied);
/// on the MCU the staticlib still needs a handler, and it stops rather than unwind
/// into C. On the host the test binary's std provides one.
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}
