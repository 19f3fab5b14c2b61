//! What the full test needs beyond the Rust toolchain, installed when missing: QEMU 10
//! from bookworm-backports, LLVM's nm/size, gcc, the Arm GNU toolchain (Debian's
//! gcc-arm-none-eabi, for the C harness), Debian's Chromium (the reports' browser
//! test), Debian's PostgreSQL server (the record store's tests), cargo-fuzz, mdbook (the
//! book). Installing with apt needs
//! root (CI runs as root); otherwise the message says what to install.
use std::process::Command;

fn ok(cmd: &mut Command) -> bool {
    cmd.output().map(|o| o.status.success()).unwrap_or(false)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

fn apt(args: &[&str]) -> Result<(), String> {
    let st = Command::new("apt-get")
        .args(args)
        .env("DEBIAN_FRONTEND", "noninteractive")
        .status()
        .map_err(|e| e.to_string())?;
    if st.success() {
        Ok(())
    } else {
        Err(format!("apt-get {args:?} failed"))
    }
}

/// Refresh the package lists (for `apt-get download` and installs).
pub fn apt_update() -> Result<(), String> {
    if !is_root() {
        return Err("apt-get update needs root".into());
    }
    apt(&["update", "-qq"])
}

/// qemu-system-arm 10 (bookworm-backports: plain bookworm's 7.2 would remove the
/// image's backports qemu-utils).
pub fn qemu() -> Result<(), String> {
    let have = Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).contains("version 1"))
        .unwrap_or(false);
    if have {
        return Ok(());
    }
    if !is_root() {
        return Err("qemu-system-arm 10 is missing: apt-get install -t bookworm-backports --no-install-recommends qemu-system-arm (as root)".into());
    }
    let listed = ok(Command::new("grep").args([
        "-rqs",
        "bookworm-backports",
        "/etc/apt/sources.list",
        "/etc/apt/sources.list.d/",
    ]));
    if !listed {
        std::fs::write(
            "/etc/apt/sources.list.d/bookworm-backports.list",
            "deb http://deb.debian.org/debian bookworm-backports main\n",
        )
        .map_err(|e| e.to_string())?;
    }
    apt_update()?;
    apt(&[
        "install",
        "-y",
        "-qq",
        "-t",
        "bookworm-backports",
        "--no-install-recommends",
        "qemu-system-arm",
    ])
}

/// llvm-nm / llvm-size and gcc.
pub fn tools() -> Result<(), String> {
    for (cmd, pkg) in [("llvm-nm", "llvm"), ("llvm-size", "llvm"), ("gcc", "gcc")] {
        if !ok(Command::new(cmd).arg("--version")) {
            if !is_root() {
                return Err(format!("{cmd} is missing: apt-get install {pkg}"));
            }
            apt(&["install", "-y", "-qq", "--no-install-recommends", pkg])?;
        }
    }
    Ok(())
}

/// arm-none-eabi-gcc (Debian's gcc-arm-none-eabi): the C harness of firmware-core-ffi.
/// No newlib: the harness brings its own start-up and semihosting output.
pub fn arm_gcc() -> Result<(), String> {
    if ok(Command::new("arm-none-eabi-gcc").arg("--version")) {
        return Ok(());
    }
    if !is_root() {
        return Err(
            "arm-none-eabi-gcc is missing: apt-get install gcc-arm-none-eabi (as root)".into(),
        );
    }
    let install = || {
        apt(&[
            "install",
            "-y",
            "-qq",
            "--no-install-recommends",
            "gcc-arm-none-eabi",
        ])
    };
    // the package lists of a fresh machine may be missing or stale
    install().or_else(|_| {
        apt_update()?;
        install()
    })
}

/// Where the reports' browser test (`tests/tests/reports_in_a_browser.rs`) looks for
/// Chromium.
pub const CHROMIUM: &str = "/usr/bin/chromium";

