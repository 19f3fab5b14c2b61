//! The line's memory end to end: `fit`, `verify`, `diagnose` and `batch` record what they
//! made (values compared with their own outputs and files, not only counted), `history`
//! lists a unit's records in order with its latest calibration marked and re-issues a
//! stored blob bit for bit, `trend` flags a process shift made with the twin (an offset
//! that moves from a lot on) with the rule such a shift trips, and a stable process no
//! more than the stated false-alarm rate; bad stores are refused, named, left alone.
use host_fit::simulate::{PAPER_UNIT, PAPER_UNIT_TEMPS};
use host_fit::store::record::{blob_run_id, Command, Record};
use host_fit::store::trend::all_rules_rate;
use host_fit::store::Store;
use serde_json::Value;
use std::path::{Path, PathBuf};
use tests::{cli, cli_json};

mod reports;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The SHA-256 of a file by coreutils (not by the code under test).
fn sha256sum(p: &Path) -> String {
    let o = std::process::Command::new("sha256sum")
        .arg(p)
        .output()
        .unwrap();
    String::from_utf8(o.stdout).unwrap()[..64].to_string()
}

/// A twin configuration of unit `serial`: the paper unit with its x offset moved by
/// `shift_v` at every temperature.
fn unit_toml(serial: &str, shift_v: f64) -> String {
    let rows: Vec<String> = PAPER_UNIT
        .iter()
        .map(|r| {
            let mut r = *r;
            r[9] += shift_v;
            format!("{:?}", r.to_vec())
        })
        .collect();
    format!(
        "[unit]\nserial = \"{serial}\"\nmodel = \"table\"\ntemps_c = {:?}\ncoeffs = [{}]\n",
        PAPER_UNIT_TEMPS.to_vec(),
        rows.join(", ")
    )
}

/// A lot of `n` units made by `host-fit simulate` (serials `LOT-i`, seeds from `seed0`)
/// in `root/LOT`.
fn lot(root: &Path, name: &str, n: usize, seed0: u64, shift_v: f64) -> PathBuf {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    let cfgs = root.join("configs");
    std::fs::create_dir_all(&cfgs).unwrap();
    for i in 0..n {
        let serial = format!("{name}-{i:02}");
        let cfg = cfgs.join(format!("{serial}.toml"));
        std::fs::write(&cfg, unit_toml(&serial, shift_v)).unwrap();
        let seed = (seed0 + i as u64).to_string();
        let out = dir.join(format!("{serial}.csv"));
        let (code, _, err) = cli(&["simulate", s(&cfg), "--seed", &seed, "--out", s(&out)]);
        assert_eq!(code, 0, "{err}");
    }
    dir
}

fn records(db: &Path) -> Vec<Record> {
    Store::open_existing(db).unwrap().all().unwrap()
}

/// Equal to the last digit JSON keeps (serde_json reads a float to within an ulp).
fn close(a: f64, b: f64) {
    assert!((a - b).abs() <= 1e-14 * a.abs().max(b.abs()), "{a} != {b}");
}

fn worst(v: &Value) -> f64 {
    v["max_by_temperature"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["max_abs_dg_mg"].as_f64().unwrap())
        .fold(0.0, f64::max)
}

