//! Any bytes: decode never panics, and whatever decodes encodes and decodes back to the
//! same blob. Input that does not start with the magic is taken as blob content and
//! wrapped in a header and a valid CRC, so the content checks (table sizes, breakpoints,
//! finiteness, ranges, physics terms) are fuzzed and not only the CRC.
#![no_main]
use firmware_core::blob::{Blob, MAGIC, MAX_BLOB_LEN};
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let wrapped;
    let bytes = if data.starts_with(&MAGIC) {
        data
    } else {
        wrapped = common::wrap(data);
        &wrapped[..]
    };
    if let Ok(b) = Blob::decode(bytes) {
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).expect("a decoded blob encodes");
        // equal as blobs; the bytes may differ (postcard accepts over-long varints)
        assert_eq!(Blob::decode(&buf[..n]).as_ref(), Ok(&b), "decode(encode(b)) != b");
    }
});
