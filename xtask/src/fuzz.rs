//! `cargo xtask fuzz --seconds N`: every cargo-fuzz target for N seconds (nightly); the
//! committed seed corpus is read, new inputs go to target/fuzz-corpus/ (the repository
//! stays clean), and any crash artefact fails the step.
use std::process::Command;

/// The targets of fuzz/Cargo.toml.
pub const TARGETS: [&str; 4] = ["blob_decode", "compensate", "recording", "positions"];

/// Run every target; prints the executions per target.
pub fn fuzz(steps: &mut crate::Steps, seconds: u64, targets: &[&str]) {
    if let Err(e) = crate::setup::cargo_fuzz() {
        eprintln!("xtask: {e}");
        steps.failed.push("fuzz: cargo-fuzz".into());
        return;
    }
    let root = crate::root();
    let mut lines = Vec::new();
    for &t in targets {
        eprintln!("\n==> fuzz {t} for {seconds} s");
        let work = root.join("target/fuzz-corpus").join(t);
        let _ = std::fs::create_dir_all(&work);
        let artifacts = root.join("target/fuzz-artifacts").join(t);
        let _ = std::fs::remove_dir_all(&artifacts);
        let _ = std::fs::create_dir_all(&artifacts);
        let out = Command::new("cargo")
            .current_dir(&root)
            .args(["+nightly", "fuzz", "run", t])
            .arg(&work)
            .arg(root.join("fuzz/corpus").join(t))
            .arg("--")
            .arg(format!("-max_total_time={seconds}"))
            .arg(format!("-artifact_prefix={}/", artifacts.display()))
            .env_remove("CARGO")
            .env_remove("RUSTUP_TOOLCHAIN")
            .output();
        let Ok(out) = out else {
            steps.failed.push(format!("fuzz {t}: could not start"));
            continue;
        };
        let err = String::from_utf8_lossy(&out.stderr);
        let runs = err
            .lines()
            .rev()
            .filter_map(|l| l.strip_prefix("Done "))
            .find_map(|l| l.split_whitespace().next())
            .unwrap_or("?")
            .to_string();
        let crashes = std::fs::read_dir(&artifacts)
            .map(|d| d.count())
            .unwrap_or(0);
        lines.push(format!(
            "{t}: {runs} executions in {seconds} s, {crashes} crash artefacts"
        ));
        if out.status.success() && crashes == 0 {
            steps.passed.push(format!("fuzz {t}"));
        } else {
            // CI keeps only the log, so the log must carry what reproduces the crash: the
            // panic message and the artefact's bytes, not libFuzzer's tail.
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
            for a in std::fs::read_dir(&artifacts)
                .into_iter()
                .flatten()
                .flatten()
            {
                if let Ok(bytes) = std::fs::read(a.path()) {
                    eprintln!(
                        "artefact {} ({} bytes): b\"{}\"",
                        a.path().display(),
                        bytes.len(),
                        escape(&bytes[..bytes.len().min(4096)])
                    );
                }
            }
            steps
                .failed
                .push(format!("fuzz {t} (artefacts in {})", artifacts.display()));
        }
    }
    for l in &lines {
        println!("fuzz {l}");
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
