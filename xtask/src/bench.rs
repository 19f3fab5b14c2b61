//! `cargo xtask bench`: criterion benchmarks of firmware-core and host-fit, and a batch
//! of 1000 simulated units; writes target/bench/summary.md.
use std::path::{Path, PathBuf};
use std::process::Command;

/// The mean estimate (ns) of one criterion benchmark, from its `new/estimates.json`.
fn estimate_ns(dir: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(dir.join("new/estimates.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v["mean"]["point_estimate"].as_f64()
}

/// All criterion results: (group/name, ns).
fn results(root: &Path) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                if p.join("new/estimates.json").exists() {
                    if let (Ok(rel), Some(ns)) = (p.strip_prefix(root), estimate_ns(&p)) {
                        out.push((rel.display().to_string(), ns));
                    }
                } else if p.file_name().is_some_and(|n| n != "report") {
                    stack.push(p);
                }
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn fmt_ns(ns: f64) -> String {
    if ns < 1e3 {
        format!("{ns:.1} ns")
    } else if ns < 1e6 {
        format!("{:.2} us", ns / 1e3)
    } else {
        format!("{:.2} ms", ns / 1e6)
    }
}

/// Run the benchmarks.
pub fn bench(steps: &mut crate::Steps) {
    let root = crate::root();
    let mut c = crate::cargo();
    c.args(["bench", "-p", "firmware-core", "--bench", "compensate"]);
    steps.run("bench firmware-core", c);
    let mut c = crate::cargo();
    c.args(["bench", "-p", "host-fit", "--bench", "host"]);
    steps.run("bench host-fit", c);
    let mut c = crate::cargo();
    c.args(["build", "--release", "-p", "host-fit"]);
    steps.run("build host-fit", c);
    let bin = root.join("target/release/host-fit");
    let units = root.join("target/bench/units");
    let _ = std::fs::create_dir_all(&units);
    eprintln!(
        "\n==> simulating 1000 units of the paper's profile into {}",
        units.display()
    );
    for seed in 1..=1000u32 {
        let p = units.join(format!("unit{seed:04}.csv"));
        if p.exists() {
            continue;
        }
        let ok = Command::new(&bin)
            .args(["simulate", "--seed", &seed.to_string(), "--out"])
            .arg(&p)
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false);
        if !ok {
            steps.failed.push(format!("simulate unit {seed}"));
            return;
        }
    }
    let out = root.join("target/bench/batch-out");
    let t = std::time::Instant::now();
    // stdout is read for the verdict counts; stderr (the progress bar) stays the user's
    let run = Command::new(&bin)
        .args(["batch"])
        .arg(&units)
        .arg("--out")
        .arg(&out)
        .args(["--jobs", "2", "--force"])
        .stderr(std::process::Stdio::inherit())
        .output();
    let batch_s = t.elapsed().as_secs_f64();
    // exit 0: every unit passed; 3: it ran and some unit failed or errored; else it did not run
    let verdicts = match &run {
        Ok(o) if matches!(o.status.code(), Some(0 | 3)) => {
            steps.passed.push("batch of 1000 units".into());
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .next()
                .unwrap_or_default()
                .to_string()
        }
        _ => {
            steps.failed.push("batch of 1000 units".into());
            String::new()
        }
    };
    let res = results(&root.join("target/criterion"));
    let get = |k: &str| res.iter().find(|r| r.0 == k).map(|r| r.1);
    let mut md = String::from("## Benchmarks (`cargo xtask bench`, this machine: 2 cores)\n\n### firmware-core on the host (x86-64, f32)\n\n| benchmark | time |\n|---|---|\n");
    for (k, v) in res.iter().filter(|r| {
        r.0.starts_with("sample") || r.0.starts_with("update") || r.0.starts_with("decode")
    }) {
        md.push_str(&format!("| {k} | {} |\n", fmt_ns(*v)));
    }
    md.push_str("\n(`update/*`: one temperature update (12 temperature models evaluated, K inverted) plus one sample, per call.)\n\n### host-fit against recording length\n\n| rows | read | read rate | identify + fit (joint, pwl) | diagnose |\n|---|---|---|---|---|\n");
    let mut lens: Vec<u64> = res
        .iter()
        .filter_map(|r| r.0.strip_prefix("host/read/").and_then(|n| n.parse().ok()))
        .collect();
    lens.sort_unstable();
    for n in lens {
        let (r, f, d) = (
            get(&format!("host/read/{n}")),
            get(&format!("host/fit/{n}")),
            get(&format!("host/diagnose/{n}")),
        );
        md.push_str(&format!(
            "| {n} | {} | {} | {} | {} |\n",
            r.map(fmt_ns).unwrap_or_default(),
            r.map(|ns| format!("{:.2} M rows/s", n as f64 / ns * 1e3))
                .unwrap_or_default(),
            f.map(fmt_ns).unwrap_or_default(),
            d.map(fmt_ns).unwrap_or_default()
        ));
    }
    md.push_str(&format!("\n### Batch\n\n`host-fit batch` of 1000 simulated units of the paper's profile (22 k rows each), `--jobs 2`, every unit's model chosen by cross-validation and judged against the acceptance specification: **{batch_s:.1} s** (target < 60 s).\n\n`{verdicts}`\n"));
    let dir = root.join("target/bench");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("summary.md"), &md);
    println!("{md}");
    let _ = PathBuf::new();
}
