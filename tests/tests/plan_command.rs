//! The `host-fit plan` command end to end (issue 19): the program it writes holds to the
//! stated chamber (range, fastest ramp) and ends with an equilibrium verification block;
//! it never overwrites without `--force`; bad options are refused naming the option; the
//! target picks the candidate it says among those whose blob covers the range asked for,
//! or says that none can within the hours; the written plan, run on the twin with
//! `simulate --plan`, fitted and verified, covers the range and is within its predicted
//! accuracy.
use host_fit::model::effects::EffectId;
use serde_json::Value;
use tests::time_true::{s, verify};
use tests::{cli, cli_json};

const LO: f64 = -30.0;
const HI: f64 = 60.0;
const RAMP: f64 = 3.0;
const POSITIONS: usize = 12;
/// The verification block's soak before its dwells, s (plan.rs: at least 30 min).
const MIN_SOAK_S: f64 = 1800.0;

/// A program row.
struct Row {
    t: f64,
    sp: f64,
    pos: String,
}

fn parse(text: &str) -> Vec<Row> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time_s,setpoint_c,position"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 3, "row {l:?}");
            Row {
                t: f[0].parse().unwrap(),
                sp: f[1].parse().unwrap(),
                pos: f[2].to_string(),
            }
        })
        .collect()
}

fn plan(dir: &std::path::Path, out: &str, target: &[&str]) -> (Value, std::path::PathBuf) {
    let p = dir.join(out);
    let mut args = vec![
        "plan",
        "--range-c=-30,60",
        "--max-ramp-c-per-min",
        "3",
        "--seed",
        "5",
        "--out",
        s(&p),
        "--json",
    ];
    args.extend_from_slice(target);
    (cli_json(&args), p)
}

fn hours(c: &Value) -> f64 {
    c["hours"].as_f64().unwrap()
}
fn predicted(c: &Value) -> f64 {
    c["predicted_mg"].as_f64().unwrap()
}
/// Its blob reaches within 1 C of each end of the range asked for.
fn covers(c: &Value) -> bool {
    c["covers"].as_bool().unwrap()
}

/// The program holds to the chamber and ends with the verification block.
fn check_program(rows: &[Row], j: &Value) {
    let chosen = &j["chosen"];
    // the program: header, times increasing, set points inside the range, ramps no
    // faster than the limit
    assert_eq!(rows.len() as u64, j["program_rows"].as_u64().unwrap());
    for w in rows.windows(2) {
        assert!(w[1].t > w[0].t, "time {} after {}", w[1].t, w[0].t);
        let rate = (w[1].sp - w[0].sp).abs() / (w[1].t - w[0].t) * 60.0;
        assert!(
            rate <= RAMP * (1.0 + 1e-9),
            "ramp {rate} C/min at {} s",
            w[0].t
        );
    }
    assert!(rows.iter().all(|r| (LO..=HI).contains(&r.sp)));
    // the verification block after the calibration program: at each verification
    // temperature, held at least MIN_SOAK_S before its dwells, every position visited
    let end = hours(chosen) * 3600.0;
    let ver: Vec<&Row> = rows.iter().filter(|r| r.t >= end - 1e-6).collect();
    let temps: Vec<f64> = j["verification_temps_c"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(temps.len(), 3);
    for &vt in &temps {
        let named: Vec<&&Row> = ver
            .iter()
            .filter(|r| r.pos != "-" && (r.sp - vt).abs() < 1e-9)
            .collect();
        let mut names: Vec<&str> = named.iter().map(|r| r.pos.as_str()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), POSITIONS, "at {vt} C: {names:?}");
        let first = named.first().unwrap().t;
        // the set point has been vt from at least MIN_SOAK_S before the first dwell
        let reached = rows
            .iter()
            .filter(|r| r.t <= first)
            .rev()
            .take_while(|r| (r.sp - vt).abs() < 1e-9)
            .last()
            .unwrap()
            .t;
        assert!(
            first - reached >= MIN_SOAK_S,
            "soak {} s at {vt} C",
            first - reached
        );
        assert!(ver.iter().all(|r| (LO..=HI).contains(&r.sp)));
    }
    // no named dwell of the verification block is at another temperature (the judge is
    // in equilibrium only)
    assert!(ver
        .iter()
        .filter(|r| r.pos != "-")
        .all(|r| temps.iter().any(|&vt| (r.sp - vt).abs() < 1e-9)));
}

