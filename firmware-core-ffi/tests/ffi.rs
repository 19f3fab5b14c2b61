//! The C interface called as C calls it: the same bits as the Rust API, every refusal a
//! status code, NULL and uninitialised storage refused without a crash.
#![allow(unsafe_code)]
// Test code: unwraps and indexing fail the test, one block holds several FFI calls.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::multiple_unsafe_ops_per_block
)]
use firmware_core::blob::{example_blob, example_physics, example_terms, BlobView, MAX_BLOB_LEN};
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core_ffi::*;
use std::mem::MaybeUninit;

fn blob_bytes(physics: bool) -> &'static [u8] {
    blob_with(physics, false)
}

/// The example blob, with physics terms and with the example's 8 discovered terms.
fn blob_with(physics: bool, terms: bool) -> &'static [u8] {
    let mut b = example_blob();
    if physics {
        b.calibration.physics = Some(example_physics());
    }
    if terms {
        b.terms = example_terms();
    }
    let mut buf = vec![0u8; MAX_BLOB_LEN];
    let n = b.encode(&mut buf).unwrap();
    buf.truncate(n);
    buf.leak()
}

fn open(bytes: &'static [u8]) -> Result<Box<fc_blob>, i32> {
    let mut blob = Box::new(MaybeUninit::<fc_blob>::zeroed());
    // SAFETY: valid storage and `len` readable bytes that live for 'static.
    let rc = unsafe { fc_blob_open(blob.as_mut_ptr(), bytes.as_ptr(), bytes.len()) };
    // SAFETY: zeroed storage is a valid fc_blob (plain u64 words).
    let blob = unsafe { blob.assume_init() };
    if rc == FC_OK {
        Ok(blob)
    } else {
        Err(rc)
    }
}

fn init(blob: &fc_blob, m: u32) -> Result<Box<fc_compensator>, i32> {
    init_at(blob, m, PERIOD)
}

/// The sample period the tests' compensators are made with, s (100 Hz).
const PERIOD: f32 = 0.01;

fn init_at(blob: &fc_blob, m: u32, period: f32) -> Result<Box<fc_compensator>, i32> {
    let mut comp = Box::new(MaybeUninit::<fc_compensator>::zeroed());
    // SAFETY: valid storage for both.
    let rc = unsafe { fc_compensator_init(comp.as_mut_ptr(), blob, m, period) };
    // SAFETY: zeroed storage is a valid fc_compensator.
    let comp = unsafe { comp.assume_init() };
    if rc == FC_OK {
        Ok(comp)
    } else {
        Err(rc)
    }
}

#[test]
fn c_results_are_the_rust_results_bit_for_bit() {
    for (physics, terms) in [(false, false), (true, false), (true, true), (false, true)] {
        let bytes = blob_with(physics, terms);
        let blob = open(bytes).unwrap();
        for (id, m) in [
            (FC_METHOD_CONSTANTS, Method::CorrectConstants),
            (
                FC_METHOD_RESULT_FULL,
                Method::CorrectResult(ErrorModel::Full),
            ),
            (
                FC_METHOD_RESULT_SIMPLIFIED,
                Method::CorrectResult(ErrorModel::Simplified),
            ),
        ] {
            let mut comp = init(&blob, id).unwrap();
            let mut rust =
                Compensator::from_blob(BlobView::new(bytes).unwrap(), m, PERIOD).unwrap();
            for k in 0..400 {
                let t = -50.0 + 0.35 * k as f32;
                let u = [0.0045 + 1e-4 * k as f32, -0.0044, -0.5521];
                let u = if k == 17 { [f32::NAN, 0.0, 0.0] } else { u };
                let mut a = [0f32; 3];
                // every third sample on its own time step (0.3 s; a negative one at 101),
                // one power cycle of the sensor at 250
                let dt = if k == 101 { -1.0 } else { 0.3 };
                if k == 250 {
                    // SAFETY: initialised storage.
                    assert_eq!(unsafe { fc_power_on(&mut *comp, 0.2) }, FC_OK);
                    rust.power_on(0.2);
                }
                let (st, r) = if k % 3 == 2 {
                    // SAFETY: initialised storage, 3 floats in and out.
                    let st =
                        unsafe { fc_compensate_dt(&mut *comp, u.as_ptr(), t, dt, a.as_mut_ptr()) };
                    (st, rust.compensate_dt(u, t, dt))
                } else {
                    // SAFETY: initialised storage, 3 floats in and out.
                    let st = unsafe { fc_compensate(&mut *comp, u.as_ptr(), t, a.as_mut_ptr()) };
                    (st, rust.compensate(u, t))
                };
                assert_eq!(
                    a.map(f32::to_bits),
                    r.accel.map(f32::to_bits),
                    "{physics} {terms} {id} {k}"
                );
                assert_eq!(st, u32::from(r.status.bits()));
            }
        }
    }
}

fn unhex(text: &str) -> &'static [u8] {
    let digits: Vec<u8> = text.bytes().filter(u8::is_ascii_hexdigit).collect();
    let bytes: Vec<u8> = digits
        .chunks(2)
        .map(|p| u8::from_str_radix(std::str::from_utf8(p).unwrap(), 16).unwrap())
        .collect();
    bytes.leak()
}

