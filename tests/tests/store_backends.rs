//! The record store on both backends, SQLite and a real PostgreSQL server (see
//! `tests/src/pg.rs`): a hostile serial is stored as text; a store moves between
//! backends with every record, bit for bit, and `history` and `trend` read the same from
//! each; a password in the URL appears in no output, record, file or report; an older
//! store is upgraded by `store migrate` and a newer one refused; the trend plots every
//! calibration (recalibrations marked) on whole-number axes with limits inside the
//! quantity's bounds; a bad `--db` leaves no output folder.
use host_fit::simulate::{simulate, SimConfig};
use host_fit::store::record::Record;
use host_fit::store::schema::{migrations, Dialect, SCHEMA_VERSION};
use host_fit::store::{Location, Store};
use serde_json::Value;
use std::path::{Path, PathBuf};
use tests::{cli, cli_json, pg, s};

/// A fast unit of the twin: one row per dwell (a voltmeter that averages each
/// position), the paper's profile, serial `serial`.
fn unit(dir: &Path, file: &str, serial: &str, seed: u64) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let mut cfg = SimConfig {
        seed,
        ..SimConfig::default()
    };
    cfg.unit.serial = serial.to_string();
    cfg.schedule.dwell_means = true;
    let p = dir.join(file);
    std::fs::write(&p, simulate(&cfg, |_| {}).unwrap().csv).unwrap();
    p
}

/// A lot of `n` fast units `PREFIX-i` in `dir`.
fn lot(dir: &Path, prefix: &str, n: u64, seed0: u64) {
    for i in 0..n {
        unit(
            dir,
            &format!("{prefix}-{i:02}.csv"),
            &format!("{prefix}-{i:02}"),
            seed0 + i,
        );
    }
}

fn ok(args: &[&str]) -> String {
    let (code, out, err) = cli(args);
    assert!(code == 0 || code == 3, "{args:?}: {code}\n{out}\n{err}");
    out
}

fn records(db: &str) -> Vec<Record> {
    Store::open_existing(Location::parse(db).unwrap())
        .unwrap()
        .all()
        .unwrap()
}

/// Both backends: a new SQLite file in `dir`, a new PostgreSQL database.
fn stores(dir: &Path, name: &str) -> [String; 2] {
    [
        dir.join(format!("{name}.sqlite")).display().to_string(),
        pg::database(name),
    ]
}

#[test]
fn a_hostile_serial_is_stored_as_text_on_both_backends() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let evil = "X'); DROP TABLE runs;--";
    let rec = unit(root, "evil.csv", evil, 4);
    let plain = unit(root, "plain.csv", "PLAIN-1", 5);
    for db in stores(root, "hostile") {
        for (r, name) in [(&plain, "plain"), (&rec, "evil")] {
            let blob = root.join(format!("{name}-{}.blob", db.len()));
            ok(&["fit", s(r), "--out", s(&blob), "--db", &db, "--json"]);
        }
        let all = records(&db);
        assert_eq!(all.len(), 2, "{db}");
        assert_eq!(all[1].serial, evil);
        let h = cli_json(&["history", evil, "--db", &db, "--json"]);
        assert_eq!(h["records"].as_array().unwrap().len(), 1, "{h}");
        assert_eq!(h["records"][0]["serial"], evil);
        // a serial that is SQL matches nothing (a serial with no records is an error
        // that says so), and the table is whole
        let (code, _, err) = cli(&["history", "x' OR '1'='1", "--db", &db, "--json"]);
        assert_eq!(code, 1, "{err}");
        assert!(err.contains("no records of unit `x' OR '1'='1`"), "{err}");
        assert_eq!(records(&db).len(), 2);
    }
}

/// Every column of every record, but the store's own name.
fn same_records(a: &[Record], b: &[Record]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x, y);
        assert_eq!(x.blob, y.blob, "blob of {}", x.serial);
        assert_eq!(x.test_record, y.test_record);
    }
}

