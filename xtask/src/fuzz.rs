//! `cargo xtask fuzz --seconds N`: every cargo-fuzz target for N seconds of one core's
//! fuzzing, spread over the machine's cores (nightly); the committed seed corpus is read,
//! new inputs go to target/fuzz-corpus/ (the repository stays clean), and any crash
//! artefact fails the step.
use std::path::Path;
use std::process::Command;

/// The targets of fuzz/Cargo.toml.
pub const TARGETS: [&str; 4] = ["blob_decode", "compensate", "recording", "positions"];

/// The firmware's targets: built without host-fit, so a change to the host costs them
/// no instrumented rebuild (the default tier fuzzes these; the host's corpus is replayed
/// by `host-fit/tests/fuzz_corpus.rs` on every test run).
pub const FIRMWARE_TARGETS: [&str; 2] = ["blob_decode", "compensate"];

/// No AddressSanitizer: firmware-core and host-fit forbid unsafe code and the targets
/// reach no C (the readers are csv and serde, the firmware is pure Rust), so ASan would
/// guard memory the compiler already guards, at the cost of a slower instrumented build
/// (host-fit with every dependency, the longest step of the full tier) and fewer
/// executions per second. libFuzzer's coverage instrumentation and debug assertions
/// stay: a panic, an overflow or a failed property is still a crash.
const SANITIZER: [&str; 2] = ["--sanitizer", "none"];

/// Fuzzing workers per target: libFuzzer's fork mode (`cargo fuzz run --jobs`) on every
/// core, at most four. One libFuzzer process keeps one core busy while the other waits.
/// Measured on a 2-core machine (2026-12-05, 30 s on 2 workers against 60 s on one):
/// 0.84x, 1.15x, 0.66x and 1.0x the executions of blob_decode, compensate, recording
/// and positions (fork mode's jobs restart and merge), in half the wall time.
fn workers() -> u64 {
    std::thread::available_parallelism()
        .map(|n| n.get() as u64)
        .unwrap_or(1)
        .clamp(1, 4)
}

/// The wall time of `core_seconds` of fuzzing on `workers` cores (at least a second).
fn wall_seconds(core_seconds: u64, workers: u64) -> u64 {
    core_seconds.div_ceil(workers.max(1)).max(1)
}

/// The executions libFuzzer reports last: `Done N runs` (one process) or the last
/// status line `#N: cov: ...` (fork mode, where the jobs' runs are summed).
fn executions(stderr: &str) -> String {
    stderr
        .lines()
        .rev()
        .find_map(|l| {
            if let Some(done) = l.strip_prefix("Done ") {
                return done.split_whitespace().next().map(String::from);
            }
            let n = l.strip_prefix('#')?.split(':').next()?;
            (l.contains(" cov: ") && n.chars().all(|c| c.is_ascii_digit())).then(|| n.to_string())
        })
        .unwrap_or_else(|| "?".to_string())
}

/// The cargo features target `t` needs (the host's readers need host-fit).
fn features(t: &str) -> &'static [&'static str] {
    if FIRMWARE_TARGETS.contains(&t) {
        &[]
    } else {
        &["--features", "host"]
    }
}

/// `cargo xtask fuzz [--seconds N] [TARGET..]`.
pub struct Options {
    /// Seconds of one core's fuzzing per target (default 60), spread over the cores.
    pub seconds: u64,
    /// The targets named, or all of them.
    pub targets: Vec<&'static str>,
}

impl Options {
    /// `--seconds N` (default 60); any other word names a target, none means all.
    pub fn parse(args: &[String]) -> Result<Options, String> {
        let mut seconds = 60;
        let mut targets = Vec::new();
        let mut words = args.iter();
        while let Some(w) = words.next() {
            if w == "--seconds" {
                seconds = words
                    .next()
                    .and_then(|v| v.parse().ok())
                    .ok_or("--seconds needs a whole number of seconds")?;
            } else {
                let t = TARGETS
                    .iter()
                    .find(|t| *t == w)
                    .ok_or_else(|| format!("no fuzz target `{w}` (targets: {TARGETS:?})"))?;
                targets.push(*t);
            }
        }
        if targets.is_empty() {
            targets = TARGETS.to_vec();
        }
        Ok(Options { seconds, targets })
    }
}

/// Run every target for `seconds` of one core's fuzzing, on every core, one step each;
/// prints the executions per target.
pub fn fuzz(steps: &mut crate::Steps, seconds: u64, targets: &[&str]) {
    if steps
        .prepare("fuzz: cargo-fuzz", crate::setup::cargo_fuzz)
        .is_none()
    {
        for t in targets {
            steps.skip(&format!("fuzz {t}"), "no cargo-fuzz");
        }
        return;
    }
    let mut lines = Vec::new();
    let jobs = workers();
    let wall = wall_seconds(seconds, jobs);
    for &t in targets {
        let name = format!("fuzz {t}");
        if let Ok(line) = steps.step(&name, || target(t, wall, jobs)) {
            lines.push(line);
        }
    }
    for l in &lines {
        println!("fuzz {l}");
    }
}

