//! The command line run in-process, as the tests use it: its exit code and output, its
//! JSON when it must succeed, the diagnosis of a shared real recording.
use crate::repo;

/// Run the CLI in-process; returns (exit code, stdout, stderr).
pub fn cli(args: &[&str]) -> (i32, String, String) {
    let mut out = Vec::new();
    let mut err = Vec::new();
    let argv = std::iter::once("host-fit").chain(args.iter().copied());
    let code = host_fit::cli::run(argv, &mut out, &mut err);
    (
        code,
        String::from_utf8_lossy(&out).into_owned(),
        String::from_utf8_lossy(&err).into_owned(),
    )
}

/// `host-fit ARGS` that must succeed (exit 0, else the test fails with its stderr), its
/// stdout parsed as JSON.
pub fn cli_json(args: &[&str]) -> serde_json::Value {
    let (code, out, err) = cli(args);
    assert_eq!(code, 0, "host-fit {}: {err}", args.join(" "));
    serde_json::from_str(&out)
        .unwrap_or_else(|e| panic!("host-fit {}: not JSON ({e}): {out}", args.join(" ")))
}

/// `host-fit diagnose --json` of `../shared/real/NAME/recording.csv`; `{dir}` in the extra
/// arguments is that recording's folder.
pub fn real_diagnosis(name: &str, extra: &[&str]) -> serde_json::Value {
    let rec = repo().join(format!("../shared/real/{name}/recording.csv"));
    assert!(
        rec.exists(),
        "the shared real recording is missing: {}",
        rec.display()
    );
    let mut args = vec![
        "diagnose".to_string(),
        rec.display().to_string(),
        "--json".into(),
    ];
    args.extend(extra.iter().map(|s| {
        s.replace(
            "{dir}",
            &repo()
                .join(format!("../shared/real/{name}"))
                .display()
                .to_string(),
        )
    }));
    let (code, out, err) = cli(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}