/// The blob's run id and output unit, copied out through the C interface.
#[test]
fn run_id_and_output_unit_are_read_from_c() {
    let bytes = unhex(include_str!(
        "../../firmware-core/tests/data/example_blob_physics.hex"
    ));
    let blob = open(bytes).unwrap();
    let mut id = [0u8; FC_RUN_ID_LEN];
    let mut unit = 0xFFu8;
    // SAFETY: opened storage; 16 writable bytes; one writable byte.
    unsafe {
        assert_eq!(fc_blob_run_id(&*blob, id.as_mut_ptr()), FC_OK);
        assert_eq!(fc_blob_output_unit(&*blob, &mut unit), FC_OK);
        assert_eq!(fc_blob_run_id(&*blob, std::ptr::null_mut()), FC_ERR_NULL);
        let never = MaybeUninit::<fc_blob>::zeroed().assume_init();
        assert_eq!(
            fc_blob_output_unit(&never, &mut unit),
            FC_ERR_NOT_INITIALISED
        );
    }
    assert_eq!(
        id,
        BlobView::new(bytes).unwrap().run_id().0,
        "the committed blob's run id"
    );
    assert_eq!(id[0], 0xa1);
    assert_eq!(unit, FC_UNIT_M_S2);
}

/// The discovered terms read from C as the blob stores them; an index past the table
/// refused.
#[test]
fn discovered_terms_are_read_from_c() {
    let blob = open(blob_with(true, true)).unwrap();
    let mut n = 0u32;
    let mut t = fc_term {
        axis: 9,
        factors: [9; 3],
        tau_s: -1.0,
        coefficient: -1.0,
    };
    // SAFETY: opened storage; a writable u32 and fc_term.
    unsafe {
        assert_eq!(fc_blob_term_count(&*blob, &mut n), FC_OK);
        assert_eq!(n, FC_MAX_TERMS);
        for (i, e) in example_terms().iter().enumerate() {
            assert_eq!(fc_blob_term(&*blob, i as u32, &mut t), FC_OK);
            assert_eq!(t.axis, e.axis as u8);
            assert_eq!(t.factors, e.term.codes());
            assert_eq!(t.tau_s, e.term.tau_s());
            assert_eq!(t.coefficient, e.coefficient);
        }
        let before = t;
        assert_eq!(fc_blob_term(&*blob, n, &mut t), FC_ERR_INDEX);
        assert_eq!(t, before, "nothing written");
        assert_eq!(fc_blob_term(&*blob, 0, std::ptr::null_mut()), FC_ERR_NULL);
        // dT*decay(power_on,20min) on z, entry 5
        assert_eq!(fc_blob_term(&*blob, 5, &mut t), FC_OK);
        assert_eq!(
            (t.axis, t.factors, t.tau_s),
            (
                2,
                [FC_FACTOR_DT, FC_FACTOR_DECAY_POWER_ON, FC_FACTOR_NONE],
                1200.0
            )
        );
        let plain = open(blob_bytes(false)).unwrap();
        assert_eq!(fc_blob_term_count(&*plain, &mut n), FC_OK);
        assert_eq!(n, 0);
        let never = MaybeUninit::<fc_blob>::zeroed().assume_init();
        assert_eq!(fc_blob_term_count(&never, &mut n), FC_ERR_NOT_INITIALISED);
    }
}

/// A term table that is not valid, behind a valid CRC: each failure its own code.
#[test]
fn bad_term_tables_are_refused_with_their_codes() {
    let good = blob_with(false, true).to_vec();
    let head = good.len() - 4 - 4 - 8 * 12;
    let reseal = |mut b: Vec<u8>| -> &'static [u8] {
        let n = b.len() - 4;
        let c = firmware_core::crc::crc32(&b[..n]);
        b[n..].copy_from_slice(&c.to_le_bytes());
        b.leak()
    };
    let edit = |at: usize, v: u8| {
        let mut b = good.clone();
        b[at] = v;
        open(reseal(b)).err()
    };
    assert_eq!(edit(head, 9), Some(FC_ERR_TOO_MANY_TERMS));
    assert_eq!(edit(head + 4, 3), Some(FC_ERR_TERM_AXIS));
    assert_eq!(edit(head + 5, 10), Some(FC_ERR_TERM_FACTORS));
    // the decay of entry 6 given no time constant
    let mut b = good.clone();
    b[head + 4 + 72 + 4..head + 4 + 72 + 8].copy_from_slice(&0f32.to_le_bytes());
    assert_eq!(open(reseal(b)).err(), Some(FC_ERR_TERM_TIME_CONSTANT));
    let mut b = good.clone();
    b.copy_within(head + 4..head + 16, head + 4 + 36);
    assert_eq!(open(reseal(b)).err(), Some(FC_ERR_DUPLICATE_TERM));
}

