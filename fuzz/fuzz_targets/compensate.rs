//! A blob (the input's head, wrapped with a valid header and CRC so the content checks
//! are reached, or the example blob, with physics terms and discovered terms when the
//! head's bit 1 is set) and a sequence of samples, each with its own time step: no
//! panic, every non-finite output flagged, and the compensator reading the blob in place
//! gives the same bits as the one over the owned f32 calibration and terms (the host's
//! evaluation).
#![no_main]
use firmware_core::blob::{example_blob, example_blob_bytes, example_physics, example_terms, BlobView, MAX_BLOB_LEN};
use firmware_core::compensate::{Compensator, ErrorModel, Method, Status};
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else { return };
    let (bytes, samples) = if head & 3 == 0 {
        (example_blob_bytes().to_vec(), rest)
    } else if head & 1 == 0 {
        // the example with physics terms and a full table of discovered terms
        let mut b = example_blob();
        b.calibration.physics = Some(example_physics());
        b.terms = example_terms();
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).expect("the example encodes");
        (buf[..n].to_vec(), rest)
    } else {
        let len = (usize::from(head) * 4).min(rest.len());
        (common::wrap(&rest[..len]), &rest[len..])
    };
    let Ok(view) = BlobView::new(&bytes) else { return };
    let owned = view.to_blob();
    let method = match head >> 6 {
        0 | 1 => Method::CorrectConstants,
        2 => Method::CorrectResult(ErrorModel::Full),
        _ => Method::CorrectResult(ErrorModel::Simplified),
    };
    let Ok(mut c) = Compensator::from_blob(view, method, 0.01) else { return };
    let mut h = Compensator::with_terms(&owned.calibration, &owned.terms, method, 0.01)
        .expect("the owned form is accepted too");
    // ux uy uz temp dt: every sample on its own time step (any bits)
    for s in samples.chunks_exact(20) {
        let f = |k: usize| f32::from_le_bytes([s[4 * k], s[4 * k + 1], s[4 * k + 2], s[4 * k + 3]]);
        let o = c.compensate_dt([f(0), f(1), f(2)], f(3), f(4));
        let r = h.compensate_dt([f(0), f(1), f(2)], f(3), f(4));
        assert_eq!(o.accel.map(f32::to_bits), r.accel.map(f32::to_bits), "flash and owned differ");
        assert_eq!(o.status, r.status);
        if !o.accel.iter().all(|v| v.is_finite()) {
            assert!(o.status.contains(Status::INPUT_NON_FINITE) || o.status.contains(Status::OUTPUT_NON_FINITE), "unflagged non-finite output");
            assert!(o.accel.iter().all(|v| v.is_nan()), "non-finite output must be NaN in all axes");
        }
    }
});
