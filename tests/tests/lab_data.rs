//! A lab's own data (issue 17): a recording with the lab's own position names (F1..F6,
//! V1..V4 with `role`), four stops, T0 = 25 C, made by the twin (`tests::lab`), through
//! every command as a lab would run them. Bad positions are refused naming file, line and
//! field; a file that is not a blob is called so; a missing output folder is named;
//! outputs get the mode the user's umask gives; every command that reads recordings takes
//! the same positions options (`batch` included); the expected notes stay out of the way
//! unless asked for; the report names the lab's positions and labels its log axis down to
//! the data.
use std::path::{Path, PathBuf};
use std::process::Command;
use tests::{cli, lab};

/// A folder removed when the test ends, passed or failed.
fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The positions file with one more line; its line number.
fn positions_with(dir: &Path, name: &str, line: &str) -> (PathBuf, usize) {
    let text = format!("{}{line}\n", lab::positions_csv());
    let p = dir.join(name);
    std::fs::write(&p, &text).unwrap();
    (p, text.lines().count())
}

#[test]
fn a_vector_far_from_unit_length_is_refused_naming_file_line_and_field() {
    let tmp = tempdir();
    let dir: PathBuf = tmp.path().to_path_buf();
    let f = lab::write(&dir, 1);
    // the tilt written in degrees, as a lab did
    let (pos, line) = positions_with(&dir, "degrees.csv", "V5,25,0,65,verification");
    let want = format!(
        "error: {}:{line}: field `fx,fy,fz`: position `V5` has length 69.6419, more than 1% from 1: a unit vector of specific force (g) is expected (angles in degrees are not a vector)\n",
        pos.display()
    );
    for args in [
        vec!["fit", s(&f.recording), "--out", "never.blob"],
        vec!["identify", s(&f.recording)],
        vec!["batch", s(&dir), "--out", "never-written"],
    ] {
        let mut args = args.clone();
        args.extend(["--positions", s(&pos)]);
        let (code, out, err) = cli(&args);
        assert_eq!((code, out.as_str()), (1, ""), "{args:?}: {err}");
        assert_eq!(err, want, "{args:?}");
    }
    assert!(!Path::new("never.blob").exists() && !Path::new("never-written").exists());
    // 2 for 1 (a typo) is refused too; 1.005 (rounded components) is normalised with a
    // warning naming the line, as recording-format.md says
    let (pos, _) = positions_with(&dir, "two.csv", "V5,0,0,2,verification");
    let (code, _, err) = cli(&["identify", s(&f.recording), "--positions", s(&pos)]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("has length 2.0000, more than 1% from 1"),
        "{err}"
    );
    let (pos, line) = positions_with(&dir, "rounded.csv", "V5,0,0,1.005,verification");
    let (code, _, err) = cli(&["identify", s(&f.recording), "--positions", s(&pos)]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains(&format!(
            "warning: {}:{line}: position `V5` has length 1.005000000; normalised",
            pos.display()
        )),
        "{err}"
    );
}

#[test]
fn a_file_that_is_not_a_blob_is_called_so() {
    let tmp = tempdir();
    let dir: PathBuf = tmp.path().to_path_buf();
    let f = lab::write(&dir, 1);
    let (code, _, err) = cli(&["inspect", s(&f.recording)]);
    assert_eq!(code, 1);
    assert_eq!(
        err,
        format!(
            "error: {}: not a blob: it starts with `# format=at-reco`..., not with the blob's magic `ATCB` (a blob is written by `fit` or `diagnose --out`)\n",
            f.recording.display()
        )
    );
    // the same when given to verify as its blob; a corrupted blob is still corrupted
    let (code, _, err) = cli(&[
        "verify",
        s(&f.recording),
        "--positions",
        s(&f.positions),
        "--blob",
        s(&f.positions),
    ]);
    assert_eq!(code, 1);
    assert!(
        err.contains("not a blob: it starts with `name,fx,fy,fz,ro`") && !err.contains("CRC"),
        "{err}"
    );
    let blob = dir.join("u.blob");
    let (code, _, err) = cli(&[
        "fit",
        s(&f.recording),
        "--positions",
        s(&f.positions),
        "--out",
        s(&blob),
    ]);
    assert_eq!(code, 0, "{err}");
    let mut bytes = std::fs::read(&blob).unwrap();
    bytes[30] ^= 1;
    std::fs::write(&blob, bytes).unwrap();
    let (code, _, err) = cli(&["inspect", s(&blob)]);
    assert_eq!(code, 1);
    assert!(err.contains("CRC-32 mismatch"), "{err}");
}

