//! The compensator at its edges: any f32 bit pattern for the voltages, the
//! temperature and the time step, with and without the physics terms and discovered
//! terms, never panics and never yields a non-finite acceleration without a flag; blobs
//! round-trip and every bit flip is caught.
mod common;

use firmware_core::blob::{
    example_physics, example_terms, Blob, BlobView, OutputUnit, RunId, FORMAT_VERSION, MAGIC,
    MAX_BLOB_LEN, OLDEST_FORMAT_VERSION,
};
use firmware_core::compensate::{Compensator, ErrorModel, Method, Status};
use firmware_core::temperature::{Calibration, TempModel};
use firmware_core::terms::TermList;
use proptest::prelude::*;

/// Any f32: normal values of every size, subnormals, zeros, infinities and NaNs.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>().prop_map(f32::from_bits),
        -100.0f32..100.0,
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(1e-40f32),
        Just(3e38f32),
    ]
}

/// The first `n` of the example's discovered terms (0: none).
fn terms(n: usize) -> TermList<f32> {
    example_terms().into_iter().take(n).collect()
}

const METHODS: [Method; 3] = [
    Method::CorrectConstants,
    Method::CorrectResult(ErrorModel::Full),
    Method::CorrectResult(ErrorModel::Simplified),
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn no_input_sequence_gives_an_unflagged_non_finite_output(
        cal in common::unit(), phys in any::<bool>(), n_terms in 0usize..=8, m in 0usize..3,
        seq in prop::collection::vec((prop::array::uniform3(any_f32()), any_f32(), any_f32()), 1..40)) {
        let mut cal: Calibration<f32> = cal;
        let terms = terms(n_terms);
        if n_terms > 0 && !cfg!(feature = "terms") {
            // never compensated without its terms
            prop_assert_eq!(
                Compensator::with_terms(&cal, &terms, METHODS[m], 0.01).err(),
                Some(firmware_core::Error::TermsNotBuiltIn)
            );
            return Ok(());
        }
        if phys {
            cal.physics = Some(example_physics());
            if !cfg!(feature = "physics") {
                prop_assert_eq!(
                    Compensator::new(&cal, METHODS[m], 0.01).err(),
                    Some(firmware_core::Error::PhysicsNotBuiltIn)
                );
                return Ok(());
            }
        }
        let mut c = Compensator::with_terms(&cal, &terms, METHODS[m], 0.01).unwrap();
        for (u, t, dt) in seq {
            // half the samples on their own time step, any bits
            let o = if dt.to_bits() & 1 == 0 { c.compensate(u, t) } else { c.compensate_dt(u, t, dt) };
            let bad_dt = dt.to_bits() & 1 == 1 && !(dt >= 0.0 && dt.is_finite());
            prop_assert_eq!(o.status.contains(Status::BAD_TIME_STEP), bad_dt);
            let finite = o.accel.iter().all(|v| v.is_finite());
            if !finite {
                prop_assert!(o.status.contains(Status::INPUT_NON_FINITE) || o.status.contains(Status::OUTPUT_NON_FINITE));
                prop_assert!(o.accel.iter().all(|v| v.to_bits() == f32::NAN.to_bits()), "one canonical NaN");
            }
            if !u.iter().all(|v| v.is_finite()) {
                prop_assert!(o.status.contains(Status::INPUT_NON_FINITE));
            }
            if !t.is_finite() {
                prop_assert!(o.status.contains(Status::TEMP_NON_FINITE));
            }
            // a good sample after any history is compensated normally
            let g = c.compensate([0.0045, -0.0044, -0.5521], 20.0);
            prop_assert!(g.accel.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn decode_of_encode_is_identity_and_flips_are_caught(cal in common::unit(), poly in any::<bool>(),
            with_phys in any::<bool>(), n_terms in 0usize..=8, flip in any::<prop::sample::Index>()) {
        let mut cal: Calibration<f32> = cal;
        if poly {
            let t0 = cal.at_t0();
            cal.model = TempModel::Poly { terms: [t0, [1e-5; 12], [-2e-7; 12]].into_iter().collect() };
        }
        if with_phys {
            cal.physics = Some(example_physics());
        }
        let mut serial = heapless::String::new();
        serial.push_str("UNIT-7").unwrap();
        let blob = Blob { serial, output_unit: OutputUnit::Counts, run_id: RunId([7; 16]), calibration: cal, terms: terms(n_terms) };
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = blob.encode(&mut buf).unwrap();
        prop_assert_eq!(buf[4], if n_terms > 0 { 5 } else { 4 });
        if n_terms > 0 && !cfg!(feature = "terms") {
            // refused when opened, never half-applied
            prop_assert_eq!(Blob::decode(&buf[..n]).err(), Some(firmware_core::Error::TermsNotBuiltIn));
            return Ok(());
        }
        prop_assert_eq!(Blob::decode(&buf[..n]).unwrap(), blob);
        let bit = flip.index(n * 8);
        let mut bad = buf[..n].to_vec();
        bad[bit / 8] ^= 1 << (bit % 8);
        prop_assert_eq!(Blob::decode(&bad).err(), Some(firmware_core::Error::CrcMismatch));
    }

    /// The compensator reading the blob's bytes in place and the one over the owned f32
    /// calibration give the same bits for any input sequence, physics terms included:
    /// the host's f32 evaluation is the firmware's.
    #[test]
    fn flash_and_owned_calibrations_agree_bit_for_bit(cal in common::unit(), poly in any::<bool>(),
            with_phys in any::<bool>(), n_terms in 0usize..=8, m in 0usize..3,
            seq in prop::collection::vec((prop::array::uniform3(any_f32()), any_f32(), any_f32()), 1..40)) {
        let mut cal: Calibration<f32> = cal;
        if poly {
            let t0 = cal.at_t0();
            cal.model = TempModel::Poly { terms: [t0, [1e-5; 12], [-2e-7; 12]].into_iter().collect() };
        }
        cal.update_step_c = 0.25;
        if with_phys && cfg!(feature = "physics") {
            cal.physics = Some(example_physics());
        }
        let terms = if cfg!(feature = "terms") { terms(n_terms) } else { TermList::new() };
        let blob = Blob { serial: heapless::String::new(), output_unit: OutputUnit::Unstated, run_id: RunId::NONE, calibration: cal, terms };
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = blob.encode(&mut buf).unwrap();
        let view = BlobView::new(&buf[..n]).unwrap();
        let mut flash = Compensator::from_blob(view, METHODS[m], 0.01).unwrap();
        let mut owned = Compensator::with_terms(&blob.calibration, &blob.terms, METHODS[m], 0.01).unwrap();
        for (u, t, dt) in seq {
            let (a, b) = (flash.compensate_dt(u, t, dt), owned.compensate_dt(u, t, dt));
            prop_assert_eq!(a.accel.map(f32::to_bits), b.accel.map(f32::to_bits));
            prop_assert_eq!(a.status, b.status);
        }
    }
}

/// `content` behind a valid magic, version, length and CRC, as the fuzz target
/// `blob_decode` wraps its input (fuzz/fuzz_targets/common.rs), so a crash input the
/// fuzzer found replays here byte for byte.
fn wrap_like_the_fuzzer(content: &[u8]) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    let terms = content.get(2).is_some_and(|f| f & 2 != 0);
    let version = if terms {
        FORMAT_VERSION
    } else {
        OLDEST_FORMAT_VERSION
    };
    b.extend_from_slice(&version.to_le_bytes());
    let n = u16::try_from(10 + content.len() + 4).unwrap_or(u16::MAX);
    b.extend_from_slice(&n.to_le_bytes());
    b.extend_from_slice(&(!n).to_le_bytes());
    b.extend_from_slice(content);
    let c = firmware_core::crc::crc32(&b);
    b.extend_from_slice(&c.to_le_bytes());
    b
}

/// Every input the fuzzer once crashed on (tests/data/fuzz-crash-*.bin) now either fails
/// validation or re-encodes to the very same bytes and reads the same both ways.
#[test]
fn fuzz_crash_inputs_are_canonical_or_refused() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut seen = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if !name.starts_with("fuzz-crash-") {
            continue;
        }
        seen += 1;
        let data = std::fs::read(&p).unwrap();
        let bytes = if data.starts_with(&MAGIC) {
            data
        } else {
            wrap_like_the_fuzzer(&data)
        };
        if let Ok(v) = BlobView::new(&bytes) {
            let b = v.to_blob();
            assert_eq!(b.validate(), Ok(()), "{name}");
            let mut buf = [0u8; MAX_BLOB_LEN];
            let n = b.encode(&mut buf).unwrap();
            assert_eq!(&buf[..n], &bytes[..], "{name}: encode(decode(b)) != b");
            assert_eq!(Blob::decode(&bytes).as_ref(), Ok(&b), "{name}");
        }
    }
    assert!(seen > 0, "no fuzz-crash-*.bin under {}", dir.display());
}
