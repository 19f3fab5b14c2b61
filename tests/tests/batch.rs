//! Production batches: every unit of a folder fitted, a bad file reported without
//! stopping the batch, and a summary that stays a valid CSV whatever the paths hold.
use tests::cli;

#[test]
fn batch_summary_is_a_real_csv_and_a_bad_unit_does_not_stop_it() {
    let root = tempfile_dir("hf-batch");
    // a folder name with a comma and a quote: the summary's file column must survive it
    let units = root.join("lot 7, \"B\"");
    std::fs::create_dir_all(&units).unwrap();
    for seed in [1u64, 2] {
        let cfg = host_fit::simulate::SimConfig {
            seed,
            ..Default::default()
        };
        let sim = host_fit::simulate::simulate(&cfg, |_| {}).unwrap();
        std::fs::write(units.join(format!("unit{seed}.csv")), sim.csv).unwrap();
    }
    std::fs::write(units.join("broken.csv"), "t_s,position\n0,TP1\n").unwrap();
    let out = root.join("out");
    let args = |force: bool| {
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
        a
    };
    let run = |force: bool| {
        let a = args(force);
        cli(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let (code, stdout, stderr) = run(false);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("3 units") && stdout.contains("2 ok, 1 failed"),
        "{stdout}"
    );
    assert!(
        stderr.contains("broken.csv"),
        "the bad unit is named: {stderr}"
    );

    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header[..3], ["unit", "file", "status"]);
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 3);
    for row in &rows {
        assert_eq!(row.len(), header.len(), "{row:?}");
        let file = std::path::Path::new(&row[1]);
        assert_eq!(file.parent(), Some(units.as_path()), "{row:?}");
        let stem = file.file_stem().unwrap().to_string_lossy();
        if stem == "broken" {
            assert!(
                row[2].starts_with("error:") && row[2].contains("temp_c"),
                "{row:?}"
            );
            assert!(!out.join("broken.blob").exists());
        } else {
            assert_eq!(&row[2], "ok", "{row:?}");
            assert_eq!(&row[0], "PAPER-UNIT");
            let before: f64 = row[3].parse().unwrap();
            let after: f64 = row[4].parse().unwrap();
            assert!(after < before, "{row:?}");
            for ext in ["blob", "json"] {
                assert!(out.join(format!("{stem}.{ext}")).exists());
            }
        }
    }
    // nothing the user had is overwritten without --force
    let (code, _, stderr) = run(false);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("--force"), "{stderr}");
    let (code, _, stderr) = run(true);
    assert_eq!(code, 0, "{stderr}");
    std::fs::remove_dir_all(&root).unwrap();
}

fn tempfile_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
