//! Verdicts that cannot pass what was not judged (issue 17 item 1): a blob fitted on one
//! stop (-29.5 C, T0 = 25 C) verified against the unit's four-stop recording fails, since
//! 18 of its verification dwells lie where the blob claims nothing; with
//! `--outside-range report` they are reported apart and the band near T0, left without a
//! judged dwell, is `not_judged` (exit 4), never a pass. `batch` does not mark such a unit
//! `pass`, and the fit states its predicted error inside its valid range only. (Such a
//! blob is refused at the door since issue 29, its T0 outside its data: these tests let
//! it past with `--allow partial`.)
use tests::four_stops::{one_stop, simulate, FOUR};
use tests::{cli, s};

#[test]
fn a_one_stop_blob_verified_on_four_stops_fails_or_is_not_judged_never_passes() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let one = simulate(dir, "one", &one_stop());
    let four = simulate(dir, "four", FOUR);
    let blob = dir.join("one.blob");
    // refused at the door (its T0 is 55 C from its data) unless the partial data are
    // let past on purpose, as here
    let (code, _, err) = cli(&["fit", s(&one), "--out", s(&blob)]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("field `t0_c`") && err.contains("--allow partial"),
        "{err}"
    );
    let (code, out, err) = cli(&[
        "fit",
        s(&one),
        "--out",
        s(&blob),
        "--json",
        "--allow",
        "partial",
    ]);
    assert_eq!(code, 0, "{err}");
    let fit: serde_json::Value = serde_json::from_str(&out).unwrap();
    // every predicted figure inside the valid range (T0 = 25 C is far outside it)
    let (lo, hi) = (
        fit["t_min_c"].as_f64().unwrap(),
        fit["t_max_c"].as_f64().unwrap(),
    );
    assert!(lo > -31.0 && hi < -28.0, "{lo}..{hi}");
    let points = fit["predicted_error"]["points"].as_array().unwrap();
    assert!(!points.is_empty());
    for p in points {
        let t = p["temp_c"].as_f64().unwrap();
        assert!(
            (lo..=hi).contains(&t),
            "predicted at {t} C outside {lo}..{hi}"
        );
    }

    // the case: exit 3, the dwells outside the range named as the reason
    let (code, out, err) = cli(&["verify", "--blob", s(&blob), s(&four)]);
    assert_eq!(code, 3, "{out}{err}");
    let last = out.lines().last().unwrap();
    assert!(
        last.starts_with("acceptance: fail")
            && last.contains("18 verification dwells outside the valid range")
            && last.contains("the blob claims nothing there"),
        "{last}"
    );
    let (code, out, _) = cli(&["verify", "--blob", s(&blob), s(&four), "--json"]);
    assert_eq!(code, 3);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        (j["acceptance"].as_str(), j["dwells_outside_range"].as_u64()),
        (Some("fail"), Some(18))
    );
    // the worst of them is the unit's thermal error, about 10 mg
    assert!(j["worst_outside_range_mg"].as_f64().unwrap() > 5.0, "{j}");

    // reported apart: the band near T0 has no judged dwell, so no pass
    let args = ["verify", "--blob", s(&blob), s(&four), "--json"];
    let (code, out, err) = cli(&[&args[..], &["--outside-range", "report"]].concat());
    assert_eq!(code, 4, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["acceptance"], "not_judged", "{j}");
    assert_eq!(j["bands_not_judged"], serde_json::json!(["near_t0"]));
    assert_eq!(j["dwells_judged"], 6);
    assert!(
        j["reason"].as_str().unwrap().ends_with("reported apart"),
        "{}",
        j["reason"]
    );

    // the four-stop unit's own blob still passes on its own recording
    let own = dir.join("four.blob");
    let (code, _, err) = cli(&["fit", s(&four), "--out", s(&own)]);
    assert_eq!(code, 0, "{err}");
    let (code, out, _) = cli(&["verify", "--blob", s(&own), s(&four)]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("acceptance: pass"), "{out}");
}

#[test]
fn batch_does_not_pass_a_unit_judged_nowhere_near_t0() {
    let tmp = tempfile::tempdir().unwrap();
    let lot = tmp.path().join("lot");
    std::fs::create_dir_all(&lot).unwrap();
    simulate(&lot, "one", &one_stop());
    let out = tmp.path().join("out");
    // let past the door's check of partial data (a one-stop unit, on purpose)
    let (code, stdout, err) = cli(&["batch", s(&lot), "--out", s(&out), "--allow", "partial"]);
    assert_eq!(code, 4, "{stdout}{err}");
    assert!(
        stdout.contains("0 pass, 0 fail, 0 error, 1 not judged"),
        "{stdout}"
    );
    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    let row = r.records().next().unwrap().unwrap();
    assert_eq!(&row[2], "not_judged", "{row:?}");
    assert!(
        row[3].starts_with("no verification dwell judged within +-5 C of T0"),
        "{row:?}"
    );
    // the unit's JSON says which band
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("one.json")).unwrap()).unwrap();
    assert_eq!(j["bands_not_judged"], serde_json::json!(["near_t0"]), "{j}");
}