#[test]
fn a_missing_output_folder_is_named() {
    let tmp = tempdir();
    let dir: PathBuf = tmp.path().to_path_buf();
    let f = lab::write(&dir, 1);
    let missing = dir.join("nodir");
    for (args, out) in [
        (vec!["fit", s(&f.recording)], "u.blob"),
        (vec!["report", s(&f.recording)], "r.html"),
        (vec!["identify", s(&f.recording), "--csv"], "t.csv"),
    ] {
        let target = missing.join(out);
        let mut args = args.clone();
        if args[0] != "identify" {
            args.push("--out");
        }
        args.extend([s(&target), "--positions", s(&f.positions)]);
        let (code, _, err) = cli(&args);
        assert_eq!(code, 1, "{args:?}");
        assert_eq!(
            err,
            format!(
                "error: {}: cannot be written: `{}` does not exist (create the folder first, or give another path)\n",
                target.display(),
                missing.display()
            ),
            "{args:?}"
        );
    }
    assert!(!missing.exists());
}

/// The environment variable that makes [`umask_child`] run the CLI.
const CHILD: &str = "HF_LAB_UMASK_CHILD";

/// Run in a child process under a chosen umask (by [`outputs_get_the_mode_of_the_umask`]):
/// the commands that write files, into the folder named by [`CHILD`].
#[test]
#[ignore = "run by outputs_get_the_mode_of_the_umask in a child process"]
fn umask_child() {
    let Some(dir) = std::env::var_os(CHILD).map(PathBuf::from) else {
        return;
    };
    let f = lab::write(&dir, 1);
    let lot = dir.join("lot");
    std::fs::create_dir_all(&lot).unwrap();
    std::fs::copy(&f.recording, lot.join("a.csv")).unwrap();
    let p = s(&f.positions);
    for args in [
        vec!["fit", s(&f.recording), "--positions", p, "--out"],
        vec!["report", s(&f.recording), "--positions", p, "--out"],
        vec!["identify", s(&f.recording), "--positions", p, "--csv"],
        vec!["batch", s(&lot), "--positions", p, "--out"],
    ] {
        let out = dir.join(format!("out-{}", args[0]));
        let mut args = args.clone();
        args.push(s(&out));
        let (code, _, err) = cli(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
    }
}

#[cfg(unix)]
#[test]
fn outputs_get_the_mode_of_the_umask() {
    use std::os::unix::fs::PermissionsExt;
    let exe = std::env::current_exe().unwrap();
    for (umask, mode) in [("022", 0o644), ("027", 0o640), ("077", 0o600)] {
        let tmp = tempdir();
        let dir: PathBuf = tmp.path().to_path_buf();
        let status = Command::new("sh")
            .args(["-c", &format!("umask {umask} && exec \"$0\" \"$@\"")])
            .arg(&exe)
            .args(["umask_child", "--exact", "--ignored", "--test-threads=1"])
            .env(CHILD, &dir)
            .status()
            .unwrap();
        assert!(status.success(), "the child under umask {umask} failed");
        let mut files = vec![
            dir.join("lab-1.csv"),
            dir.join("truth-1.json"),
            dir.join("out-fit"),
            dir.join("out-report"),
            dir.join("out-identify"),
        ];
        for f in ["a.blob", "a.json", "summary.csv", "lot.csv"] {
            files.push(dir.join("out-batch").join(f));
        }
        for f in &files {
            let m = std::fs::metadata(f)
                .unwrap_or_else(|e| panic!("{}: {e}", f.display()))
                .permissions()
                .mode();
            assert_eq!(
                m & 0o777,
                mode,
                "{} under umask {umask}: mode {:o}",
                f.display(),
                m & 0o777
            );
        }
    }
}

/// Every command that reads recordings takes `--positions`, `--positions-for-check` and
/// `--unknown-orientations` (the last needs the first): the grammar accepts them (the
/// command then stops at the missing positions file, exit 1, not at its arguments,
/// exit 2).
#[test]
fn every_command_that_reads_recordings_takes_the_positions_options() {
    let tmp = tempdir();
    let dir: PathBuf = tmp.path().to_path_buf();
    let missing = dir.join("missing.csv");
    let options = [
        "--positions",
        s(&missing),
        "--positions-for-check",
        "V1,V2",
        "--unknown-orientations",
    ];
    let (rec, out) = (dir.join("r.csv"), dir.join("out"));
    std::fs::write(&rec, lab::positions_csv()).unwrap();
    for cmd in [
        vec!["identify", s(&rec)],
        vec!["fit", s(&rec), "--out", s(&out)],
        vec!["verify", s(&rec), "--blob", s(&rec)],
        vec!["report", s(&rec), "--out", s(&out)],
        vec!["diagnose", s(&rec)],
        vec!["batch", s(&dir), "--out", s(&out)],
    ] {
        let mut args = cmd.clone();
        args.extend(options);
        let (code, _, err) = cli(&args);
        // verify reads its blob first: the recording given as the blob is not one
        let reached = err.contains("missing.csv") || err.contains("not a blob");
        assert!(code == 1 && reached, "{}: exit {code}: {err}", cmd[0]);
        let mut alone = cmd.clone();
        alone.push("--unknown-orientations");
        let (code, _, err) = cli(&alone);
        assert_eq!(code, 2, "{}: --unknown-orientations alone: {err}", cmd[0]);
    }
    assert!(!out.exists());
}

#[test]
fn batch_reads_a_lab_s_own_positions() {
    let tmp = tempdir();
    let dir: PathBuf = tmp.path().to_path_buf();
    let lot = dir.join("lot");
    lab::write(&lot, 1);
    let f = lab::write(&lot, 2);
    // every *.csv of the lot's folder is a recording: the positions file lies apart
    let pos = dir.join("positions.csv");
    std::fs::rename(&f.positions, &pos).unwrap();
    let out = dir.join("out");
    let (code, _, err) = cli(&["batch", s(&lot), "--out", s(&out), "--jobs", "1"]);
    assert_eq!(code, 3);
    assert!(
        err.contains("unknown position name `F1`"),
        "without the file every unit is an error naming the position: {err}"
    );
    let (code, stdout, err) = cli(&[
        "batch",
        s(&lot),
        "--out",
        s(&out),
        "--jobs",
        "1",
        "--positions",
        s(&pos),
        "--force",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.starts_with("2 units in "), "{stdout}");
    assert!(stdout.contains("2 pass, 0 fail, 0 error"), "{stdout}");
    let unit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("lab-1.json")).unwrap()).unwrap();
    assert_eq!(unit["acceptance"], "pass", "{unit}");
    assert_eq!(unit["dwells_judged"], 16, "{unit}");
    // --positions-for-check: two of the four judged
    let (code, _, err) = cli(&[
        "batch",
        s(&lot),
        "--out",
        s(&out),
        "--jobs",
        "1",
        "--positions",
        s(&pos),
        "--positions-for-check",
        "V1,V2",
        "--force",
    ]);
    assert_eq!(code, 0, "{err}");
    let unit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("lab-1.json")).unwrap()).unwrap();
    assert_eq!(unit["dwells_judged"], 8, "{unit}");
}