/// Fewer hours than any plan that covers the range needs (`shortest`): refused, naming
/// the hours that would do, and nothing written.
fn refuses_too_few_hours(dir: &std::path::Path, shortest: f64) {
    let none = dir.join("none.csv");
    let (code, _, err) = cli(&[
        "plan",
        "--range-c=-30,60",
        "--seed",
        "5",
        "--hours",
        &format!("{}", shortest - 0.01),
        "--out",
        s(&none),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("no plan covers -30..60 C within")
            && err.contains(&format!(
                "give --hours {:.2}",
                (shortest * 100.0).ceil() / 100.0
            )),
        "{err}"
    );
    assert!(!none.exists());
}

/// Bad options are refused naming the option, and write nothing.
fn refuses_bad_options(dir: &std::path::Path) {
    // bad options: refused, naming the option
    let other = dir.join("bad.csv");
    for (args, opt) in [
        (vec!["--range-c=60,-30", "--target-mg", "1"], "--range-c"),
        (vec!["--range-c", "10,10", "--hours", "3"], "--range-c"),
        (
            vec!["--max-ramp-c-per-min", "0", "--hours", "3"],
            "--max-ramp-c-per-min",
        ),
        (vec!["--noise=-1", "--hours", "3"], "--noise"),
        (vec!["--target-mg=-0.1"], "--target-mg"),
        (vec![], "--target-mg"),
    ] {
        let mut a = vec!["plan", "--out", s(&other)];
        a.extend(args.iter().copied());
        let (code, _, err) = cli(&a);
        assert_ne!(code, 0, "{a:?}");
        assert!(err.contains(opt), "{a:?}: {err}");
        assert!(!other.exists(), "{a:?} wrote a program");
    }
}

#[test]
fn plan_writes_a_program_the_chamber_can_follow_and_the_twin_meets_its_prediction() {
    let dir = tempfile::tempdir().unwrap();
    // a target between the candidates' predictions: some meet it, some do not
    let (all, _) = plan(dir.path(), "all.csv", &["--hours", "1000"]);
    let every = all["candidates"].as_array().unwrap().clone();
    // a candidate whose blob falls short of the range is never chosen; its valid range
    // says so
    for c in &every {
        let v = &c["valid_c"];
        let (lo, hi) = (v[0].as_f64().unwrap(), v[1].as_f64().unwrap());
        assert_eq!(covers(c), lo <= LO + 1.0 && hi >= HI - 1.0, "{c}");
    }
    let cands: Vec<Value> = every.iter().filter(|c| covers(c)).cloned().collect();
    assert!(cands.len() >= 4, "{every:?}");
    assert!(covers(&all["chosen"]));
    let mut preds: Vec<f64> = cands.iter().map(predicted).collect();
    preds.sort_by(f64::total_cmp);
    // --hours without a binding limit: the most accurate of all
    assert_eq!(predicted(&all["chosen"]), preds[0]);
    let target_mg = (preds[preds.len() / 2] + preds[preds.len() / 2 - 1]) / 2.0;
    let (j, prog) = plan(
        dir.path(),
        "plan.csv",
        &["--target-mg", &format!("{target_mg}")],
    );
    let chosen = &j["chosen"];
    let meets: Vec<&Value> = cands.iter().filter(|c| predicted(c) <= target_mg).collect();
    let shortest = meets.iter().map(|c| hours(c)).fold(f64::INFINITY, f64::min);
    assert!(predicted(chosen) <= target_mg, "{chosen}");
    assert_eq!(
        hours(chosen),
        shortest,
        "not the shortest that meets {target_mg} mg"
    );

    // --hours: the most accurate within the hours (between the shortest and longest)
    let mut hs: Vec<f64> = cands.iter().map(hours).collect();
    hs.sort_by(f64::total_cmp);
    let limit = (hs[1] + hs[2]) / 2.0;
    let (jh, _) = plan(dir.path(), "hours.csv", &["--hours", &format!("{limit}")]);
    let best = cands
        .iter()
        .filter(|c| hours(c) <= limit)
        .map(predicted)
        .fold(f64::INFINITY, f64::min);
    assert!(hours(&jh["chosen"]) <= limit);
    assert_eq!(predicted(&jh["chosen"]), best);
    refuses_too_few_hours(dir.path(), hs[0]);

    let text = std::fs::read_to_string(&prog).unwrap();
    let rows = parse(&text);
    check_program(&rows, &j);
    let end = hours(chosen) * 3600.0;
    // never overwritten without --force
    let (code, _, err) = cli(&[
        "plan",
        "--range-c=-30,60",
        "--target-mg",
        "1",
        "--out",
        s(&prog),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("--force"), "{err}");
    assert_eq!(std::fs::read_to_string(&prog).unwrap(), text);

    refuses_bad_options(dir.path());

    // the written plan on the twin: the calibration program and the verification block
    // recorded apart (so no verification dwell is fitted), fitted and verified
    let cut = rows.iter().position(|r| r.t >= end - 1e-6).unwrap();
    let csv = |rs: &[Row], t0: f64| {
        let mut s = String::from("time_s,setpoint_c,position\n");
        for r in rs {
            s.push_str(&format!("{},{},{}\n", r.t - t0, r.sp, r.pos));
        }
        s
    };
    let cal_plan = dir.path().join("cal-plan.csv");
    std::fs::write(&cal_plan, csv(&rows[..=cut], 0.0)).unwrap();
    let ver_plan = dir.path().join("ver-plan.csv");
    std::fs::write(&ver_plan, csv(&rows[cut..], rows[cut].t)).unwrap();
    let (cal, vrec, blob) = (
        dir.path().join("cal.csv"),
        dir.path().join("ver.csv"),
        dir.path().join("b.blob"),
    );
    // the same unit (seed) for both: the verification judges the unit calibrated
    for (p, r, seed) in [(&cal_plan, &cal, "11"), (&ver_plan, &vrec, "11")] {
        let (code, _, err) = cli(&["simulate", "--plan", s(p), "--out", s(r), "--seed", seed]);
        assert_eq!(code, 0, "{err}");
    }
    let fitted = cli_json(&[
        "fit",
        s(&cal),
        "--route",
        "dynamic",
        "--out",
        s(&blob),
        "--json",
    ]);
    // the blob covers the range asked for, as the plan said
    let (lo, hi) = (
        fitted["t_min_c"].as_f64().unwrap(),
        fitted["t_max_c"].as_f64().unwrap(),
    );
    assert!(lo <= LO + 1.0 && hi >= HI - 1.0, "valid {lo}..{hi} C");
    let (worst, dg) = verify(&vrec, None, &blob);
    // verify judges the verification positions (PP1..PP6) of the block's 36 dwells at
    // three temperatures; its TP dwells are calibration positions
    assert_eq!(dg.len(), 18, "{dg:?}");
    println!(
        "chosen {}: predicted {:.4} mg, simulated {worst:.4} mg",
        chosen["kind"],
        predicted(chosen)
    );
    assert!(
        worst <= predicted(chosen),
        "simulated {worst:.4} mg over the predicted {:.4} mg",
        predicted(chosen)
    );
}

/// `--from-diagnosis`: the unit type's time constant and noise read from an earlier
/// `diagnose --json` of a lagging unit (the truth: 600 s, 2e-5 per sample); `--tau-s`
/// and `--noise` override; a JSON without them is refused naming what is missing.
#[test]
fn plan_reads_the_unit_types_lag_and_noise_from_a_diagnosis() {
    use host_fit::simulate::{simulate, PerAxis, SimConfig};
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = SimConfig {
        seed: 3,
        ..SimConfig::default()
    };
    cfg.effects.thermal_lag = Some(PerAxis { value: [600.0; 3] });
    let truth_noise = cfg.unit.noise_v;
    let rec = dir.path().join("unit.csv");
    std::fs::write(&rec, simulate(&cfg, |_| {}).unwrap().csv).unwrap();
    let (code, diag, err) = cli(&["diagnose", s(&rec), "--json"]);
    assert_eq!(code, 0, "{err}");
    let d = dir.path().join("d.json");
    std::fs::write(&d, &diag).unwrap();
    let out = dir.path().join("p.csv");
    let run = |extra: &[&str]| {
        let mut a = vec![
            "plan",
            "--from-diagnosis",
            s(&d),
            "--hours",
            "100",
            "--out",
            s(&out),
            "--force",
            "--json",
        ];
        a.extend_from_slice(extra);
        cli_json(&a)["limits"].clone()
    };
    let l = run(&[]);
    let tau = l["tau_s"].as_f64().unwrap();
    let noise = l["noise_v"].as_f64().unwrap();
    assert!((tau - 600.0).abs() < 0.05 * 600.0, "tau {tau} s");
    assert!(
        (noise / truth_noise - 1.0).abs() < 0.3,
        "noise {noise}, truth {truth_noise}"
    );
    let l = run(&["--tau-s", "120", "--noise", "3e-5"]);
    assert_eq!(l["tau_s"].as_f64(), Some(120.0));
    assert_eq!(l["noise_v"].as_f64(), Some(3e-5));

    // a diagnosis without the lag (or the noise): refused, naming what is missing
    let mut j: Value = serde_json::from_str(&diag).unwrap();
    j["findings"] = Value::Array(vec![]);
    std::fs::write(&d, j.to_string()).unwrap();
    let fresh = dir.path().join("q.csv");
    let (code, _, err) = cli(&[
        "plan",
        "--from-diagnosis",
        s(&d),
        "--hours",
        "100",
        "--out",
        s(&fresh),
    ]);
    assert_ne!(code, 0);
    assert!(
        err.contains("thermal_lag") && err.contains("--tau-s"),
        "{err}"
    );
    assert!(!fresh.exists());
    j.as_object_mut().unwrap().remove("noise_sigma_per_sample");
    std::fs::write(&d, j.to_string()).unwrap();
    let (code, _, err) = cli(&[
        "plan",
        "--from-diagnosis",
        s(&d),
        "--tau-s",
        "0",
        "--hours",
        "100",
        "--out",
        s(&fresh),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("noise_sigma_per_sample"), "{err}");
    assert!(!fresh.exists());
}

/// `--report`: the page plots a point per candidate at its (hours, predicted mg), and
/// rings the chosen one on its point; the page is well-formed XML.
#[test]
fn plan_report_plots_every_candidate_and_rings_the_chosen_one() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("plan.html");
    let (j, _) = plan(dir.path(), "p.csv", &["--hours", "3", "--report", s(&page)]);
    let cands = j["candidates"].as_array().unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    let opt = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(&html, opt).unwrap();
    // the drawn data beside the SVG: a point per candidate, the chosen one apart
    let data: Value = serde_json::from_str(
        doc.descendants()
            .find(|n| n.attribute("class") == Some("plot-data"))
            .unwrap()
            .text()
            .unwrap(),
    )
    .unwrap();
    let series = data["series"].as_array().unwrap();
    // stops and soaks, sweeps, those short of the range (each where there are some),
    // the chosen one's ring last
    let n = series.len();
    assert!((3..=4).contains(&n), "{n} series");
    assert_eq!(series[n - 1]["marker"], "ring");
    let drawn: Vec<(f64, f64)> = series[..n - 1]
        .iter()
        .flat_map(|s| s["points"].as_array().unwrap().iter())
        .map(|p| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
        .collect();
    assert_eq!(drawn.len(), cands.len());
    for c in cands {
        assert!(
            drawn.contains(&(hours(c), predicted(c))),
            "{c} not drawn: {drawn:?}"
        );
    }
    // every candidate labelled as in the table (A, B, ...)
    let mut labels: Vec<&str> = series[..n - 1]
        .iter()
        .flat_map(|s| s["labels"].as_array().unwrap().iter())
        .map(|l| l.as_str().unwrap())
        .collect();
    labels.sort_unstable();
    let want: Vec<String> = (0..cands.len())
        .map(host_fit::plan::Candidate::label)
        .collect();
    assert_eq!(labels, want);
    let mut drawn_labels: Vec<&str> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("point-label"))
        .filter_map(|n| n.text())
        .collect();
    drawn_labels.sort_unstable();
    assert_eq!(drawn_labels, want);
    let ring = &series[n - 1]["points"][0];
    assert_eq!(
        (ring[0].as_f64().unwrap(), ring[1].as_f64().unwrap()),
        (hours(&j["chosen"]), predicted(&j["chosen"]))
    );
    // the SVG: as many marker vertices as candidates, the ring on one of them
    let vertices = |i: usize| -> Vec<(String, String)> {
        let g = doc
            .descendants()
            .find(|n| n.attribute("data-series") == Some(&i.to_string()))
            .unwrap();
        let d = g
            .descendants()
            .find(|n| n.attribute("class") == Some("markers"))
            .unwrap()
            .attribute("d")
            .unwrap()
            .trim_start_matches('M')
            .to_string();
        let v: Vec<String> = d.split_whitespace().map(String::from).collect();
        v.chunks(2).map(|c| (c[0].clone(), c[1].clone())).collect()
    };
    let marks: Vec<(String, String)> = (0..n - 1).flat_map(vertices).collect();
    assert_eq!(marks.len(), cands.len());
    let ringed = vertices(n - 1);
    assert_eq!(ringed.len(), 1);
    assert!(
        marks.contains(&ringed[0]),
        "{ringed:?} not on a candidate {marks:?}"
    );
    // never overwritten without --force
    let (code, _, err) = cli(&[
        "plan",
        "--hours",
        "3",
        "--out",
        s(&dir.path().join("other.csv")),
        "--report",
        s(&page),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("--force"), "{err}");
    assert_eq!(std::fs::read_to_string(&page).unwrap(), html);
}

/// `--from-diagnosis` of a unit with a hysteresis and a temperature-rate term (issue 27):
/// on stops reached only from below the two are split by ramps alone, and the flight,
/// warming and cooling both ways, pays for the split. The plan reads them from the
/// diagnosis and each stop-and-soak candidate ends with a return from the hot end to the
/// middle stop (the chamber's fastest ramp, a soak, the positions), its hours counted;
/// a sweep does not separate them and is not chosen; the chosen program holds the
/// return; a plan without the diagnosis adds nothing. The flight this buys is held by
/// the full tier (`time_true::the_plan_for_a_hysteresis_and_rate_unit_flies_within_the_aim`).
#[test]
fn plan_separates_the_coupled_effects_a_diagnosis_found() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let unit = tests::time_true::production("hysteresis+temp_rate", 1);
    let (rec, _) = tests::time_true::write(d, "unit", &unit);
    let (code, diag, err) = cli(&["diagnose", s(&rec), "--json"]);
    assert_eq!(code, 0, "{err}");
    let found: Value = serde_json::from_str(&diag).unwrap();
    let names = tests::time_true::found(&found);
    assert!(
        names.contains(&EffectId::Hysteresis) && names.contains(&EffectId::TempRate),
        "the diagnosis found {names:?}"
    );
    let dj = d.join("d.json");
    std::fs::write(&dj, &diag).unwrap();
    let noise = found["noise_sigma_per_sample"][0]
        .as_f64()
        .unwrap()
        .to_string();
    let run = |out: &str, from: bool| {
        let p = d.join(out);
        let mut a = vec![
            "plan",
            "--tau-s",
            "0",
            "--hours",
            "100",
            "--out",
            s(&p),
            "--json",
        ];
        if from {
            a.extend(["--from-diagnosis", s(&dj)]);
        } else {
            a.extend(["--noise", noise.as_str()]);
        }
        (cli_json(&a), p)
    };
    let (j, p) = run("sep.csv", true);
    let (plain, _) = run("plain.csv", false);
    assert_eq!(
        j["limits"]["separate"],
        serde_json::json!(["hysteresis", "temp_rate"])
    );
    assert!(plain["limits"].get("separate").is_none() && plain.get("separation").is_none());
    // the return's hours: 55 C down at 3 C/min, the soak (five case time constants, at
    // least 30 min), a move and a dwell per position
    let soak_s = (5.0 * host_fit::simulate::config::CASE_TAU_S).max(MIN_SOAK_S);
    let extra_h = (55.0 / 3.0 * 60.0 + soak_s + POSITIONS as f64 * 60.0) / 3600.0;
    for (c, q) in j["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .zip(plain["candidates"].as_array().unwrap())
    {
        let want = if c["kind"]["kind"] == "stop_soak" {
            hours(q) + extra_h
        } else {
            hours(q)
        };
        assert!((hours(c) - want).abs() < 1e-9, "{c} against {q}");
    }
    let sep = j["separation"].as_str().unwrap();
    println!("{}: {sep}", j["chosen"]["kind"]);
    let rows = parse(&std::fs::read_to_string(&p).unwrap());
    // only a stop-and-soak program separates them: a sweep at one rate each way flips
    // its rate term with the direction, as a hysteresis does
    assert_eq!(j["chosen"]["kind"]["kind"], "stop_soak", "{}", j["chosen"]);
    for c in j["candidates"].as_array().unwrap() {
        assert_eq!(
            c["separates"] == true,
            c["kind"]["kind"] == "stop_soak",
            "{c}"
        );
    }
    assert!(sep.contains("return from the hot end to 15.0 C"), "{sep}");
    // after the last dwell at the hot end: the ramp down, the soak, every position
    let hot = rows
        .iter()
        .rposition(|r| r.sp == 70.0 && r.pos == "PP6")
        .unwrap();
    let back: Vec<&Row> = rows[hot + 1..].iter().filter(|r| r.sp == 15.0).collect();
    let named = back
        .iter()
        .filter(|r| r.pos != "-" && r.pos != "TP1")
        .count();
    assert!(
        named >= POSITIONS - 1,
        "{named} dwells at 15 C after the hot end"
    );
    let soaked = back[1].t - back[0].t;
    assert!((soaked - soak_s).abs() < 1e-6, "soak {soaked} s");
    // the text output says so too
    let text = d.join("text.csv");
    let (code, out, err) = cli(&[
        "plan",
        "--from-diagnosis",
        s(&dj),
        "--tau-s",
        "0",
        "--hours",
        "100",
        "--out",
        s(&text),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("separating: the program ends with a return from the hot end to 15.0 C"),
        "{out}"
    );
}