/// Debian's chromium (headless, for the reports' browser test) and the DejaVu fonts its
/// text is measured in.
pub fn chromium() -> Result<(), String> {
    if std::path::Path::new(CHROMIUM).exists() {
        return Ok(());
    }
    if !is_root() {
        return Err(format!(
            "{CHROMIUM} is missing: apt-get install chromium fonts-dejavu-core (as root)"
        ));
    }
    eprintln!("xtask: installing Debian's chromium (the reports' browser test)");
    let install = || {
        apt(&[
            "install",
            "-y",
            "-qq",
            "--no-install-recommends",
            "chromium",
            "fonts-dejavu-core",
        ])
    };
    // the package lists of a fresh machine may be missing or stale
    install().or_else(|_| {
        apt_update()?;
        install()
    })
}

/// Debian's PostgreSQL server (the record store's tests start a throwaway cluster of
/// it; no service is started for them).
pub fn postgresql() -> Result<(), String> {
    if crate::pgcluster::bindir().is_some() {
        return Ok(());
    }
    if !is_root() {
        return Err("PostgreSQL's server is missing: apt-get install postgresql (as root)".into());
    }
    eprintln!("xtask: installing Debian's postgresql (the record store's tests)");
    let install = || {
        apt(&[
            "install",
            "-y",
            "-qq",
            "--no-install-recommends",
            "postgresql",
        ])
    };
    install().or_else(|_| {
        apt_update()?;
        install()
    })?;
    crate::pgcluster::bindir()
        .map(|_| ())
        .ok_or_else(|| "postgresql installed, but no initdb under pg_config --bindir".into())
}

/// cargo-fuzz for the nightly toolchain (from crates.io).
pub fn cargo_fuzz() -> Result<(), String> {
    if !ok(Command::new("cargo").args(["+nightly", "--version"])) {
        eprintln!("xtask: installing the nightly toolchain (rustup, minimal profile) for fuzzing");
        let st = Command::new("rustup")
            .args(["toolchain", "install", "nightly", "--profile", "minimal"])
            .status()
            .map_err(|e| format!("rustup: {e}"))?;
        if !st.success() {
            return Err("rustup toolchain install nightly failed".into());
        }
    }
    if ok(Command::new("cargo").args(["+nightly", "fuzz", "--version"])) {
        return Ok(());
    }
    eprintln!("xtask: installing cargo-fuzz from crates.io");
    let st = Command::new("cargo")
        .args(["install", "cargo-fuzz", "--locked"])
        .status()
        .map_err(|e| e.to_string())?;
    if st.success() {
        Ok(())
    } else {
        Err("cargo install cargo-fuzz failed".into())
    }
}

/// What `cargo install` builds of mdbook: the pinned version with the search index only.
/// Its default features add `serve` and `watch` (a web server on tokio and axum, a file
/// watcher) that a build of the book never runs; leaving them out takes about two
/// minutes off a fresh machine's first run.
const MDBOOK_INSTALL: [&str; 8] = [
    "install",
    "mdbook",
    "--locked",
    "--version",
    "0.5.4",
    "--no-default-features",
    "--features",
    "search",
];

/// mdbook (from crates.io), which builds the book under docs/.
pub fn mdbook() -> Result<(), String> {
    if ok(Command::new("mdbook").arg("--version")) {
        return Ok(());
    }
    eprintln!("xtask: installing mdbook from crates.io (a minute or two of build, once)");
    let st = Command::new("cargo")
        .args(MDBOOK_INSTALL)
        .status()
        .map_err(|e| e.to_string())?;
    if !st.success() {
        return Err(format!("cargo {} failed", MDBOOK_INSTALL.join(" ")));
    }
    if ok(Command::new("mdbook").arg("--version")) {
        Ok(())
    } else {
        Err("mdbook was installed but is not on PATH: add cargo's bin folder (~/.cargo/bin)".into())
    }
}
