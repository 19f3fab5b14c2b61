//! A reader that goes away (`host-fit inspect B | head -1`) ends the output, not the
//! command: the binary run with its stdout a pipe whose reading end is already closed
//! (every write fails with EPIPE) ends as it would with a reader, its own exit code and
//! its files written, without a word about the pipe (issue 29 item 4).
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Six static TP dwells of 3 samples at 20 C (identifiable; no warning).
fn recording(dir: &Path) -> PathBuf {
    let u = [
        ("TP1", "0.0045,-0.0044,-0.5521"),
        ("TP2", "0.0050,0.5441,-0.0031"),
        ("TP3", "0.0045,-0.0044,0.5451"),
        ("TP4", "0.0040,-0.5530,-0.0038"),
        ("TP5", "0.5551,0.0088,0.0112"),
        ("TP6", "-0.5461,-0.0177,-0.0181"),
    ];
    let mut s = String::from("# unit=PIPE-1\nt_s,position,temp_c,ux_v,uy_v,uz_v\n");
    let mut t = 0;
    for (p, v) in u {
        for k in 0..3 {
            s.push_str(&format!("{t},{p},20.0{k},{v}\n"));
            t += 1;
        }
    }
    let p = dir.join("rec.csv");
    std::fs::write(&p, s).unwrap();
    p
}

/// Run host-fit with `args`, its stdout a pipe nobody reads (closed before it starts),
/// or (`closed` false) an open pipe read to the end: (exit code, stderr).
fn run(args: &[&str], closed: bool) -> (i32, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_host-fit"));
    cmd.args(args).stderr(Stdio::piped());
    if closed {
        let (read, write) = nix::unistd::pipe().unwrap();
        drop(read);
        cmd.stdout(Stdio::from(write));
    } else {
        cmd.stdout(Stdio::piped());
    }
    let o = cmd.output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn a_closed_pipe_ends_every_command_quietly() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let rec = recording(dir);
    let blob = dir.join("u.blob");
    let (code, err) = run(
        &[
            "fit",
            rec.to_str().unwrap(),
            "--out",
            blob.to_str().unwrap(),
        ],
        true,
    );
    assert_eq!((code, err.as_str()), (0, ""), "fit");
    assert!(
        blob.exists(),
        "fit wrote its blob with nobody reading its output"
    );
    let table = dir.join("t.csv");
    for args in [
        vec!["--help"],
        vec!["inspect", blob.to_str().unwrap()],
        vec!["inspect", blob.to_str().unwrap(), "--json"],
        vec!["identify", rec.to_str().unwrap()],
        vec![
            "verify",
            rec.to_str().unwrap(),
            "--blob",
            blob.to_str().unwrap(),
        ],
        vec![
            "fw-vectors",
            "--blob",
            blob.to_str().unwrap(),
            "--make-inputs",
            table.to_str().unwrap(),
            "--force",
        ],
        vec![
            "fw-vectors",
            "--blob",
            blob.to_str().unwrap(),
            "--inputs",
            table.to_str().unwrap(),
        ],
    ] {
        let open = run(&args, false);
        let closed = run(&args, true);
        assert_eq!(
            closed.0, open.0,
            "{args:?}: exit code {closed:?}, with a reader {open:?}"
        );
        assert_eq!(closed.1, open.1, "{args:?}: stderr");
        assert!(!closed.1.contains("Broken pipe"), "{args:?}: {}", closed.1);
    }
}
