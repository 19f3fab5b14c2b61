//! The tasks that are one host-fit run: `cargo xtask demo` (the main job) and
//! `cargo xtask blind` (the long blind suite of the diagnosis).
use crate::Steps;
use std::path::Path;
use std::process::{Command, ExitCode};

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
    let mut c = crate::cargo();
    c.args(["run", "--release", "-p", "host-fit", "--"])
        .args(args);
    c
}

/// `cargo xtask demo [--out DIR] [--seed N] [--force]`: host-fit's own output is the
/// report, so no step table.
pub fn demo(rest: &[String]) -> ExitCode {
    let cwd = std::env::current_dir().unwrap_or_else(|_| crate::root());
    let mut args = vec!["demo".to_string()];
    args.extend(absolute_out(rest, &cwd));
    match host_fit(&args).status() {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        _ => ExitCode::FAILURE,
    }
}

/// `cargo xtask blind`: the long suite, one step.
pub fn blind(s: &mut Steps) {
    let c = host_fit(&["blind".to_string(), "--long".to_string()]);
    s.run("blind tests of the diagnosis (long suite)", c);
}

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
