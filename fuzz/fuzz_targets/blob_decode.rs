//! Any bytes: decode never panics, and whatever decodes encodes and decodes back to the
//! same blob. Input that does not start with the magic is taken as blob content and
//! wrapped in a header and a valid CRC, so the content checks (table sizes, breakpoints,
//! finiteness, ranges, physics terms) are fuzzed and not only the CRC.
#![no_main]
use firmware_core::blob::{Blob, FORMAT_VERSION, MAGIC, MAX_BLOB_LEN};
use libfuzzer_sys::fuzz_target;

fn crc32(data: &[u8]) -> u32 {
    let mut c = !0u32;
    for &x in data {
        c ^= u32::from(x);
        for _ in 0..8 {
            c = if c & 1 != 0 { (c >> 1) ^ 0xEDB8_8320 } else { c >> 1 };
        }
    }
    !c
}

fuzz_target!(|data: &[u8]| {
    let wrapped;
    let bytes = if data.starts_with(&MAGIC) {
        data
    } else {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        b.extend_from_slice(data);
        let c = crc32(&b);
        b.extend_from_slice(&c.to_le_bytes());
        wrapped = b;
        &wrapped[..]
    };
    if let Ok(b) = Blob::decode(bytes) {
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).expect("a decoded blob encodes");
        // equal as blobs; the bytes may differ (postcard accepts over-long varints)
        assert_eq!(Blob::decode(&buf[..n]).as_ref(), Ok(&b), "decode(encode(b)) != b");
    }
});
