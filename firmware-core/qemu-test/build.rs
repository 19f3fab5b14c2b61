//! Puts memory.x where the linker finds it; the blob and the input table come from
//! `cargo xtask embedded` through FW_TEST_BLOB and FW_TEST_INPUTS.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
    std::fs::write(out.join("memory.x"), include_bytes!("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory.x");
    for v in ["FW_TEST_BLOB", "FW_TEST_BLOB_PHYS", "FW_TEST_INPUTS"] {
        println!("cargo:rerun-if-env-changed={v}");
        if let Some(p) = std::env::var_os(v) {
            println!("cargo:rerun-if-changed={}", PathBuf::from(p).display());
        }
    }
}
