//! Any bytes: validation never panics, and whatever validates re-encodes to the very
//! same bytes (formats 4 and 5 are canonical: a blob's version follows from whether it
//! has discovered terms) and reads the same through the view and the owned form. Input
//! that does not start with the magic is taken as header fields and content and wrapped
//! in a valid magic, version, length and CRC, so the checks behind the CRC (layout,
//! table sizes, breakpoints, finiteness, ranges, physics terms, the table of discovered
//! terms) are fuzzed.
#![no_main]
use firmware_core::blob::{Blob, BlobView, MAGIC, MAX_BLOB_LEN};
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
    let _ = BlobView::from_region(bytes);
    if let Ok(v) = BlobView::new(bytes) {
        let b = v.to_blob();
        assert_eq!(b.validate(), Ok(()), "a validated blob's owned form is valid");
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).expect("a validated blob encodes");
        assert_eq!(&buf[..n], bytes, "encode(decode(b)) != b");
        assert_eq!(Blob::decode(bytes).as_ref(), Ok(&b));
        assert_eq!(b.terms.len(), firmware_core::temperature::Source::term_count(&v));
        assert_eq!(v.version(), b.version());
    }
});