#[test]
fn expected_notes_only_with_verbose_and_warnings_always() {
    let tmp = tempdir();
    let dir: PathBuf = tmp.path().to_path_buf();
    let f = lab::write(&dir, 1);
    // a warning that needs action (a rounded vector, normalised) must stay
    let (pos, _) = positions_with(&dir, "rounded.csv", "V5,0,0,1.005,verification");
    let run = |verbose: bool| {
        let blob = dir.join("u.blob");
        let mut args = vec![
            "fit",
            s(&f.recording),
            "--positions",
            s(&pos),
            "--out",
            s(&blob),
            "--force",
        ];
        if verbose {
            args.push("--verbose");
        }
        let (code, _, err) = cli(&args);
        assert_eq!(code, 0, "{err}");
        err
    };
    let quiet = run(false);
    let ramps = "dwells rest through temperature ramps";
    assert!(!quiet.contains(ramps), "{quiet}");
    assert_eq!(quiet.matches("warning: ").count(), 1, "{quiet}");
    assert!(quiet.contains("normalised"), "{quiet}");
    let verbose = run(true);
    assert_eq!(verbose.matches(ramps).count(), 1, "{verbose}");
    assert!(
        verbose.contains("note: ") && verbose.contains("normalised"),
        "{verbose}"
    );
}