/// What `fit`, `verify` and `diagnose` recorded holds what they made and printed.
fn assert_records_hold_what_was_made(
    all: &[Record],
    rec: &Path,
    (fb, dblob): (&Path, &Path),
    (fit, ver, diag): (&Value, &Value, &Value),
) {
    let cmds: Vec<Command> = all.iter().map(|r| r.command).collect();
    assert_eq!(cmds, [Command::Fit, Command::Verify, Command::Diagnose]);
    let sha = sha256sum(rec);
    for r in all {
        assert_eq!(r.serial, "PAPER-UNIT");
        assert_eq!(r.input, s(rec));
        assert_eq!(r.input_sha256.as_deref(), Some(sha.as_str()));
        assert_eq!(r.version, env!("CARGO_PKG_VERSION"));
        assert!(
            r.commit == "unknown"
                || (r.commit.len() == 40 && r.commit.bytes().all(|c| c.is_ascii_hexdigit())),
            "{}",
            r.commit
        );
        assert!(host_fit::store::clock::parse(&r.time_utc, false).is_some());
        assert_eq!(
            r.output_unit,
            Some(host_fit::data::output_unit::OutputUnit::Volt)
        );
    }
    let (f, v, d) = (&all[0], &all[1], &all[2]);
    // fit: its options, model, blob, coefficients at T0 (the blob's f32 row dT^0)
    assert_eq!(f.lot.as_deref(), Some("L7"));
    assert_eq!(f.options["lot"], "L7");
    assert_eq!(f.options["out"], s(fb));
    assert_eq!(f.options["route"], "auto");
    assert_eq!(f.options["json"], true);
    assert_eq!(f.model.as_deref(), fit["model"].as_str());
    assert_eq!(f.blob.as_deref(), Some(&std::fs::read(fb).unwrap()[..]));
    let at = f.at_t0.unwrap();
    assert_eq!(at.t0_c, fit["t0_c"].as_f64().unwrap());
    let insp = cli_json(&["inspect", s(fb), "--json"]);
    // the table's row at T0: a polynomial's dT^0, or a piecewise-linear model's 20 C
    let row = insp["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["at"] == "dT^0" || r["at"] == "20 C")
        .unwrap_or_else(|| panic!("no row at T0: {insp}"));
    for (c, x) in row["values"].as_array().unwrap().iter().enumerate() {
        let x = x.as_f64().unwrap();
        assert!(
            (x - at.values[c]).abs() <= 1e-7 * x.abs().max(1e-3),
            "{c}: {x} {}",
            at.values[c]
        );
    }
    let sigma = at.sigma.expect("a fit's 1-sigma");
    assert!(sigma.iter().all(|s| *s > 1e-8 && *s < 1e-4), "{sigma:?}");
    // verify: the blob it verified, the verdict, the worst |dg|
    assert_eq!(v.blob, f.blob);
    let j = v.judged.as_ref().unwrap();
    assert_eq!(
        Some(j.verdict),
        ver["acceptance"].as_str().unwrap().parse().ok()
    );
    assert_eq!(j.reason, ver["reason"].as_str().unwrap());
    close(v.worst_dg_mg.unwrap(), worst(ver));
    assert!(v.at_t0.unwrap().sigma.is_none());
    // the blobs carry their run's id: the fit's as `inspect` and the firmware read it,
    // the verified one the fit's, the diagnosis' its own
    let fit_bytes = std::fs::read(fb).unwrap();
    assert_eq!(insp["run_id"], f.run_id.to_string());
    let view = firmware_core::blob::BlobView::new(&fit_bytes).unwrap();
    assert_eq!(view.run_id().0, f.run_id.0);
    assert_eq!(blob_run_id(v.blob.as_ref().unwrap()), Some(f.run_id));
    assert_eq!(blob_run_id(d.blob.as_ref().unwrap()), Some(d.run_id));
    // diagnose: the contract's verdict and findings, its blob
    assert_eq!(
        d.diagnosis_verdict,
        diag["verdict"].as_str().unwrap().parse().ok()
    );
    assert_eq!(d.findings.as_ref(), Some(&diag["findings"]));
    assert_eq!(d.blob.as_deref(), Some(&std::fs::read(dblob).unwrap()[..]));
}

/// `history` lists the records oldest first, the latest calibration marked, and
/// re-issues stored blobs bit for bit, never over a file without `--force`.
fn assert_history_and_blobs(root: &Path, db: &Path, all: &[Record], (fb, dblob): (&Path, &Path)) {
    let db_s = s(db);
    let (f, d) = (&all[0], &all[2]);
    // history: oldest first, the diagnosis' blob is the latest calibration
    let h = cli_json(&["history", "PAPER-UNIT", "--db", db_s, "--json"]);
    let ids: Vec<i64> = h["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["id"].as_i64().unwrap())
        .collect();
    assert_eq!(ids, [1, 2, 3]);
    let latest: Vec<bool> = h["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["latest"].as_bool().unwrap())
        .collect();
    assert_eq!(latest, [false, false, true]);
    assert_eq!(h["records"][0]["run_id"], f.run_id.to_string());
    let (code, text, _) = cli(&["history", "PAPER-UNIT", "--db", db_s]);
    assert_eq!(code, 0);
    let marked: Vec<&str> = text.lines().filter(|l| l.starts_with("* #")).collect();
    assert_eq!(marked.len(), 1, "{text}");
    assert!(
        marked[0].starts_with("* #3 ") && marked[0].contains("diagnose"),
        "{text}"
    );

    // --blob RUN re-issues the fit's blob bit for bit, by a prefix of its run id
    let again = root.join("again.blob");
    let run = f.run_id.to_string();
    let h = |extra: &[&str]| {
        let mut a = vec!["history", "PAPER-UNIT", "--db", db_s];
        a.extend_from_slice(extra);
        cli(&a)
    };
    let (code, out, err) = h(&["--blob", &run[..8], "--out", s(&again)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&run), "{out}");
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(fb).unwrap());
    // never over a file without --force; with it, the diagnosis' blob
    let (code, _, err) = h(&["--blob", &d.run_id.to_string(), "--out", s(&again)]);
    assert_eq!(code, 1);
    assert!(
        err.contains("--force") && err.contains("again.blob"),
        "{err}"
    );
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(fb).unwrap());
    let (code, _, err) = h(&[
        "--blob",
        &d.run_id.to_string(),
        "--out",
        s(&again),
        "--force",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        std::fs::read(&again).unwrap(),
        std::fs::read(dblob).unwrap()
    );
    // a run of another unit, a prefix too short
    let (code, _, err) = cli(&[
        "history",
        "OTHER",
        "--db",
        db_s,
        "--blob",
        &run,
        "--out",
        s(&root.join("x.blob")),
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("of unit `PAPER-UNIT`"), "{err}");
    let (code, _, err) = h(&["--blob", &run[..4], "--out", s(&root.join("x.blob"))]);
    assert_eq!(code, 1);
    assert!(err.contains("6 or more"), "{err}");
}

/// `fit`, `verify` and `diagnose` with `--db`: one record each, holding what each made.
#[test]
fn fit_verify_and_diagnose_record_what_they_made_and_history_re_issues_blobs() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().to_path_buf();
    let rec = root.join("unit.csv");
    let (code, _, err) = cli(&["simulate", "--seed", "3", "--out", s(&rec)]);
    assert_eq!(code, 0, "{err}");
    let db = root.join("line.sqlite");
    let (fb, db_s) = (root.join("fit.blob"), s(&db));
    let fit = cli_json(&[
        "fit",
        s(&rec),
        "--out",
        s(&fb),
        "--db",
        db_s,
        "--lot",
        "L7",
        "--json",
    ]);
    let (code, out, err) = cli(&["verify", s(&rec), "--blob", s(&fb), "--db", db_s, "--json"]);
    assert!(code == 0 || code == 3, "{err}");
    let ver: Value = serde_json::from_str(&out).unwrap();
    let dblob = root.join("diag.blob");
    let diag = cli_json(&[
        "diagnose",
        s(&rec),
        "--out",
        s(&dblob),
        "--db",
        db_s,
        "--json",
    ]);

    let all = records(&db);
    assert_records_hold_what_was_made(&all, &rec, (&fb, &dblob), (&fit, &ver, &diag));

    assert_history_and_blobs(&root, &db, &all, (&fb, &dblob));

    // calibrated again: every record stays, the new fit is the latest
    let fb2 = root.join("fit2.blob");
    cli_json(&[
        "fit",
        s(&rec),
        "--out",
        s(&fb2),
        "--db",
        db_s,
        "--model",
        "pwl",
        "--json",
    ]);
    let all2 = records(&db);
    assert_eq!(all2.len(), 4);
    assert_eq!(all2[..3], all[..]);
    let h = cli_json(&["history", "PAPER-UNIT", "--db", db_s, "--json"]);
    let latest: Vec<bool> = h["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["latest"].as_bool().unwrap())
        .collect();
    assert_eq!(latest, [false, false, false, true]);
    assert!(
        all2[3].model.as_ref().unwrap().starts_with("pwl"),
        "{:?}",
        all2[3].model
    );
}

/// The flagged points of chart `q` in a `trend --json`: (unit place, rules).
fn flags(t: &Value, q: &str) -> Vec<(usize, Vec<u64>)> {
    t["charts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["quantity"] == q)
        .unwrap_or_else(|| panic!("no chart {q}"))["flags"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["unit"].as_u64().unwrap() as usize,
                f["rules"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|r| r.as_u64().unwrap())
                    .collect(),
            )
        })
        .collect()
}

/// A batch without `--db` records into its output folder, each unit as its own files say.
fn assert_default_store_matches_the_files(root: &Path, dir: &Path, n: usize) {
    let own = root.join("out-default");
    let (code, _, err) = cli(&["batch", s(dir), "--out", s(&own), "--jobs", "2"]);
    assert!(code == 0 || code == 3, "{err}");
    let recs = records(&own.join("records.sqlite"));
    assert_eq!(recs.len(), n);
    let summary = std::fs::read_to_string(own.join("summary.csv")).unwrap();
    let mut rd = csv::Reader::from_reader(summary.as_bytes());
    for row in rd.records() {
        let row = row.unwrap();
        let (unit, file, acc, reason) = (&row[0], &row[1], &row[2], &row[3]);
        let r = recs
            .iter()
            .find(|r| r.serial == unit)
            .unwrap_or_else(|| panic!("{unit}"));
        assert_eq!(r.command, Command::Batch);
        assert_eq!(r.input, file);
        assert_eq!(r.lot.as_deref(), Some("L1"));
        assert_eq!(
            r.input_sha256.as_deref(),
            Some(sha256sum(Path::new(file)).as_str())
        );
        let j = r.judged.as_ref().unwrap();
        assert_eq!((j.verdict.name(), j.reason.as_str()), (acc, reason));
        let blob = own.join(format!("{unit}.blob"));
        assert_eq!(r.blob.as_deref(), Some(&std::fs::read(&blob).unwrap()[..]));
        assert_eq!(blob_run_id(r.blob.as_ref().unwrap()), Some(r.run_id));
        let uj: Value = serde_json::from_str(
            &std::fs::read_to_string(own.join(format!("{unit}.json"))).unwrap(),
        )
        .unwrap();
        close(
            r.worst_dg_mg.unwrap(),
            uj["max_abs_dg_mg_method1"].as_f64().unwrap(),
        );
        assert_eq!(r.model.as_deref(), uj["model"].as_str());
        assert!(r.at_t0.unwrap().sigma.is_some());
    }
}

/// Lots made by the twin, batched into one store (one job: units in file order): the
/// batch records every unit as its own files say; from lot 5 on the units' x offset is
/// 3 uV higher (2.7 times the lot's own spread of u0x): `trend` flags at least half the
/// shifted units on u0x, with Nelson 2 (nine on one side, the rule of a sustained shift)
/// and Nelson 1 there and nowhere before, and the stable units of every chart no more
/// often than the false-alarm rate stated for a reference of 20 units allows.
#[test]
fn batches_record_every_unit_and_trend_flags_a_shift_across_lots() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().to_path_buf();
    let shared = root.join("line.sqlite");
    let (stable, per_stable, per_shifted) = (4, 10, 8);
    let mut made = 0;
    for l in 1..=6 {
        let name = format!("L{l}");
        let (n, shift) = if l <= stable {
            (per_stable, 0.0)
        } else {
            (per_shifted, 3e-6)
        };
        let dir = lot(&root, &name, n, 1000 * l as u64, shift);
        let out = root.join(format!("out-{name}"));
        let (code, text, err) = cli(&[
            "batch",
            s(&dir),
            "--out",
            s(&out),
            "--db",
            s(&shared),
            "--jobs",
            "1",
        ]);
        assert!(code == 0 || code == 3, "{err}");
        assert!(
            text.contains(&format!("records: {n} units recorded")),
            "{text}"
        );
        made += n;
        if l == 1 {
            assert_default_store_matches_the_files(&root, &dir, n);
        }
    }
    assert_eq!(records(&shared).len(), made);

    let html = root.join("trend.html");
    let reference = stable / 2 * per_stable;
    let t = cli_json(&[
        "trend",
        "--db",
        s(&shared),
        "--out",
        s(&html),
        "--reference-first",
        &reference.to_string(),
        "--json",
    ]);
    assert_eq!(t["unit_count"], made);
    let shift_at = stable * per_stable;
    let u0x = flags(&t, "u0x");
    let shifted: Vec<usize> = u0x
        .iter()
        .filter(|f| f.0 >= shift_at)
        .map(|f| f.0)
        .collect();
    assert!(
        shifted.len() * 2 >= made - shift_at,
        "{} of {} shifted units flagged: {u0x:?}",
        shifted.len(),
        made - shift_at
    );
    // nine on one side and beyond 3 sigma: only after the shift (before it, a stable
    // process's false alarms of the other rules are counted below)
    for rule in [1, 2] {
        let at: Vec<usize> = u0x
            .iter()
            .filter(|f| f.1.contains(&rule))
            .map(|f| f.0)
            .collect();
        assert!(
            !at.is_empty() && at.iter().all(|u| *u >= shift_at),
            "Nelson {rule} on u0x: {u0x:?}"
        );
    }
    // the stable units after the reference, on every chart: flagged no more often than
    // the rate stated for limits from a reference of this size (5.4 % for 20 units),
    // with half of it again for the sampling of 260 points whose flags come in runs
    let mut stable_flags = 0;
    let charts = t["charts"].as_array().unwrap();
    for c in charts {
        let q = c["quantity"].as_str().unwrap();
        stable_flags += flags(&t, q)
            .iter()
            .filter(|f| f.0 >= reference && f.0 < shift_at)
            .count();
    }
    let points = charts.len() * (shift_at - reference);
    let rate = stable_flags as f64 / points as f64;
    println!("stable points flagged: {stable_flags} of {points} ({rate:.4}); u0x: {u0x:?}");
    let stated = all_rules_rate(reference).unwrap();
    assert!(
        rate <= 1.5 * stated,
        "{stable_flags} of {points} stable points flagged ({rate:.3}), stated {stated}"
    );
    // the report draws it: the u0x chart has a series for Nelson 2, over its data
    let page = std::fs::read_to_string(&html).unwrap();
    let figures = reports::check_plots(&page);
    let u = figures
        .iter()
        .find(|f| f.id == "trend-u0x")
        .expect("a u0x chart");
    let names: Vec<&str> = u.data["series"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert!(
        names.iter().any(|n| n.starts_with("Nelson 2:")),
        "{names:?}"
    );
    assert_eq!(figures.len(), 13);
    // a date range as the reference: the whole period is every unit
    let (code, out, err) = cli(&[
        "trend",
        "--db",
        s(&shared),
        "--out",
        s(&html),
        "--force",
        "--reference-from",
        "2000-01-01",
        "--reference-to",
        "2999-12-31",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&format!("({made} calibrations)")), "{out}");
}

/// A store of a newer schema, cut short, not a database, empty or missing: every command
/// refuses it naming the file and the reason, leaves it as it was, and writes nothing.
#[test]
fn bad_stores_are_refused_named_and_left_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().to_path_buf();
    let rec = root.join("unit.csv");
    let (code, _, err) = cli(&["simulate", "--seed", "5", "--out", s(&rec)]);
    assert_eq!(code, 0, "{err}");
    let good = root.join("good.sqlite");
    for i in 0..3 {
        cli_json(&[
            "fit",
            s(&rec),
            "--out",
            s(&root.join(format!("f{i}.blob"))),
            "--db",
            s(&good),
            "--json",
        ]);
    }
    let newer = root.join("newer.sqlite");
    std::fs::copy(&good, &newer).unwrap();
    rusqlite::Connection::open(&newer)
        .unwrap()
        .execute_batch("PRAGMA user_version = 7;")
        .unwrap();
    let cut = root.join("cut.sqlite");
    let bytes = std::fs::read(&good).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let text = root.join("text.sqlite");
    std::fs::write(&text, "serial,time\nA,now\n".repeat(20)).unwrap();
    let empty = root.join("empty.sqlite");
    std::fs::write(&empty, "").unwrap();
    let units = root.join("units");
    std::fs::create_dir_all(&units).unwrap();
    std::fs::copy(&rec, units.join("unit.csv")).unwrap();
    for (store, why) in [
        (&newer, "schema version 7"),
        (&cut, "cut short"),
        (&text, "not an SQLite database"),
        (&empty, "is empty"),
    ] {
        let before = std::fs::read(store).unwrap();
        let blob = root.join("new.blob");
        let out = root.join("batch-out");
        for args in [
            vec!["history", "PAPER-UNIT", "--db", s(store)],
            vec!["trend", "--db", s(store), "--out", s(&root.join("t.html"))],
            vec!["fit", s(&rec), "--out", s(&blob), "--db", s(store)],
            vec!["batch", s(&units), "--out", s(&out), "--db", s(store)],
        ] {
            let (code, _, err) = cli(&args);
            assert_eq!(code, 1, "{args:?}");
            assert!(
                err.contains(s(store)) && err.contains(why),
                "{args:?}: {err}"
            );
            assert_eq!(
                std::fs::read(store).unwrap(),
                before,
                "{args:?} changed {}",
                s(store)
            );
            // the record comes first: no blob leaves without it
            assert!(!blob.exists(), "{args:?} wrote a blob");
            assert!(
                !out.join("unit.blob").exists(),
                "{args:?} wrote a batch blob"
            );
        }
    }
    let (code, _, err) = cli(&["history", "X", "--db", s(&root.join("none.sqlite"))]);
    assert_eq!(code, 1);
    assert!(err.contains("no record store"), "{err}");
    assert!(!root.join("none.sqlite").exists());
    // a newer store's version is named by name
    let (_, _, err) = cli(&["history", "PAPER-UNIT", "--db", s(&newer)]);
    let known = host_fit::store::schema::SCHEMA_VERSION;
    assert!(
        err.contains(&format!("reads versions up to {known}")),
        "{err}"
    );
}

/// The demo records every blob it writes in its folder's store and ends by printing the
/// unit's history, the data-chosen model marked as its calibration; run again with
/// `--force` it appends.
#[test]
fn the_demo_records_its_blobs_and_shows_the_history() {
    let demo = tests::demo::demo();
    let (dir, out) = (&demo.dir, &demo.out);
    let db = dir.join("records.sqlite");
    let all = records(&db);
    // the paper's pwl-2, the pwl through every stop, the plan's blob, the chosen model
    assert_eq!(all.len(), 4);
    let sha = sha256sum(&dir.join("recording.csv"));
    let plan_sha = sha256sum(&dir.join("plan-recording.csv"));
    for r in &all {
        assert_eq!(r.command, Command::Demo);
        let want = if r.options["blob"] == "plan.blob" {
            &plan_sha
        } else {
            &sha
        };
        assert_eq!(r.input_sha256.as_deref(), Some(want.as_str()));
        let file = r.options["blob"].as_str().unwrap();
        assert_eq!(
            blob_run_id(r.blob.as_ref().unwrap()),
            Some(r.run_id),
            "{file}"
        );
        assert_eq!(
            r.blob.as_deref(),
            Some(&std::fs::read(dir.join(file)).unwrap()[..]),
            "{file}"
        );
    }
    assert_eq!(all[2].options["blob"], "plan.blob");
    assert_eq!(all[3].options["blob"], "chosen.blob");
    // the history printed is the store's, the chosen model marked
    let shown = &out[out.find("unit PAPER-UNIT: 4 records").expect("the history")..];
    let (code, text, _) = cli(&["history", "PAPER-UNIT", "--db", s(&db)]);
    assert_eq!(code, 0);
    assert_eq!(shown.trim_end(), text.trim_end());
    let marked: Vec<&str> = text.lines().filter(|l| l.starts_with("* #")).collect();
    assert!(
        marked.len() == 1 && marked[0].starts_with("* #4 "),
        "{text}"
    );
    assert!(text.contains("model chosen-poly4"), "{text}");
    // run again with --force over a copy (the run is shared): the store appends
    let tmp = tempfile::tempdir().unwrap();
    let copy = tmp.path().join("demo-out");
    demo.copy_to(&copy);
    let (code, _, err) = cli(&["demo", "--out", s(&copy), "--force"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(records(&copy.join("records.sqlite")).len(), 8);
}
