//! Project tasks: `cargo xtask test | demo`. Each task runs every step, collects the
//! failures and exits non-zero at the end if any step failed.
mod bench;
mod embedded;
mod fuzz;
mod setup;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

/// `cargo` in the repository root.
pub fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

/// The steps of a task: what passed and what failed.
pub struct Steps {
    /// Names of the steps that passed.
    pub passed: Vec<String>,
    /// Names of the steps that failed.
    pub failed: Vec<String>,
}

impl Steps {
    fn new() -> Self {
        Steps {
            passed: Vec::new(),
            failed: Vec::new(),
        }
    }

    fn run(&mut self, name: &str, mut cmd: Command) {
        eprintln!("\n==> {name}");
        match cmd.status() {
            Ok(s) if s.success() => self.passed.push(name.to_string()),
            Ok(s) => {
                eprintln!("xtask: step `{name}` failed ({s})");
                self.failed.push(name.to_string());
            }
            Err(e) => {
                eprintln!("xtask: step `{name}` could not start: {e}");
                self.failed.push(name.to_string());
            }
        }
    }

    fn finish(self) -> ExitCode {
        eprintln!();
        for f in &self.failed {
            eprintln!("FAILED: {f}");
        }
        println!(
            "xtask: {} passed, {} failed",
            self.passed.len(),
            self.failed.len()
        );
        if self.failed.is_empty() {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        }
    }
}

fn args(c: &mut Command, a: &[&str]) -> Command {
    let mut n = std::mem::replace(c, cargo());
    n.args(a);
    n
}

fn test() -> ExitCode {
    let mut s = Steps::new();
    let mut c = cargo();
    s.run("fmt", args(&mut c, &["fmt", "--all", "--", "--check"]));
    s.run(
        "clippy (workspace)",
        args(
            &mut c,
            &[
                "clippy",
                "--workspace",
                "--all-targets",
                "--",
                "-D",
                "warnings",
            ],
        ),
    );
    s.run(
        "clippy (firmware-core, no default features)",
        args(
            &mut c,
            &[
                "clippy",
                "-p",
                "firmware-core",
                "--no-default-features",
                "--",
                "-D",
                "warnings",
            ],
        ),
    );
    s.run(
        "build firmware-core alone, no default features",
        args(
            &mut c,
            &["build", "-p", "firmware-core", "--no-default-features"],
        ),
    );
    s.run(
        "tests (firmware-core without the physics feature)",
        args(
            &mut c,
            &[
                "test",
                "-p",
                "firmware-core",
                "--no-default-features",
                "--release",
            ],
        ),
    );
    s.run(
        "tests (workspace)",
        args(&mut c, &["test", "--workspace", "--release"]),
    );
    embedded::cross(&mut s);
    embedded::embedded(&mut s);
    // the fuzz smoke run: XTASK_FUZZ_SECONDS per target (default 30)
    let secs = std::env::var("XTASK_FUZZ_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(30);
    if secs > 0 {
        fuzz::fuzz(&mut s, secs, &fuzz::TARGETS);
    }
    s.finish()
}

fn demo(rest: &[String]) -> ExitCode {
    let mut c = cargo();
    c.args([
        "run",
        "--quiet",
        "--release",
        "-p",
        "host-fit",
        "--",
        "demo",
    ])
    .args(rest);
    match c.status() {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        _ => ExitCode::FAILURE,
    }
}

/// Run one task's steps and report.
fn task(f: impl FnOnce(&mut Steps)) -> ExitCode {
    let mut s = Steps::new();
    f(&mut s);
    s.finish()
}

fn main() -> ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    match argv.first().map(String::as_str) {
        Some("test") => test(),
        Some("demo") => demo(&argv[1..]),
        Some("fuzz") => {
            // `--seconds N` (default 60); any other word names a target, none means all
            let mut secs = 60;
            let mut named: Vec<&str> = Vec::new();
            let mut words = argv[1..].iter();
            while let Some(w) = words.next() {
                if w != "--seconds" {
                    named.push(w);
                    continue;
                }
                match words.next().map(|v| v.parse()) {
                    Some(Ok(n)) => secs = n,
                    _ => {
                        eprintln!("xtask: --seconds needs a whole number of seconds");
                        return ExitCode::FAILURE;
                    }
                }
            }
            if let Some(bad) = named.iter().find(|n| !fuzz::TARGETS.contains(n)) {
                eprintln!(
                    "xtask: no fuzz target `{bad}` (targets: {:?})",
                    fuzz::TARGETS
                );
                return ExitCode::FAILURE;
            }
            let targets = if named.is_empty() {
                fuzz::TARGETS.to_vec()
            } else {
                named
            };
            task(|s| fuzz::fuzz(s, secs, &targets))
        }
        Some("bench") => task(bench::bench),
        Some("blind") => task(|s| {
            let mut c = cargo();
            c.args([
                "run",
                "--quiet",
                "--release",
                "-p",
                "host-fit",
                "--",
                "blind",
                "--long",
            ]);
            s.run("blind tests of the diagnosis (long suite)", c);
        }),
        Some("cross") => task(embedded::cross),
        Some("embedded") => task(embedded::embedded),
        _ => {
            eprintln!("usage: cargo xtask <test | demo [args] | blind | bench | fuzz [--seconds N] [TARGET..] | cross | embedded>");
            ExitCode::FAILURE
        }
    }
}