/// One target for `seconds` on `jobs` workers: its executions, or the crash (panic
/// message and input printed, so a CI log is enough to reproduce it).
fn target(t: &str, seconds: u64, jobs: u64) -> Result<String, String> {
    let root = crate::root();
    let work = root.join("target/fuzz-corpus").join(t);
    let _ = std::fs::create_dir_all(&work);
    let artifacts = root.join("target/fuzz-artifacts").join(t);
    let _ = std::fs::remove_dir_all(&artifacts);
    let _ = std::fs::create_dir_all(&artifacts);
    let out = Command::new("cargo")
        .current_dir(&root)
        .args(["+nightly", "fuzz", "run"])
        .args(SANITIZER)
        .args(features(t))
        .args(["--jobs", &jobs.to_string()])
        .arg(t)
        .arg(&work)
        .arg(root.join("fuzz/corpus").join(t))
        .arg("--")
        .arg(format!("-max_total_time={seconds}"))
        .arg(format!("-artifact_prefix={}/", artifacts.display()))
        .env_remove("CARGO")
        .env_remove("RUSTUP_TOOLCHAIN")
        .output()
        .map_err(|e| format!("could not start cargo +nightly fuzz: {e}"))?;
    let err = String::from_utf8_lossy(&out.stderr);
    let runs = executions(&err);
    let crashes = std::fs::read_dir(&artifacts)
        .map(|d| d.count())
        .unwrap_or(0);
    let line = format!(
        "{t}: {runs} executions in {seconds} s on {jobs} worker{}, {crashes} crash artefacts",
        if jobs == 1 { "" } else { "s" }
    );
    if out.status.success() && crashes == 0 {
        return Ok(line);
    }
    show_crash(&err, &artifacts);
    Err(format!(
        "{line} (artefacts in {}; the panic and each crashing input are printed above:          add the input to a test, fix, and keep it in fuzz/corpus/{t}/ as a regression seed)",
        artifacts.display()
    ))
}

/// The panic message and each artefact's bytes: CI keeps only the log, so the log must
/// carry what reproduces the crash, not libFuzzer's tail.
fn show_crash(err: &str, artifacts: &Path) {
    let mut shown: Vec<&str> = Vec::new();
    let lines: Vec<&str> = err.lines().collect();
    for (i, l) in lines.iter().enumerate() {
        if l.contains("panicked at") || l.contains("ERROR: libFuzzer") {
            shown.extend(lines.iter().skip(i).take(3));
        }
    }
    if shown.is_empty() {
        shown = lines.iter().rev().take(30).rev().copied().collect();
    }
    eprintln!("{}", shown.join("\n"));
    for a in std::fs::read_dir(artifacts).into_iter().flatten().flatten() {
        if let Ok(bytes) = std::fs::read(a.path()) {
            eprintln!(
                "artefact {} ({} bytes): b\"{}\"",
                a.path().display(),
                bytes.len(),
                escape(&bytes[..bytes.len().min(4096)])
            );
        }
    }
}

/// Bytes as a Rust byte-string body, so a crash input can be pasted into a test.
fn escape(bytes: &[u8]) -> String {
    bytes
        .iter()
        .flat_map(|b| std::ascii::escape_default(*b))
        .map(char::from)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{executions, features, wall_seconds, Options, TARGETS};

    #[test]
    fn options_name_targets_and_seconds() {
        let a = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let o = Options::parse(&a(&["recording", "--seconds", "5"])).unwrap();
        assert_eq!((o.seconds, o.targets), (5, vec!["recording"]));
        let all = Options::parse(&[]).unwrap();
        assert_eq!((all.seconds, all.targets), (60, TARGETS.to_vec()));
        assert!(Options::parse(&a(&["--seconds", "x"])).is_err());
        assert!(Options::parse(&a(&["--seconds"])).is_err());
        // the host's readers need host-fit; the firmware's targets build without it
        assert_eq!(features("recording"), ["--features", "host"]);
        assert_eq!(features("positions"), ["--features", "host"]);
        assert!(features("blob_decode").is_empty() && features("compensate").is_empty());
        assert!(Options::parse(&a(&["nope"])).is_err_and(|e| e.contains("`nope`")));
    }

    #[test]
    fn fork_mode_spreads_the_seconds_and_its_executions_are_read() {
        // 60 s of one core on 2 workers is 30 s of wall time; a remainder rounds up
        assert_eq!(wall_seconds(60, 2), 30);
        assert_eq!(wall_seconds(10, 3), 4);
        assert_eq!(wall_seconds(1, 4), 1);
        assert_eq!(wall_seconds(5, 0), 5);
        // one process: `Done N runs`
        let one = "#1024 pulse cov: 3\nDone 1633337 runs in 11 second(s)\n";
        assert_eq!(executions(one), "1633337");
        // fork mode: the last status line (no `Done`)
        let fork = "INFO: -fork=2: 5 seed inputs\n#584271: cov: 253 ft: 299 corp: 5\n#3355078: cov: 368 ft: 634 corp: 127 exec/s: 132705\nINFO: fuzzed for 12 seconds, wrapping up soon\nINFO: exiting: 0 time: 12s\n";
        assert_eq!(executions(fork), "3355078");
        assert_eq!(executions("nothing here"), "?");
    }
}
