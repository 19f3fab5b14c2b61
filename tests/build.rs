//! The key of the shared demo fixture (`tests::demo`): a hash of every source the demo's
//! output depends on, so that the test binaries of one build share one demo run and a
//! changed source never reads a stale one.
use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default()).join("..");
    let mut all = Vec::new();
    for dir in ["host-fit/src", "firmware-core/src"] {
        println!("cargo:rerun-if-changed=../{dir}");
        files(&root.join(dir), &mut all);
    }
    for f in [
        "Cargo.lock",
        "host-fit/Cargo.toml",
        "firmware-core/Cargo.toml",
    ] {
        println!("cargo:rerun-if-changed=../{f}");
        all.push(root.join(f));
    }
    all.sort();
    // FNV-1a, 64 bits: stable across toolchains, unlike std's hasher
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in &all {
        let name = p
            .strip_prefix(&root)
            .unwrap_or(p)
            .to_string_lossy()
            .into_owned();
        for b in name.bytes().chain(std::fs::read(p).unwrap_or_default()) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    println!("cargo:rustc-env=DEMO_FIXTURE_KEY={h:016x}");
}
