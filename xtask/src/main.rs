//! Project tasks: `cargo xtask test | demo | blind | bench | fuzz | cross | embedded`
//! (`cargo xtask --help` lists them). Each task runs every step, collects the failures
//! and exits non-zero at the end if any step failed.
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
    // the reports' browser test needs Chromium: it fails (not skips) without it
    if let Err(e) = setup::chromium() {
        eprintln!("xtask: {e}");
        s.failed.push("install chromium".into());
    }
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

/// `--out DIR` made absolute against the directory `cargo xtask` was run from: host-fit
/// runs in the repository root, where a relative DIR would land otherwise.
fn absolute_out(rest: &[String], cwd: &Path) -> Vec<String> {
    let abs = |d: &str| {
        let p = Path::new(d);
        if p.is_absolute() {
            d.to_string()
        } else {
            cwd.join(p).to_string_lossy().into_owned()
        }
    };
    let mut out = Vec::new();
    let mut words = rest.iter();
    while let Some(w) = words.next() {
        if w == "--out" {
            out.push(w.clone());
            if let Some(d) = words.next() {
                out.push(abs(d));
            }
        } else if let Some(d) = w.strip_prefix("--out=") {
            out.push(format!("--out={}", abs(d)));
        } else {
            out.push(w.clone());
        }
    }
    out
}

/// `cargo run --release -p host-fit -- ARGS` in the repository root, cargo's own build
/// progress shown (the first build takes a minute or two).
fn host_fit(args: &[String]) -> Command {
    let mut c = cargo();
    c.args(["run", "--release", "-p", "host-fit", "--"])
        .args(args);
    c
}

fn demo(rest: &[String]) -> ExitCode {
    let cwd = std::env::current_dir().unwrap_or_else(|_| root());
    let mut args = vec!["demo".to_string()];
    args.extend(absolute_out(rest, &cwd));
    match host_fit(&args).status() {
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
            let c = host_fit(&["blind".to_string(), "--long".to_string()]);
            s.run("blind tests of the diagnosis (long suite)", c);
        }),
        Some("cross") => task(embedded::cross),
        Some("embedded") => task(embedded::embedded),
        Some("-h" | "--help" | "help") | None => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        Some(other) => {
            eprintln!("xtask: unknown command `{other}`\n\n{USAGE}");
            ExitCode::FAILURE
        }
    }
}

/// What `cargo xtask --help` prints.
const USAGE: &str = "usage: cargo xtask <command>

commands:
  test                      fmt, clippy, no_std build, all tests (headless Chromium included),
                            thumb cross builds, the QEMU proof, a fuzz smoke run per target;
                            installs what it needs when missing (apt as root)
  demo [--out DIR] [--seed N] [--force]
                            the paper's experiment on the digital twin -> demo-out/ (or DIR,
                            relative to where you run it): recording, blobs, summary.json,
                            report.html
  blind                     the long blind suite of the diagnosis (about 2 minutes)
  bench                     criterion benchmarks and a batch of 1000 simulated units
                            -> target/bench/summary.md
  fuzz [--seconds N] [TARGET..]
                            cargo-fuzz targets (default all, 60 s each)
  cross                     firmware-core built for thumbv7em-none-eabihf
  embedded                  the firmware test under QEMU (bit-exact against the host)
  help, -h, --help          this text";

#[cfg(test)]
mod tests {
    use super::absolute_out;
    use std::path::Path;

    #[test]
    fn a_relative_out_is_taken_from_where_xtask_was_run() {
        let a = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let cwd = Path::new("/home/u/repo/sub");
        assert_eq!(
            absolute_out(&a(&["--out", "mydir", "--seed", "2"]), cwd),
            a(&["--out", "/home/u/repo/sub/mydir", "--seed", "2"])
        );
        assert_eq!(
            absolute_out(&a(&["--force", "--out=x/y"]), cwd),
            a(&["--force", "--out=/home/u/repo/sub/x/y"])
        );
        assert_eq!(
            absolute_out(&a(&["--out", "/tmp/d"]), cwd),
            a(&["--out", "/tmp/d"])
        );
    }
}