/// The end of the first match of `pat` in `line`.
fn end_of(line: &str, pat: &str) -> usize {
    line.find(pat)
        .map(|i| i + pat.len())
        .unwrap_or_else(|| panic!("`{pat}` not in `{line}`"))
}

/// The text table: named, and each temperature's values end under its heading; columns
/// never touch.
fn check_text_table(out: &str) {
    let lines: Vec<&str> = out.lines().collect();
    assert!(
        lines[0].starts_with("max |dg| in the verification positions V1..V4, mg"),
        "{out}"
    );
    let heads: Vec<String> = lines[1]
        .split("   ")
        .map(str::trim)
        .filter(|h| h.ends_with(" C"))
        .map(String::from)
        .collect();
    assert_eq!(heads.len(), 4, "{}", lines[1]);
    for row in lines[2..]
        .iter()
        .take_while(|l| !l.starts_with("data-chosen"))
    {
        let cells: Vec<&str> = row.split_whitespace().collect();
        let values: Vec<&&str> = cells[2..]
            .iter()
            .filter(|c| !c.starts_with('(') && !c.ends_with(')'))
            .collect();
        assert_eq!(values.len(), heads.len(), "{row}");
        let mut from = 0;
        for (h, v) in heads.iter().zip(values) {
            let want = end_of(lines[1], h);
            let at = from + end_of(&row[from..], v);
            assert_eq!(
                at, want,
                "`{v}` does not end under `{h}`:\n{}\n{row}",
                lines[1]
            );
            from = at;
        }
        // columns never touch: a bracket is followed by three spaces or the line's end
        for (i, _) in row.match_indices(')') {
            let rest = &row[i + 1..];
            assert!(
                rest.is_empty() || rest.starts_with(' ') || rest.starts_with(')'),
                "{row}"
            );
        }
    }
}

