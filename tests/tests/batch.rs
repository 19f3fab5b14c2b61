//! Production batches: every unit of a folder fitted with the model its data choose and
//! judged against the acceptance specification (pass, fail, error, and why), a bad file
//! reported without stopping the batch, a summary that stays a valid CSV whatever the
//! paths hold, the lot's statistics flag the unit unlike the others, and the exit code
//! says whether every unit passed.
use firmware_core::model::COEFF_NAMES;
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::diagnose::diagnose;
use host_fit::fit::pipeline::{fit_chosen, ModelRequest};
use host_fit::fit::predict::coefficient_sigma;
use host_fit::simulate::{simulate, Curvature, SimConfig, Stop, PAPER_UNIT, PAPER_UNIT_TEMPS};
use tests::cli;

/// A unit whose scale factors carry a 0.2 % bump at +32.5 C, between the stops (where
/// no calibration dwell sees it), with PP dwells there: it must fail.
fn bump_unit() -> SimConfig {
    let mut cfg = SimConfig::default();
    cfg.effects.temp_curvature = Some(Curvature {
        u0_v: [0.0; 3],
        k_rel: [2e-3, 2e-3, 0.0],
        period_c: 50.0,
    });
    cfg.schedule.stops.insert(
        3,
        Stop {
            temp_c: 32.5,
            soak_s: 1500.0,
            ramp_c_per_min: 1.0,
            positions: Some((1..=6).map(|i| format!("PP{i}")).collect()),
        },
    );
    cfg
}

/// The paper unit with its x offset 5 mV away from the lot's at every temperature: a
/// good unit, but not like the others.
fn odd_unit() -> SimConfig {
    let mut cfg = SimConfig {
        seed: 9,
        ..SimConfig::default()
    };
    cfg.unit.model = host_fit::simulate::UnitModel::Table;
    cfg.unit.temps_c = PAPER_UNIT_TEMPS.to_vec();
    cfg.unit.coeffs = PAPER_UNIT
        .iter()
        .map(|r| {
            let mut r = *r;
            r[9] += 5e-3;
            r
        })
        .collect();
    cfg
}

#[test]
fn batch_judges_every_unit_writes_a_real_csv_and_flags_the_odd_unit() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    // a folder name with a comma and a quote: the summary's file column must survive it
    let units = root.join("lot 7, \"B\"");
    std::fs::create_dir_all(&units).unwrap();
    let write = |name: &str, cfg: &SimConfig| {
        let sim = simulate(cfg, |_| {}).unwrap();
        std::fs::write(units.join(format!("{name}.csv")), sim.csv).unwrap();
    };
    for seed in 1u64..=5 {
        write(
            &format!("unit{seed}"),
            &SimConfig {
                seed,
                ..Default::default()
            },
        );
    }
    write("odd", &odd_unit());
    write("bump", &bump_unit());
    std::fs::write(units.join("broken.csv"), "t_s,position\n0,TP1\n").unwrap();
    let out = root.join("out");
    let run = |force: bool| {
        let mut a = vec![
            "batch".to_string(),
            units.display().to_string(),
            "--out".into(),
            out.display().to_string(),
            "--jobs".into(),
            "2".into(),
        ];
        if force {
            a.push("--force".into());
        }
        cli(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let (code, stdout, stderr) = run(false);
    assert_eq!(
        code, 3,
        "a unit failed and one errored: exit 3\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.contains("8 units") && stdout.contains("6 pass, 1 fail, 1 error"),
        "{stdout}"
    );
    assert!(
        stderr.contains("broken.csv"),
        "the bad unit is named: {stderr}"
    );

    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header[..4], ["unit", "file", "acceptance", "reason"]);
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 8);
    for row in &rows {
        assert_eq!(row.len(), header.len(), "{row:?}");
        let file = std::path::Path::new(&row[1]);
        assert_eq!(file.parent(), Some(units.as_path()), "{row:?}");
        let stem = file.file_stem().unwrap().to_string_lossy();
        let (acc, reason, far) = (&row[2], &row[3], &row[col("far_from_lot")]);
        assert!(!reason.is_empty(), "{row:?}");
        match stem.as_ref() {
            "broken" => {
                assert_eq!(acc, "error");
                assert!(reason.contains("temp_c"), "{row:?}");
                assert!(!out.join("broken.blob").exists());
            }
            "bump" => {
                assert_eq!(acc, "fail", "{row:?}");
                assert!(
                    reason.contains("32."),
                    "the failing temperature is named: {row:?}"
                );
            }
            _ => {
                assert_eq!(acc, "pass", "{row:?}");
                let before: f64 = row[col("max_abs_dg_mg_before")].parse().unwrap();
                let after: f64 = row[col("max_abs_dg_mg_after")].parse().unwrap();
                assert!(after < 0.3 && after < before, "{row:?}");
                for ext in ["blob", "json"] {
                    assert!(out.join(format!("{stem}.{ext}")).exists());
                }
                if stem == "odd" {
                    assert!(far.contains("u0x"), "the odd unit is flagged: {row:?}");
                } else {
                    assert!(far.is_empty(), "{row:?}");
                }
            }
        }
    }
    // the per-unit JSON carries the verdict and the data's choice
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("unit1.json")).unwrap()).unwrap();
    assert_eq!(j["acceptance"], "pass");
    assert!(j["chosen_by"]["method"]
        .as_str()
        .unwrap()
        .contains("cross-validation"));
    // the lot: 12 coefficients over the 7 units with a fit, u0x far for one unit
    let mut lot = csv::Reader::from_path(out.join("lot.csv")).unwrap();
    let lot: Vec<csv::StringRecord> = lot.records().map(Result::unwrap).collect();
    assert_eq!(lot.len(), 12);
    let u0x = lot.iter().find(|r| &r[0] == "u0x").unwrap();
    assert_eq!((&u0x[1], &u0x[6]), ("7", "1"), "{u0x:?}");

    // nothing the user had is overwritten without --force
    let (code, _, stderr) = run(false);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("--force"), "{stderr}");
    let (code, _, stderr) = run(true);
    assert_eq!(code, 3, "{stderr}");
}

