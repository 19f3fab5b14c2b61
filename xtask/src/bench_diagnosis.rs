//! The diagnosis's speed side by side with the previous release, for `cargo xtask bench`
//! (and alone: `cargo xtask bench diagnosis`): the previous release's host-fit is built
//! from its commit in a git worktree under target/bench/previous, and both binaries
//! diagnose the same recordings end to end (a 10k-row production unit of the twin, the
//! real wrist recording with its vectors as given and with every orientation unknown),
//! best of three each, run alternately so a busy machine slows both alike.
use std::path::{Path, PathBuf};
use std::process::Command;

/// The release the diagnosis's speed is held to: main just before the re-search of the
/// diagnosis was merged (`Merge branch 'issue-18-research'`, 2026-12-02), whose
/// diagnosis of the wrist recording was the fastest of the last releases.
pub const PREVIOUS_RELEASE: &str = "766098d71882f45a301b482f1b41009ae2e4a633";

/// The twin's configuration of the 10k-row production unit (three stops, K2, a rate
/// term and a warm-up): the same unit the previous release's bench diagnosed.
const PRODUCTION_10K: &str = "[schedule]\npositions = [\"TP1\",\"TP2\",\"TP3\",\"TP4\",\"TP5\",\"TP6\",\"PP1\",\"PP2\",\"PP3\",\"PP4\",\"PP5\",\"PP6\"]\n[[schedule.stops]]\ntemp_c = 20.0\nsoak_s = 1200.0\n[[schedule.stops]]\ntemp_c = -20.0\nsoak_s = 1200.0\n[[schedule.stops]]\ntemp_c = 10.0\nsoak_s = 1200.0\n[effects.nonlinearity_k2]\nvalue = [2e-4, 0.0, -1e-4]\n[effects.temp_rate]\nvalue = [0.03, 0.0, 0.0]\n[effects.warmup_drift]\nd_v = [0.0, 0.0, 4e-4]\ntau_s = 1500.0\n";

/// One recording diagnosed by both binaries.
struct Case {
    /// As the table names it.
    name: String,
    /// host-fit's arguments.
    args: Vec<String>,
}

/// The previous release's host-fit, built in a detached worktree of its commit (kept
/// between runs, so only the first run builds it).
fn previous_binary(root: &Path) -> Result<PathBuf, String> {
    let wt = root.join("target/bench/previous");
    if !wt.join("Cargo.toml").exists() {
        let _ = std::fs::remove_dir_all(&wt);
        let mut prune = Command::new("git");
        prune.current_dir(root).args(["worktree", "prune"]);
        let _ = prune.status();
        crate::sh(
            Command::new("git")
                .current_dir(root)
                .args(["worktree", "add", "--detach"])
                .arg(&wt)
                .arg(PREVIOUS_RELEASE),
        )
        .map_err(|e| {
            format!("{e}: the previous release's commit is needed (a shallow clone lacks it: `git fetch --unshallow`)")
        })?;
    }
    let target = root.join("target/bench/previous-target");
    crate::sh(
        Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
            .current_dir(&wt)
            .args(["build", "--release", "-p", "host-fit"])
            .env("CARGO_TARGET_DIR", &target),
    )?;
    Ok(target.join("release/host-fit"))
}

/// The recordings: the 10k-row unit simulated by this release's twin (the previous
/// release reads the same file), and the wrist recording both ways.
fn cases(bin: &Path, root: &Path) -> Result<Vec<Case>, String> {
    let dir = root.join("target/bench");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let cfg = dir.join("production-10k.toml");
    std::fs::write(&cfg, PRODUCTION_10K).map_err(|e| format!("{}: {e}", cfg.display()))?;
    let rec = dir.join("production-10k.csv");
    let s = |p: &Path| p.display().to_string();
    crate::sh(Command::new(bin).args(["simulate", &s(&cfg), "--out", &s(&rec), "--force"]))?;
    let rows = std::fs::read_to_string(&rec)
        .map(|t| t.lines().count())
        .map_err(|e| format!("{}: {e}", rec.display()))?;
    let wrist = root.join("../shared/real/ggir-wrist");
    let wrist_args = |unknown: bool| {
        let mut a = vec![
            "diagnose".to_string(),
            s(&wrist.join("recording.csv")),
            "--positions".into(),
            s(&wrist.join("positions.csv")),
        ];
        if unknown {
            a.push("--unknown-orientations".into());
        }
        a.push("--json".into());
        a
    };
    Ok(vec![
        Case {
            name: format!("{rows}-row production unit (K2, rate, warm-up)"),
            args: vec!["diagnose".to_string(), s(&rec), "--json".into()],
        },
        Case {
            name: "11k-row real wrist recording, vectors as given".into(),
            args: wrist_args(false),
        },
        Case {
            name: "11k-row real wrist recording, every orientation unknown".into(),
            args: wrist_args(true),
        },
    ])
}

/// One run's wall time (s), or the command's failure.
fn once(bin: &Path, args: &[String]) -> Result<f64, String> {
    let t = std::time::Instant::now();
    let out = Command::new(bin)
        .args(args)
        .output()
        .map_err(|e| format!("{}: {e}", bin.display()))?;
    if out.status.success() {
        Ok(t.elapsed().as_secs_f64())
    } else {
        Err(format!(
            "{} {} failed ({}): {}",
            bin.display(),
            args.join(" "),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// Best of three for each binary, the two alternating: (this release, previous).
fn side_by_side(now: &Path, before: &Path, args: &[String]) -> Result<(f64, f64), String> {
    let (mut a, mut b) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..3 {
        a = a.min(once(now, args)?);
        b = b.min(once(before, args)?);
    }
    Ok((a, b))
}

/// The table of the diagnosis's times, this release beside the previous one (Markdown),
/// one step per recording; `bin` is this release's host-fit.
pub fn diagnosis_times(bin: &Path, steps: &mut crate::Steps) -> String {
    let root = crate::root();
    let short = PREVIOUS_RELEASE.get(..7).unwrap_or(PREVIOUS_RELEASE);
    let mut md = format!("\n### Diagnosis, end to end, beside the previous release ({short})\n\nRelease binaries, one thread each, best of 3, the two alternating.\n\n| recording | this release | previous release | ratio |\n|---|---|---|---|\n");
    let Some(before) = steps
        .step("build the previous release's host-fit", || {
            previous_binary(&root)
        })
        .ok()
    else {
        return md;
    };
    let Some(cases) = steps
        .step("the recordings to diagnose", || cases(bin, &root))
        .ok()
    else {
        return md;
    };
    for c in cases {
        let timed = steps.step(&format!("diagnose the {}", c.name), || {
            side_by_side(bin, &before, &c.args)
        });
        if let Ok((now, prev)) = timed {
            md.push_str(&format!(
                "| {} | {now:.2} s | {prev:.2} s | {:.2}x |\n",
                c.name,
                now / prev
            ));
        }
    }
    md
}

/// `cargo xtask bench diagnosis`: only the table above (this release built first).
pub fn diagnosis_only(steps: &mut crate::Steps) {
    let mut c = crate::cargo();
    c.args(["build", "--release", "-p", "host-fit"]);
    if !steps.run("build host-fit", c) {
        return;
    }
    let bin = crate::root().join("target/release/host-fit");
    let md = diagnosis_times(&bin, steps);
    let dir = crate::root().join("target/bench");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("diagnosis.md"), &md);
    println!("{md}");
}
