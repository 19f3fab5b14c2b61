//! Any bytes: decode never panics; whatever decodes re-encodes to the same bytes.
#![no_main]
use firmware_core::blob::{Blob, MAX_BLOB_LEN};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(b) = Blob::decode(data) {
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).expect("a decoded blob encodes");
        assert_eq!(&buf[..n], data, "decode(bytes) re-encodes to other bytes");
    }
});
