//! Project tasks: `cargo xtask test | demo | blind | bench | fuzz | cross | embedded | book`
//! (`cargo xtask --help` lists them). One task per file; each runs every step, prints
//! each as it starts and ends with its time, collects the failures, and ends with a table
//! of the steps (`steps`), exiting non-zero if any step failed.
mod bench;
mod bench_diagnosis;
mod book;
mod budgets;
mod c_harness;
mod cross;
mod embedded;
mod fuzz;
mod host;
mod links;
mod measure;
mod pgcluster;
mod qemu;
mod setup;
mod steps;
mod store_bench;
mod summary;
mod test;
mod toolchain;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
pub use steps::Steps;

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

/// Run a command to its end: an error naming it unless it succeeded.
pub fn sh(cmd: &mut Command) -> Result<(), String> {
    let st = cmd.status().map_err(|e| format!("{cmd:?}: {e}"))?;
    if st.success() {
        Ok(())
    } else {
        Err(format!("{cmd:?} failed ({st})"))
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
    let rest = argv.get(1..).unwrap_or_default();
    match argv.first().map(String::as_str) {
        Some("test") => match test::Tier::parse(rest) {
            Ok(tier) => task(|s| test::test(s, tier)),
            Err(e) => {
                eprintln!("xtask: {e}");
                ExitCode::FAILURE
            }
        },
        Some("demo") => host::demo(rest),
        Some("fuzz") => match fuzz::Options::parse(rest) {
            Ok(o) => task(|s| fuzz::fuzz(s, o.seconds, &o.targets)),
            Err(e) => {
                eprintln!("xtask: {e}");
                ExitCode::FAILURE
            }
        },
        Some("bench") if rest.first().map(String::as_str) == Some("store") => {
            task(store_bench::store_only)
        }
        Some("bench") if rest.first().map(String::as_str) == Some("diagnosis") => {
            task(bench_diagnosis::diagnosis_only)
        }
        Some("bench") => task(bench::bench),
        Some("blind") => task(host::blind),
        Some("cross") => task(cross::cross),
        Some("embedded") => task(embedded::embedded),
        Some("book") => task(book::book),
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
  test [--full]             fmt, the book (links checked), clippy, no_std build, all tests
                            (headless Chromium and a throwaway PostgreSQL cluster included),
                            thumb cross builds, the QEMU proof, a fuzz run per target (10 s);
                            installs what it needs when missing (apt as root). --full adds
                            the tests marked `full tier` (the blind suites, the heavy
                            figures) and fuzzes 60 s per target: what .ci/run runs
  demo [--out DIR] [--seed N] [--force]
                            the paper's experiment on the digital twin -> demo-out/ (or DIR,
                            relative to where you run it): recording, blobs, summary.json,
                            report.html
  blind                     the long blind suite of the diagnosis (tens of minutes)
  bench                     criterion benchmarks, a batch of 1000 simulated units, the record
                            store on SQLite and PostgreSQL (8 writers, history among 100 000
                            records) -> target/bench/summary.md
  bench diagnosis           only the diagnosis's speed beside the previous release's (built
                            from its commit under target/bench/previous)
                            -> target/bench/diagnosis.md
  bench store               only the record store's figures (from a batch of 64 units)
                            -> target/bench/store.md
  fuzz [--seconds N] [TARGET..]
                            cargo-fuzz targets (default all, 60 s of one core each,
                            spread over the machine's cores)
  cross                     firmware-core built for thumbv7em-none-eabihf
  embedded                  the firmware test under QEMU (bit-exact against the host)
  book                      the manual under docs/ built with mdbook -> target/book/, every
                            relative link of README.md and docs/*.md checked
  help, -h, --help          this text

Every task but demo prints each step as it starts and ends with its time, then a table
of the steps (pass, FAILED or skipped with the reason, time) and every failure with what
to do; it exits 1 if any step failed.";
