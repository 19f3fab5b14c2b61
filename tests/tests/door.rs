//! The checks at the door (issue 29 item 2), each on a real file through the command
//! line: outputs in mV (or m/s2, or counts) whose recording states another unit, or
//! none; temperatures in Kelvin or Fahrenheit; a test cut short (its T0 outside the
//! data, or cut off on its way to its next stop). Each is named in words with its fix
//! before anything is fitted (the file, and the line and field where one applies), a
//! blob is refused unless `--allow` lets the data past (then a warning), and the twin's
//! complete recording passes every check without a word.
use host_fit::simulate::{simulate, SimConfig};
use std::path::{Path, PathBuf};
use tests::{cli, s};

/// The twin's production test of the paper unit (20 C, then stops at -40, -10, 20, 45
/// and 70 C; outputs in V, about 0.55 V per g).
fn twin() -> String {
    simulate(&SimConfig::default(), |_| {}).unwrap().csv
}

/// `csv` with `f` applied to the fields of every data row (t_s, position, temp_c,
/// chamber_c, ux_v, uy_v, uz_v); comments and the header kept.
fn map_rows(csv: &str, f: &dyn Fn(&mut [String])) -> String {
    let mut out = String::new();
    for l in csv.lines() {
        if l.starts_with('#') || l.starts_with("t_s") {
            out.push_str(l);
        } else {
            let mut v: Vec<String> = l.split(',').map(String::from).collect();
            f(&mut v);
            out.push_str(&v.join(","));
        }
        out.push('\n');
    }
    out
}

fn scaled(v: &mut [String], cols: std::ops::Range<usize>, f: &dyn Fn(f64) -> f64) {
    for x in &mut v[cols] {
        *x = format!("{}", f(x.parse::<f64>().unwrap()));
    }
}

