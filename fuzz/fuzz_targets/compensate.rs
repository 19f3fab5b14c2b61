//! A blob (the input's head, with a valid CRC so the content checks are reached, or the
//! example blob) and a sequence of samples: no panic, and every non-finite output is
//! flagged.
#![no_main]
use firmware_core::blob::{example_blob_bytes, Blob};
use firmware_core::compensate::{Compensator, ErrorModel, Method, Status};
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else { return };
    let (blob, samples) = if head & 1 == 0 {
        (Blob::decode(&example_blob_bytes()).ok(), rest)
    } else {
        let len = (usize::from(head) * 4).min(rest.len());
        (Blob::decode(&common::wrap(&rest[..len])).ok(), &rest[len..])
    };
    let Some(blob) = blob else { return };
    let method = match head >> 6 {
        0 | 1 => Method::CorrectConstants,
        2 => Method::CorrectResult(ErrorModel::Full),
        _ => Method::CorrectResult(ErrorModel::Simplified),
    };
    let Ok(mut c) = Compensator::new(&blob.calibration, method) else { return };
    for s in samples.chunks_exact(16) {
        let f = |k: usize| f32::from_le_bytes([s[4 * k], s[4 * k + 1], s[4 * k + 2], s[4 * k + 3]]);
        let o = c.compensate([f(0), f(1), f(2)], f(3));
        if !o.accel.iter().all(|v| v.is_finite()) {
            assert!(o.status.contains(Status::INPUT_NON_FINITE) || o.status.contains(Status::OUTPUT_NON_FINITE), "unflagged non-finite output");
            assert!(o.accel.iter().all(|v| v.is_nan()), "non-finite output must be NaN in all axes");
        }
    }
});
