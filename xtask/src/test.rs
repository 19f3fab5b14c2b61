//! `cargo xtask test [--full]`: everything, in this order: fmt, the book (mdbook build,
//! its links checked), clippy, the no_std build and tests, the workspace's tests
//! (Chromium installed first for the reports' browser test; PostgreSQL installed and a
//! throwaway cluster started for the record store's, stopped right after them, also
//! when one fails), the thumb cross builds, the firmware under QEMU, a fuzz run per
//! target. Two tiers: the default answers in minutes; `--full` adds the tests marked
//! `#[ignore = "full tier ..."]` (the long blind suites, the heavy figures) and fuzzes
//! longer.
use crate::Steps;
use std::process::Command;

/// Which tests run: the default tier answers in minutes, the full one holds the long
/// studies as well (what `.ci/run` runs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    /// Every crate and behaviour, the long studies left out (`cargo xtask test`).
    Default,
    /// The default tier plus the long blind suite, the heavy figures and longer fuzzing
    /// (`cargo xtask test --full`).
    Full,
}

impl Tier {
    /// `--full` or nothing; anything else is refused with the usage.
    pub fn parse(args: &[String]) -> Result<Tier, String> {
        match args {
            [] => Ok(Tier::Default),
            [a] if a == "--full" => Ok(Tier::Full),
            _ => Err(format!(
                "`cargo xtask test` takes `--full` or nothing, not `{}`",
                args.join(" ")
            )),
        }
    }

    /// The line above the step table.
    fn title(self) -> &'static str {
        match self {
            Tier::Default => "tier: default (`cargo xtask test`; the long blind suite, the heavy figures, long fuzzing and fuzzing the host's readers are in `cargo xtask test --full`)",
            Tier::Full => "tier: full (`cargo xtask test --full`: the default tier plus the long blind suite, the heavy figures and long fuzzing)",
        }
    }

    /// The fuzz targets run: the firmware's in the default tier (a change to the host
    /// costs no instrumented rebuild of it; its corpus is replayed by the tests), all in
    /// the full tier.
    fn fuzz_targets(self) -> &'static [&'static str] {
        match self {
            Tier::Default => &crate::fuzz::FIRMWARE_TARGETS,
            Tier::Full => &crate::fuzz::TARGETS,
        }
    }

    /// Seconds of one core's fuzzing per target (spread over the cores: half of it in
    /// wall time on two), unless XTASK_FUZZ_SECONDS says otherwise.
    fn fuzz_seconds(self) -> u64 {
        match self {
            Tier::Default => 10,
            Tier::Full => 60,
        }
    }
}

/// `cargo ARGS` in the repository root.
fn cargo(args: &[&str]) -> Command {
    let mut c = crate::cargo();
    c.args(args);
    c
}

/// `cargo xtask test [--full]`.
pub fn test(s: &mut Steps, tier: Tier) {
    s.title(tier.title());
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
    if tier == Tier::Full {
        // the tests the default tier leaves out, each marked `#[ignore = "full tier: why"]`
        let mut full = cargo(&[
            "test",
            "--workspace",
            "--release",
            "--no-fail-fast",
            "--",
            "--ignored",
        ]);
        if let Some(c) = &cluster {
            full.env(crate::pgcluster::TEST_PG_VAR, c.url("postgres"));
        }
        s.run(
            "tests (full tier: the long blind suite, heavy figures)",
            full,
        );
    }
    drop(cluster);
    crate::cross::cross(s);
    crate::embedded::embedded(s);
    // the fuzz run: XTASK_FUZZ_SECONDS of one core per target (by default 10 s on the
    // firmware's targets, 60 s on all four in the full tier), spread over the cores
    let secs = std::env::var("XTASK_FUZZ_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(tier.fuzz_seconds());
    if secs > 0 {
        crate::fuzz::fuzz(s, secs, tier.fuzz_targets());
    } else {
        s.skip("fuzz smoke run", "XTASK_FUZZ_SECONDS=0");
    }
}

#[cfg(test)]
mod tests {
    use super::Tier;

    fn words(w: &[&str]) -> Vec<String> {
        w.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn the_tier_is_the_default_or_full_and_nothing_else() {
        assert_eq!(Tier::parse(&words(&[])), Ok(Tier::Default));
        assert_eq!(Tier::parse(&words(&["--full"])), Ok(Tier::Full));
        for bad in [&["--fast"][..], &["--full", "--full"], &["full"]] {
            let e = Tier::parse(&words(bad)).unwrap_err();
            assert!(e.contains("--full"), "{bad:?}: {e}");
        }
        // the step table says which tier ran, and the full tier fuzzes longer
        assert!(Tier::Default.title().starts_with("tier: default"));
        assert!(Tier::Full.title().starts_with("tier: full"));
        assert!(Tier::Full.fuzz_seconds() > Tier::Default.fuzz_seconds());
        // the full tier fuzzes every target; the default the firmware's, which build
        // without host-fit
        assert_eq!(Tier::Full.fuzz_targets(), crate::fuzz::TARGETS);
        assert_eq!(Tier::Default.fuzz_targets(), crate::fuzz::FIRMWARE_TARGETS);
    }
}
