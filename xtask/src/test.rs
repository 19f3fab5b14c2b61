//! `cargo xtask test`: everything, in this order: fmt, clippy, the no_std build and
//! tests, the workspace's tests (Chromium installed first for the reports' browser
//! test), the thumb cross builds, the firmware under QEMU, a fuzz smoke run per target.
use crate::Steps;
use std::process::Command;

/// `cargo ARGS` in the repository root.
fn cargo(args: &[&str]) -> Command {
    let mut c = crate::cargo();
    c.args(args);
    c
}

/// `cargo xtask test`.
pub fn test(s: &mut Steps) {
    s.run("fmt", cargo(&["fmt", "--all", "--", "--check"]));
    s.run(
        "clippy (workspace)",
        cargo(&[
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ]),
    );
    s.run(
        "clippy (firmware-core, no default features)",
        cargo(&[
            "clippy",
            "-p",
            "firmware-core",
            "--no-default-features",
            "--",
            "-D",
            "warnings",
        ]),
    );
    s.run(
        "build firmware-core alone, no default features",
        cargo(&["build", "-p", "firmware-core", "--no-default-features"]),
    );
    s.run(
        "tests (firmware-core without the physics feature)",
        cargo(&[
            "test",
            "-p",
            "firmware-core",
            "--no-default-features",
            "--release",
        ]),
    );
    s.run(
        "tests (firmware-core with physics, without the terms feature)",
        cargo(&[
            "test",
            "-p",
            "firmware-core",
            "--no-default-features",
            "--features",
            "physics",
            "--release",
        ]),
    );
    // the reports' browser test needs Chromium: it fails (not skips) without it
    s.prepare("install chromium", crate::setup::chromium);
    // every test binary runs, so one failure does not hide the others
    s.run(
        "tests (workspace)",
        cargo(&["test", "--workspace", "--release", "--no-fail-fast"]),
    );
    crate::cross::cross(s);
    crate::embedded::embedded(s);
    // the fuzz smoke run: XTASK_FUZZ_SECONDS per target (default 30)
    let secs = std::env::var("XTASK_FUZZ_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(30);
    if secs > 0 {
        crate::fuzz::fuzz(s, secs, &crate::fuzz::TARGETS);
    } else {
        s.skip("fuzz smoke run", "XTASK_FUZZ_SECONDS=0");
    }
}