/// The report of the lab's recording: the lab's position names in the headings and the
/// text table (never PP1..PP6), the table's columns aligned, the log axis labelled down
/// to the lowest value, the truth drawn as a reference and labelled so, the per-stop
/// values named in words, the held-out dwells ringed in the residual plot.
#[test]
fn the_report_of_a_lab_s_recording_speaks_its_language() {
    let tmp = tempdir();
    let dir: PathBuf = tmp.path().to_path_buf();
    let f = lab::write(&dir, 1);
    let html_path = dir.join("r.html");
    let (code, out, err) = cli(&[
        "report",
        s(&f.recording),
        "--positions",
        s(&f.positions),
        "--truth",
        s(&f.truth),
        "--out",
        s(&html_path),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("PP1") && !err.contains("PP1"), "{out}\n{err}");

    check_text_table(&out);

    let html = std::fs::read_to_string(&html_path).unwrap();
    assert!(!html.contains("PP1") && !html.contains("per-stop (10)"));
    assert!(
        html.contains(
            "<h2>Compensation error in the verification positions V1..V4 (formula (13))</h2>"
        ),
        "the section heading"
    );
    let doc = roxmltree::Document::parse_with_options(
        &html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    let figure = |id: &str| {
        doc.descendants()
            .find(|n| n.has_tag_name("figure") && n.attribute("id") == Some(id))
            .unwrap_or_else(|| panic!("no figure {id}"))
    };
    let data = |id: &str| -> serde_json::Value {
        let f = figure(id);
        let script = f.descendants().find(|n| n.has_tag_name("script")).unwrap();
        serde_json::from_str(script.text().unwrap()).unwrap()
    };
    let texts = |id: &str, class: &str| -> Vec<String> {
        figure(id)
            .descendants()
            .filter(|n| n.has_tag_name("text") && n.attribute("class") == Some(class))
            .map(|n| n.text().unwrap_or("").to_string())
            .collect()
    };
    assert_eq!(
        texts("max-dg", "title"),
        ["worst |dg| over the verification positions V1..V4"]
    );

    // the log axis: a labelled tick at or below the lowest value, and one within a
    // factor 2.5 above it (0.016-0.04 mg can be read)
    let max_dg = data("max-dg");
    let lowest = max_dg["series"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["points"].as_array().unwrap().iter())
        .map(|p| p[1].as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    let ticks: Vec<f64> = texts("max-dg", "tick y")
        .iter()
        .map(|t| t.parse().unwrap())
        .collect();
    assert!(lowest > 0.0 && lowest < 0.05, "{lowest}");
    assert!(
        ticks.iter().any(|t| *t <= lowest),
        "no tick label at or below {lowest} mg: {ticks:?}"
    );
    assert!(
        ticks.iter().any(|t| *t >= lowest && *t <= 2.5 * lowest),
        "no tick label within 2.5x above {lowest} mg: {ticks:?}"
    );

    // the truth: a line without markers, labelled as the twin's, in every coefficient
    // plot; the per-stop values named in words
    for c in ["kxx", "u0z"] {
        let d = data(&format!("coeff-{c}"));
        let series = d["series"].as_array().unwrap();
        let truth = series
            .iter()
            .find(|s| s["name"] == "truth (the twin's)")
            .unwrap_or_else(|| panic!("coeff-{c}: no truth"));
        assert_eq!(truth["marker"], "none");
        assert!(truth["line"].is_string() && truth["width"].as_f64().unwrap() >= 5.0);
        assert!(
            series
                .iter()
                .any(|s| s["name"] == "identified at each stop (formula (10))"),
            "coeff-{c}"
        );
    }
    let diff = data("coeff-kxx-diff");
    assert!(diff["series"]
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s["name"] == "identified at each stop (formula (10), ±1 sigma)"));

    // the held-out dwells ringed: one ring per axis of each verification dwell (4
    // positions x 4 stops), with its legend entry
    let res = data("residual-time");
    let ring = res["series"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["marker"] == "ring")
        .expect("held-out dwells marked");
    assert_eq!(
        ring["name"],
        "held out of every fit (verification positions V1..V4)"
    );
    assert_eq!(ring["points"].as_array().unwrap().len(), 3 * 16);
    let legend = figure("residual-time")
        .descendants()
        .filter(|n| n.attribute("class") == Some("legend-entry"))
        .filter_map(|n| n.descendants().find(|t| t.has_tag_name("text")))
        .any(|t| t.text() == ring["name"].as_str());
    assert!(legend, "the held-out dwells in the legend");
}