/// `csv` with `line` added after its first line (a metadata line).
fn with_meta(csv: &str, line: &str) -> String {
    let (first, rest) = csv.split_once('\n').unwrap();
    format!("{first}\n{line}\n{rest}")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// `fit REC --out BLOB` with `extra`: (code, stdout, stderr, whether the blob exists).
fn fit(rec: &Path, extra: &[&str]) -> (i32, String, String, bool) {
    let blob = rec.with_extension("blob");
    let _ = std::fs::remove_file(&blob);
    let mut a = vec!["fit", s(rec), "--out", s(&blob)];
    a.extend_from_slice(extra);
    let (code, out, err) = cli(&a);
    (code, out, err, blob.exists())
}

#[test]
fn outputs_implausible_for_their_unit_are_named_with_the_unit_they_look_like() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let csv = twin();
    // the twin as it is: no word from the door
    let good = write(dir, "good.csv", &csv);
    let (code, _, err, made) = fit(&good, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(made && !err.contains("per g"), "{err}");

    // in mV without an output_unit line: refused before anything is fitted, naming the
    // file, the columns, the scale, the unit it looks like and the line that fixes it
    let mv = map_rows(&csv, &|v| scaled(v, 4..7, &|x| 1000.0 * x));
    let p = write(dir, "mv.csv", &mv);
    let (code, out, err, made) = fit(&p, &[]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(!made, "a blob was written");
    for words in [
        "mv.csv: field `ux_v..uz_v`: the outputs change by about 55",
        "implausible for V (the default: the recording has no `# output_unit=` line)",
        "they look like mV or mg",
        "state the unit in the recording (`# output_unit=mV`)",
        "`--allow output-scale`",
    ] {
        assert!(err.contains(words), "`{words}` not in {err}");
    }
    // every command that reads it says the same
    for cmd in ["identify", "diagnose"] {
        let (code, _, e) = cli(&[cmd, s(&p)]);
        assert_eq!(code, 1, "{cmd}: {e}");
        assert!(e.contains("they look like mV"), "{cmd}: {e}");
    }
    // the fix it names works; `--allow` lets the numbers past with a warning
    let stated = write(dir, "mv-stated.csv", &with_meta(&mv, "# output_unit=mV"));
    let (code, _, err, made) = fit(&stated, &[]);
    assert!(code == 0 && made, "{err}");
    assert!(!err.contains("per g"), "{err}");
    let (code, _, err, made) = fit(&p, &["--allow", "output-scale"]);
    assert!(code == 0 && made, "{err}");
    assert!(
        err.contains("warning: ") && err.contains("(let past by --allow output-scale)"),
        "{err}"
    );

    // m/s2 stated as g, and integer counts stated as nothing: each named
    let ms2 = map_rows(&csv, &|v| scaled(v, 4..7, &|x| x / 0.55 * 9.80665));
    let p = write(dir, "ms2.csv", &with_meta(&ms2, "# output_unit=g"));
    let (code, _, err, _) = fit(&p, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("implausible for `# output_unit=g`") && err.contains("look like m/s2"),
        "{err}"
    );
    let counts = map_rows(&csv, &|v| scaled(v, 4..7, &|x| (x * 2000.0).round()));
    let p = write(dir, "counts.csv", &counts);
    let (code, _, err, _) = fit(&p, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("they look like counts (they are all integers)"),
        "{err}"
    );
}

#[test]
fn temperatures_in_kelvin_or_fahrenheit_are_refused_with_the_conversion() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let csv = twin();
    // temp_c and chamber_c in K
    let k = write(
        dir,
        "kelvin.csv",
        &map_rows(&csv, &|v| scaled(v, 2..4, &|x| x + 273.15)),
    );
    let (code, out, err, made) = fit(&k, &[]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(!made);
    // the line of the hottest reading, the field, the scale and the conversion
    let at = err.find("kelvin.csv:").expect("the file named") + "kelvin.csv:".len();
    let line: usize = err[at..].split(':').next().unwrap().parse().unwrap();
    let hottest = csv
        .lines()
        .nth(line - 1)
        .unwrap()
        .split(',')
        .nth(2)
        .unwrap()
        .parse::<f64>()
        .unwrap();
    assert!(hottest > 69.0, "line {line}: {hottest} C");
    for words in [
        "field `temp_c`: the unit's temperatures read 233.",
        "all of them above 130 C",
        "they look like Kelvin (-39.",
        "convert the column (temp_c = K - 273.15)",
    ] {
        assert!(err.contains(words), "`{words}` not in {err}");
    }
    // verify reads recordings too: the same refusal
    let good = write(dir, "good.csv", &csv);
    let (code, _, err0, _) = fit(&good, &[]);
    assert_eq!(code, 0, "{err0}");
    let (code, _, e) = cli(&["verify", s(&k), "--blob", s(&good.with_extension("blob"))]);
    assert_eq!(code, 1, "{e}");
    assert!(e.contains("they look like Kelvin"), "{e}");

    // in F: the hottest readings give it away
    let f = write(
        dir,
        "fahrenheit.csv",
        &map_rows(&csv, &|v| scaled(v, 2..4, &|x| x * 1.8 + 32.0)),
    );
    let (code, _, err, made) = fit(&f, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(!made);
    for words in [
        "fahrenheit.csv:",
        "field `temp_c`",
        "the hottest above 130 C",
        "they look like Fahrenheit (-39.",
        "convert the column (temp_c = (F - 32) / 1.8)",
        "`--allow temperature-scale` if they really are C",
    ] {
        assert!(err.contains(words), "`{words}` not in {err}");
    }
    let (code, _, err, made) = fit(&f, &["--allow", "temperature-scale"]);
    assert!(code == 0 && made, "{err}");
    assert!(
        err.contains("(let past by --allow temperature-scale)"),
        "{err}"
    );
}

/// The data rows of `csv` up to the first row (after the cold stop) where `stop(temp)`
/// holds: a test cut short.
fn cut(csv: &str, stop: &dyn Fn(f64) -> bool) -> String {
    let mut out = String::new();
    let mut cold = false;
    for l in csv.lines() {
        if !l.starts_with('#') && !l.starts_with("t_s") {
            let t: f64 = l.split(',').nth(2).unwrap().parse().unwrap();
            cold |= t < -35.0;
            if cold && stop(t) {
                break;
            }
        }
        out.push_str(l);
        out.push('\n');
    }
    out
}

#[test]
fn a_test_cut_short_is_refused_where_a_blob_is_made_and_warned_where_it_is_studied() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let csv = twin();
    // aborted on the way from the -10 C stop back up: its stops cover -40..-10 C, its
    // T0 (20 C) is outside them
    let short = write(dir, "short.csv", &cut(&csv, &|t| t > -5.0));
    let (code, out, err, made) = fit(&short, &[]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(!made);
    for words in [
        "short.csv: field `t0_c`: the reference temperature T0 = 20 C (stated by `# t0_c=`) lies outside the -39.",
        "the acceptance's band of +-5 C about T0 could not be judged",
        "run the rest of it",
        "`--allow partial`",
    ] {
        assert!(err.contains(words), "`{words}` not in {err}");
    }
    // let past: fitted over what it covers, with the warning
    let (code, out, err, made) = fit(&short, &["--allow", "partial"]);
    assert!(code == 0 && made, "{err}");
    assert!(err.contains("(let past by --allow partial)"), "{err}");
    assert!(out.contains("valid -40.46..-9.5"), "{out}");
    // a study of it is not refused: warned
    let (code, _, err) = cli(&["identify", s(&short)]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: ") && err.contains("field `t0_c`"),
        "{err}"
    );

    // cut off while heating from the 20 C stop to the next: it covers its T0, and ends
    // still ramping away from where it began
    let cutoff = write(dir, "cutoff.csv", &cut(&csv, &|t| t > 27.0));
    let (code, _, err, made) = fit(&cutoff, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(!made);
    let last_line = std::fs::read_to_string(&cutoff).unwrap().lines().count();
    for words in [
        format!("cutoff.csv:{last_line}: field `temp_c`: the recording ends while the temperature still rises"),
        "away from the 20.0 C it began at), past the -39.".to_string(),
        "the test looks cut off before its next stop".to_string(),
    ] {
        assert!(err.contains(&words), "`{words}` not in {err}");
    }

    // a batch: the cut unit is an error with the reason, the complete one passes
    let units = dir.join("units");
    std::fs::create_dir_all(&units).unwrap();
    std::fs::write(units.join("cut.csv"), std::fs::read(&cutoff).unwrap()).unwrap();
    std::fs::write(units.join("whole.csv"), &csv).unwrap();
    let run = |extra: &[&str]| {
        let out = dir.join(format!("out{}", extra.len()));
        let mut a = vec!["batch", s(&units), "--out", s(&out), "--no-db"];
        a.extend_from_slice(extra);
        let (code, stdout, err) = cli(&a);
        (
            code,
            stdout,
            err,
            std::fs::read_to_string(out.join("summary.csv")).unwrap(),
        )
    };
    let (code, out, err, summary) = run(&[]);
    assert_eq!(code, 3, "{out}{err}");
    let row = summary.lines().find(|l| l.contains("cut.csv")).unwrap();
    assert!(
        row.contains(",error,") && row.contains("cut off before its next stop"),
        "{row}"
    );
    assert!(
        summary
            .lines()
            .any(|l| l.contains("whole.csv") && l.contains(",pass,")),
        "{summary}"
    );
    let (_, _, _, summary) = run(&["--allow", "partial"]);
    let row = summary.lines().find(|l| l.contains("cut.csv")).unwrap();
    assert!(!row.contains(",error,"), "{row}");
}