/// A trend's JSON without the store's name.
fn trend_json(db: &str, out: &Path) -> Value {
    let mut t = cli_json(&[
        "trend",
        "--db",
        db,
        "--out",
        s(out),
        "--force",
        "--reference-first",
        "6",
        "--json",
    ]);
    t["store"] = Value::Null;
    t
}

#[test]
fn a_store_moves_between_backends_with_every_record() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let dir = root.join("L1");
    lot(&dir, "CP", 6, 30);
    let first = root.join("first.sqlite").display().to_string();
    ok(&[
        "batch",
        s(&dir),
        "--out",
        s(&root.join("out")),
        "--db",
        &first,
        "--station",
        "ST-1",
        "--operator",
        "ana",
    ]);
    // a fit and a verify of one unit: records of other commands too
    let rec = dir.join("CP-00.csv");
    let b = root.join("cp0.blob");
    ok(&["fit", s(&rec), "--out", s(&b), "--db", &first]);
    ok(&["verify", s(&rec), "--blob", s(&b), "--db", &first]);
    let want = records(&first);
    assert_eq!(want.len(), 8);
    assert!(want[0].test_record.is_some() && want[0].trace.station.as_deref() == Some("ST-1"));
    let server = pg::database("copy");
    let back = root.join("back.sqlite").display().to_string();
    let out = ok(&["store", "copy", &first, &server]);
    assert!(out.contains("copied 8 records"), "{out}");
    let out = ok(&["store", "copy", &server, &back]);
    assert!(out.contains("copied 8 records"), "{out}");
    same_records(&want, &records(&server));
    same_records(&want, &records(&back));
    // copied again: nothing twice
    let out = ok(&["store", "copy", &first, &server]);
    assert!(
        out.contains("copied 0 records") && out.contains("8 there already"),
        "{out}"
    );
    assert_eq!(records(&server).len(), 8);
    // history and trend read the same from either backend
    for serial in ["CP-00", "CP-03"] {
        let h = |db: &str| {
            let mut v = cli_json(&["history", serial, "--db", db, "--json"]);
            v["store"] = Value::Null;
            v
        };
        assert_eq!(h(&first), h(&server));
    }
    let html = root.join("t.html");
    assert_eq!(trend_json(&first, &html), trend_json(&server, &html));
    // the test record comes back from the server as it was written beside the blob
    let tr = cli_json(&["history", "CP-02", "--db", &server, "--test-record"]);
    let file: Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("out/CP-02.test-record.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(tr, file);
    assert_eq!(tr["dut_id"], "CP-02");
    assert_eq!(tr["station_id"], "ST-1");
    assert_eq!(tr["metadata"]["operator"], "ana");
}

/// Every file under `dir`, as text (lossy).
fn files_text(dir: &Path) -> String {
    let mut all = String::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            all.push_str(&files_text(&p));
        } else {
            all.push_str(&String::from_utf8_lossy(&std::fs::read(&p).unwrap()));
        }
    }
    all
}

