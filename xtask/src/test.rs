//! `cargo xtask test`: everything, in this order: fmt, the book (mdbook build, its links
//! checked), clippy, the no_std build and tests, the workspace's tests (Chromium
//! installed first for the reports' browser test; PostgreSQL installed and a throwaway
//! cluster started for the record store's, stopped right after them, also when one
//! fails), the thumb cross builds, the firmware under QEMU, a fuzz smoke run per target.
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
    crate::book::book(s);
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
    // the record store's tests need a real PostgreSQL server: one throwaway cluster
    // for the whole run (each test makes its own database in it), its URL handed over
    // in HOSTFIT_TEST_PG; the guard stops it when dropped, right after the tests
    let cluster = s
        .prepare("install postgresql", crate::setup::postgresql)
        .and_then(|()| {
            s.prepare("start a throwaway PostgreSQL cluster", || {
                crate::pgcluster::Cluster::start(&crate::root().join("target"), false)
            })
        });
    let mut tests = cargo(&["test", "--workspace", "--release", "--no-fail-fast"]);
    if let Some(c) = &cluster {
        tests.env(crate::pgcluster::TEST_PG_VAR, c.url("postgres"));
    }
    // every test binary runs, so one failure does not hide the others
    s.run("tests (workspace)", tests);
    drop(cluster);
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