#[test]
fn refusals_are_status_codes() {
    let good = blob_bytes(false);
    assert_eq!(open(&good[..good.len() - 1]).err(), Some(FC_ERR_TRUNCATED));
    let mut bad = good.to_vec();
    bad[4] ^= 1; // the version byte: corruption, not an old version
    assert_eq!(open(bad.leak()).err(), Some(FC_ERR_CRC));
    let v2 = include_str!("../../firmware-core/tests/data/example_blob_v2.hex");
    let v2: Vec<u8> = v2
        .lines()
        .flat_map(|l| {
            (0..l.len())
                .step_by(2)
                .map(move |i| u8::from_str_radix(&l[i..i + 2], 16).unwrap())
        })
        .collect();
    let v2: &'static [u8] = v2.leak();
    assert_eq!(open(v2).err(), Some(FC_ERR_UNSUPPORTED_VERSION));
    // SAFETY: a readable slice.
    assert_eq!(unsafe { fc_blob_version(v2.as_ptr(), v2.len()) }, 2);
    let v3 = unhex(include_str!(
        "../../firmware-core/tests/data/example_blob_v3.hex"
    ));
    assert_eq!(open(v3).err(), Some(FC_ERR_UNSUPPORTED_VERSION));
    // SAFETY: a readable slice.
    assert_eq!(unsafe { fc_blob_version(v3.as_ptr(), v3.len()) }, 3);
    let blob = open(good).unwrap();
    assert_eq!(init(&blob, 7).err(), Some(FC_ERR_BAD_METHOD));
    for bad in [0.0, -0.01, f32::NAN, f32::INFINITY] {
        assert_eq!(
            init_at(&blob, FC_METHOD_CONSTANTS, bad).err(),
            Some(FC_ERR_BAD_SAMPLE_PERIOD)
        );
    }
    // the library is built with physics (firmware-core's default): a physics blob runs
    assert!(init(&open(blob_bytes(true)).unwrap(), FC_METHOD_CONSTANTS).is_ok());
}

#[test]
fn null_and_uninitialised_storage_are_refused() {
    let good = blob_bytes(false);
    let mut a = [0f32; 3];
    let u = [0f32; 3];
    // SAFETY: NULL pointers and zeroed (never opened) storage, as the contract allows.
    unsafe {
        assert_eq!(
            fc_blob_open(std::ptr::null_mut(), good.as_ptr(), good.len()),
            FC_ERR_NULL
        );
        let mut blob = MaybeUninit::<fc_blob>::zeroed().assume_init();
        assert_eq!(fc_blob_open(&mut blob, std::ptr::null(), 0), FC_ERR_NULL);
        let mut comp = MaybeUninit::<fc_compensator>::zeroed().assume_init();
        assert_eq!(
            fc_compensator_init(&mut comp, &blob, 0, PERIOD),
            FC_ERR_NOT_INITIALISED
        );
        assert_eq!(
            fc_compensator_init(&mut comp, std::ptr::null(), 0, PERIOD),
            FC_ERR_NULL
        );
        assert_eq!(
            fc_compensate_dt(&mut comp, u.as_ptr(), 20.0, 0.1, a.as_mut_ptr()),
            FC_STATUS_BAD_ARGUMENT
        );
        assert_eq!(fc_power_on(&mut comp, 0.0), FC_ERR_NOT_INITIALISED);
        assert_eq!(fc_power_on(std::ptr::null_mut(), 0.0), FC_ERR_NULL);
        assert_eq!(
            fc_compensate(&mut comp, u.as_ptr(), 20.0, a.as_mut_ptr()),
            FC_STATUS_BAD_ARGUMENT
        );
        assert_eq!(
            fc_compensate(std::ptr::null_mut(), u.as_ptr(), 20.0, a.as_mut_ptr()),
            FC_STATUS_BAD_ARGUMENT
        );
        assert_eq!(fc_set_method(&mut comp, 1), FC_ERR_NOT_INITIALISED);
        assert_eq!(fc_blob_version(std::ptr::null(), 0), 0);
    }
    let blob = open(good).unwrap();
    let mut comp = init(&blob, FC_METHOD_CONSTANTS).unwrap();
    // SAFETY: initialised storage.
    unsafe {
        assert_eq!(fc_set_method(&mut *comp, FC_METHOD_RESULT_FULL), FC_OK);
        assert_eq!(fc_set_method(&mut *comp, 9), FC_ERR_BAD_METHOD);
        assert_eq!(
            fc_compensate(&mut *comp, std::ptr::null(), 20.0, a.as_mut_ptr()),
            FC_STATUS_BAD_ARGUMENT
        );
        assert_eq!(
            fc_compensate(
                &mut *comp,
                [0.0045, -0.0044, -0.5521].as_ptr(),
                20.0,
                a.as_mut_ptr()
            ),
            0
        );
        assert_eq!(
            fc_compensate_dt(
                &mut *comp,
                [0.0045, -0.0044, -0.5521].as_ptr(),
                20.0,
                f32::NAN,
                a.as_mut_ptr()
            ),
            FC_STATUS_BAD_TIME_STEP
        );
    }
    assert!((a[2] - 1.0).abs() < 0.01);
}