#[test]
fn a_password_in_the_url_appears_nowhere() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let secret = "Pw-7f3c9-Sekr3t";
    // the server trusts 127.0.0.1: the password is sent and ignored, so every command
    // runs with it in its URL
    let url = pg::database("secret").replacen("postgres@", &format!("postgres:{secret}@"), 1);
    let dir = root.join("L2");
    lot(&dir, "PW", 3, 40);
    let rec = dir.join("PW-00.csv");
    let mut seen = String::new();
    let mut run = |args: &[&str]| {
        let (code, out, err) = cli(args);
        seen.push_str(&out);
        seen.push_str(&err);
        code
    };
    let out = root.join("out");
    assert_eq!(run(&["batch", s(&dir), "--out", s(&out), "--db", &url]), 0);
    assert_eq!(
        run(&[
            "fit",
            s(&rec),
            "--out",
            s(&root.join("f.blob")),
            "--db",
            &url
        ]),
        0
    );
    assert_eq!(run(&["history", "PW-00", "--db", &url]), 0);
    assert_eq!(run(&["history", "PW-00", "--db", &url, "--json"]), 0);
    assert_eq!(run(&["history", "PW-01", "--db", &url, "--test-record"]), 0);
    assert_eq!(
        run(&["trend", "--db", &url, "--out", s(&root.join("t.html"))]),
        0
    );
    let copy = root.join("copy.sqlite");
    assert_eq!(run(&["store", "copy", &url, s(&copy)]), 0);
    assert_eq!(run(&["store", "migrate", "--db", &url]), 0);
    // refused: a wrong port, a database that does not exist, a bad port number
    let hostport = url.split('@').nth(1).unwrap().split('/').next().unwrap();
    let port = hostport.rsplit_once(':').unwrap().1;
    for bad in [
        url.replace(&format!(":{port}/"), ":1/"),
        format!("{}/nosuchdb", url.rsplit_once('/').unwrap().0),
        url.replace(&format!(":{port}/"), ":notaport/"),
    ] {
        assert_eq!(run(&["history", "PW-00", "--db", &bad]), 1, "{bad}");
        assert_eq!(
            run(&["batch", s(&dir), "--out", s(&root.join("o2")), "--db", &bad]),
            1
        );
    }
    assert!(seen.contains("postgresql://postgres@127.0.0.1"), "{seen}");
    assert!(!seen.contains(secret), "the password was printed:\n{seen}");
    // nor in any record's columns (options included), file, test record or report
    let rows = records(&url);
    assert_eq!(rows.len(), 4);
    let stored = serde_json::to_string(&rows).unwrap()
        + &rows
            .iter()
            .map(|r| format!("{:?}{}", r.test_record, r.options))
            .collect::<String>();
    assert!(stored.contains("postgresql://postgres@"), "{stored}");
    assert!(!stored.contains(secret));
    assert!(!files_text(root).contains(secret));
}

#[test]
fn an_older_store_is_upgraded_by_migrate_and_a_newer_one_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let insert = "INSERT INTO runs (run_id, serial, time_utc, host_fit_version, host_fit_commit, command, options, input) VALUES ('0123456789abcdef0123456789abcdef', 'OLD-1', '2025-01-01T00:00:00.000000Z', '0.0.9', 'c', 'fit', '{}', 'old.csv')";
    // SQLite: a version-1 store as the previous host-fit made it
    let file = root.join("v1.sqlite");
    {
        let c = rusqlite::Connection::open(&file).unwrap();
        c.execute_batch(&migrations(Dialect::Sqlite)[0]).unwrap();
        c.execute_batch("PRAGMA application_id = 1096041298; PRAGMA user_version = 1;")
            .unwrap();
        c.execute_batch(insert).unwrap();
    }
    // PostgreSQL: the same
    let server = pg::database("older");
    {
        let mut c = postgres::Client::connect(&server, postgres::NoTls).unwrap();
        c.batch_execute(&migrations(Dialect::Postgres)[0]).unwrap();
        c.batch_execute("INSERT INTO store_schema VALUES (1, '2025-01-01', '0.0.9')")
            .unwrap();
        c.batch_execute(insert).unwrap();
    }
    for db in [file.display().to_string(), server.clone()] {
        let (code, _, err) = cli(&["history", "OLD-1", "--db", &db]);
        assert_eq!(code, 1);
        assert!(
            err.contains("schema version 1") && err.contains(&format!("store migrate --db {db}")),
            "{err}"
        );
        let out = ok(&["store", "migrate", "--db", &db]);
        let now = format!("schema version {SCHEMA_VERSION}");
        assert!(out.contains(&now), "{out}");
        let h = cli_json(&["history", "OLD-1", "--db", &db, "--json"]);
        assert_eq!(
            h["records"][0]["run_id"],
            "0123456789abcdef0123456789abcdef"
        );
        // every traceability column an older store lacked is there, empty
        for n in host_fit::store::record::Trace::names() {
            assert_eq!(h["records"][0][&n], Value::Null, "{n}");
        }
    }
    // a newer server store is refused, its version named, and left alone
    let mut c = postgres::Client::connect(&server, postgres::NoTls).unwrap();
    c.batch_execute("INSERT INTO store_schema VALUES (9, '2030-01-01', '9.0.0')")
        .unwrap();
    let (code, _, err) = cli(&["store", "migrate", "--db", &server]);
    assert_eq!(code, 1);
    assert!(
        err.contains("schema version 9") && err.contains(&format!("up to {SCHEMA_VERSION}")),
        "{err}"
    );
    let n: i64 = c
        .query_one("SELECT count(*) FROM runs", &[])
        .unwrap()
        .get(0);
    assert_eq!(n, 1);
}

