//! The committed C header is what cbindgen generates from the current source: this test
//! fails when it is stale (`UPDATE_HEADER=1 cargo test -p firmware-core-ffi --test
//! header` rewrites it).
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::path::Path;

#[test]
fn header_is_current() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let bindings = cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).unwrap();
    let path = dir.join("include/firmware_core.h");
    if std::env::var_os("UPDATE_HEADER").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "{} is stale: regenerate it with `UPDATE_HEADER=1 cargo test -p firmware-core-ffi --test header`",
        path.display()
    );
}