/// A lot where every unit passes exits 0.
#[test]
fn a_lot_that_passes_exits_zero() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let units = root.join("units");
    std::fs::create_dir_all(&units).unwrap();
    for seed in [3u64, 4] {
        let sim = simulate(
            &SimConfig {
                seed,
                ..Default::default()
            },
            |_| {},
        )
        .unwrap();
        std::fs::write(units.join(format!("u{seed}.csv")), sim.csv).unwrap();
    }
    let (code, out, err) = cli(&[
        "batch",
        units.to_str().unwrap(),
        "--out",
        root.join("out").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("2 pass, 0 fail, 0 error"), "{out}");
    // the same lot against a specification no unit can meet fails, exit 3
    let (code, out, _) = cli(&[
        "batch",
        units.to_str().unwrap(),
        "--out",
        root.join("out").to_str().unwrap(),
        "--force",
        "--accept-t0-mg",
        "0.0001",
    ]);
    assert_eq!(code, 3, "{out}");
    assert!(out.contains("0 pass, 2 fail"), "{out}");
}

/// With --diagnose the blob and the "after" figure are the diagnosed model's.
#[test]
fn batch_with_the_diagnosis_takes_the_diagnosed_blob() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let units = root.join("units");
    std::fs::create_dir_all(&units).unwrap();
    let sim = simulate(&SimConfig::default(), |_| {}).unwrap();
    std::fs::write(units.join("u1.csv"), sim.csv).unwrap();
    let out = root.join("out");
    let (code, stdout, err) = cli(&[
        "batch",
        units.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--diagnose",
    ]);
    assert_eq!(code, 0, "{stdout}{err}");
    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let row = r.records().next().unwrap().unwrap();
    let model = &row[header.iter().position(|h| h == "model").unwrap()];
    assert!(model.starts_with("diagnosed"), "{row:?}");
    // the blob is the diagnosis's: byte for byte what `diagnose --out` writes, but for the
    // run id each run stamps into its blob (the batch records, this diagnose does not)
    let own = root.join("diagnosed.blob");
    let (code, _, err) = cli(&[
        "diagnose",
        units.join("u1.csv").to_str().unwrap(),
        "--out",
        own.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let batch_blob = std::fs::read(out.join("u1.blob")).unwrap();
    let run = host_fit::store::record::blob_run_id(&batch_blob).expect("a run id");
    assert_eq!(
        batch_blob,
        host_fit::store::record::stamp(&std::fs::read(&own).unwrap(), run).unwrap()
    );
    let u: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("u1.json")).unwrap()).unwrap();
    assert!(
        u["diagnosis"].is_object() && u["acceptance"] == "pass",
        "{u}"
    );
    // the lot's statistics take the diagnosed model's own uncertainty, not the chosen
    // fit's: with one unit the lot's robust sigma is that unit's 1-sigma
    let rec = Recording::read(&units.join("u1.csv"), Positions::default()).unwrap();
    let diagnosed = diagnose(&rec).unwrap().coefficient_sigma(rec.t0_c);
    let oc = fit_chosen(&rec, &ModelRequest::default()).unwrap();
    let chosen = coefficient_sigma(&oc.fit, &oc.noise, rec.t0_c);
    let mut lot = csv::Reader::from_path(out.join("lot.csv")).unwrap();
    let cols: Vec<String> = lot.headers().unwrap().iter().map(String::from).collect();
    let at = |name: &str| cols.iter().position(|h| h == name).unwrap();
    let (mut same, mut differ) = (0, 0);
    for row in lot.records().map(Result::unwrap) {
        let c = COEFF_NAMES
            .iter()
            .position(|n| *n == &row[at("coefficient")])
            .unwrap();
        let lot_sigma: f64 = row[at("robust_sigma")].parse().unwrap();
        let rel = |v: f64| (lot_sigma - v).abs() / v;
        assert!(
            rel(diagnosed[c]) < 1e-3,
            "{}: lot {lot_sigma:e}, diagnosed {:e}, chosen fit {:e}",
            &row[at("coefficient")],
            diagnosed[c],
            chosen[c]
        );
        same += 1;
        differ += usize::from(rel(chosen[c]) > 0.05);
    }
    assert_eq!(same, 12);
    assert!(
        differ > 0,
        "the two models' sigmas must differ for the check to tell"
    );
}