/// The x tick labels of the plot `id` in a report.
fn x_ticks(page: &str, id: &str) -> Vec<String> {
    let at = page
        .find(&format!("id=\"{id}\""))
        .unwrap_or_else(|| panic!("no {id}"));
    let svg = &page[at..at + page[at..].find("</svg>").unwrap()];
    svg.split("class=\"tick x\"")
        .skip(1)
        .map(|t| {
            let t = &t[t.find('>').unwrap() + 1..];
            t[..t.find('<').unwrap()].to_string()
        })
        .collect()
}

#[test]
fn the_trend_shows_every_calibration_on_whole_numbers_within_bounds() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let dir = root.join("L3");
    lot(&dir, "RC", 6, 50);
    for db in stores(root, "recal") {
        // the same six units calibrated by two lots
        for (k, lotname) in ["first", "second"].iter().enumerate() {
            let out = root.join(format!("out-{lotname}-{}", db.len()));
            ok(&[
                "batch",
                s(&dir),
                "--out",
                s(&out),
                "--db",
                &db,
                "--lot",
                lotname,
                "--jobs",
                "1",
            ]);
            assert_eq!(records(&db).len(), 6 * (k + 1));
        }
        let html = root.join("trend.html");
        let t = cli_json(&[
            "trend",
            "--db",
            &db,
            "--out",
            s(&html),
            "--force",
            "--reference-first",
            "6",
            "--json",
        ]);
        assert_eq!(t["unit_count"], 12, "{t}");
        assert_eq!(t["recalibrations"], 6);
        let lots: Vec<&str> = t["lots"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l["lot"].as_str().unwrap())
            .collect();
        assert_eq!(lots, ["first", "second"]);
        let dg = t["charts"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["quantity"] == "worst_dg")
            .unwrap();
        let l = &dg["limits"];
        let lower = l["lower"].as_f64().unwrap();
        assert!(lower >= 0.0, "{l}");
        assert!(l["upper"].as_f64().unwrap() > l["centre"].as_f64().unwrap());
        let page = std::fs::read_to_string(&html).unwrap();
        for id in ["trend-worst-dg", "trend-u0x"] {
            let ticks = x_ticks(&page, id);
            assert!(ticks.len() >= 2, "{id}: {ticks:?}");
            assert!(
                ticks.iter().all(|t| t.parse::<u64>().is_ok()),
                "{id}: {ticks:?}"
            );
        }
        assert!(page.contains("recalibrations: a unit calibrated again (6)"));
    }
}

#[test]
fn a_bad_db_leaves_no_output_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let dir = root.join("L4");
    lot(&dir, "BD", 1, 60);
    let text = root.join("notes.txt");
    std::fs::write(&text, "x".repeat(300)).unwrap();
    for bad in [
        "postgresql://postgres@127.0.0.1:1/none".to_string(),
        "mysql://x@y/z".to_string(),
        s(&text).to_string(),
        s(root).to_string(),
    ] {
        let out = root.join("never");
        let (code, _, err) = cli(&["batch", s(&dir), "--out", s(&out), "--db", &bad]);
        assert_eq!(code, 1, "{bad}");
        assert!(!err.is_empty());
        assert!(!out.exists(), "{bad} left {}", out.display());
    }
}
