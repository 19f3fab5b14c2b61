//! Debian's rustc-web cross toolchain for the MCU target, with the matching library
//! sources for `-Zbuild-std=core`: downloaded with `apt-get download` and unpacked under
//! `target/cross-toolchain/` (cached: a second run does not download). The rustup
//! toolchain stays untouched for the host build. See ../shared/embedded/cross-build-notes.md.
use std::path::{Path, PathBuf};
use std::process::Command;

const PACKAGES: [&str; 13] = [
    "rustc-web",
    "cargo-web",
    "libstd-rust-web-1.96",
    "libstd-rust-web-dev",
    "rust-web-src",
    "rust-web-llvm",
    "libllvm22",
    "lld-22",
    "libgit2-1.5",
    "libhttp-parser2.9",
    "libmbedcrypto7",
    "libmbedtls14",
    "libmbedx509-1",
];
/// The MCU target.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// The unpacked toolchain (downloaded on first use).
pub fn toolchain() -> Result<PathBuf, String> {
    let dir = crate::root().join("target/cross-toolchain");
    let sysroot = dir.join("root");
    let stamp = dir.join("ok");
    if stamp.exists() && sysroot.join("usr/bin/rustc").exists() {
        return Ok(sysroot);
    }
    let debs = dir.join("debs");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&debs).map_err(|e| e.to_string())?;
    eprintln!(
        "xtask: downloading Debian's rustc-web toolchain (~150 MB) into {}",
        dir.display()
    );
    let download = || {
        crate::sh(
            Command::new("apt-get")
                .arg("download")
                .args(PACKAGES)
                .current_dir(&debs),
        )
    };
    if download().is_err() {
        // stale package lists (the security archive keeps only the newest build)
        crate::setup::apt_update()?;
        download().map_err(|e| {
            format!("{e}\n(apt-get download needs current package lists: `apt-get update` as root)")
        })?;
    }
    std::fs::create_dir_all(&sysroot).map_err(|e| e.to_string())?;
    for entry in std::fs::read_dir(&debs).map_err(|e| e.to_string())? {
        let deb = entry.map_err(|e| e.to_string())?.path();
        let name = deb
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.starts_with("rust-web-src") {
            // only the library sources build-std needs: 519 MB instead of 885 MB
            let script = format!(
                "dpkg-deb --fsys-tarfile '{}' | tar -x -C '{}' --wildcards './usr/lib/rustlib/src/rust' './usr/src/rustc-*/library/*'",
                deb.display(),
                sysroot.display()
            );
            crate::sh(Command::new("sh").arg("-c").arg(script))?;
        } else {
            crate::sh(Command::new("dpkg").arg("-x").arg(&deb).arg(&sysroot))?;
        }
    }
    let _ = std::fs::remove_dir_all(&debs);
    std::fs::write(&stamp, b"").map_err(|e| e.to_string())?;
    Ok(sysroot)
}

/// A command run with the cross toolchain first in PATH.
pub fn cross_cmd(sysroot: &Path, program: &str) -> Command {
    let mut c = Command::new(sysroot.join("usr/bin").join(program));
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut paths = vec![sysroot.join("usr/bin")];
    paths.extend(std::env::split_paths(&path));
    c.env("PATH", std::env::join_paths(paths).unwrap_or_default())
        .env("LD_LIBRARY_PATH", sysroot.join("usr/lib/x86_64-linux-gnu"))
        .env("RUSTC_BOOTSTRAP", "1")
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("CARGO")
        .env_remove("RUSTC")
        .env_remove("RUSTDOC");
    c
}
