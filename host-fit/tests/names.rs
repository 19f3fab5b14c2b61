//! Every closed set with names: text -> enum -> text for each variant, serde's JSON string
//! is the enum's Display, and the names are the ones the contracts (JSON, CSV, the store,
//! the command line) already use, in order. A renamed variant fails here, not in a
//! consumer. `tidy.rs` checks that every enum with derived names is named here by its
//! defining path.
use serde::Serialize;
use std::fmt::{Debug, Display};
use std::str::FromStr;
use strum::IntoEnumIterator;

/// `E`'s names are `names` (in declaration order), each parses back to its variant and
/// names it the same way through `Into<&'static str>`.
fn text_round_trip<E>(names: &[&str]) -> Vec<E>
where
    E: IntoEnumIterator + Display + FromStr + Into<&'static str> + PartialEq + Debug + Copy,
{
    let all: Vec<E> = E::iter().collect();
    let shown: Vec<String> = all.iter().map(ToString::to_string).collect();
    assert_eq!(shown, names, "{}", std::any::type_name::<E>());
    for e in &all {
        let text = e.to_string();
        assert_eq!(text.parse::<E>().ok(), Some(*e), "{text}");
        let name: &'static str = (*e).into();
        assert_eq!(name, text);
    }
    all
}

/// [`text_round_trip`], and serde writes each variant as its name.
fn round_trip<E>(names: &[&str])
where
    E: IntoEnumIterator
        + Display
        + FromStr
        + Into<&'static str>
        + PartialEq
        + Debug
        + Copy
        + Serialize,
{
    for e in text_round_trip::<E>(names) {
        assert_eq!(
            serde_json::to_value(e).unwrap(),
            serde_json::Value::String(e.to_string())
        );
    }
}

/// A command-line enum: its value names are `names`, each parsed back to its variant.
fn clap_round_trip<E: clap::ValueEnum + PartialEq + Debug>(names: &[&str]) {
    let shown: Vec<String> = E::value_variants()
        .iter()
        .map(|v| v.to_possible_value().unwrap().get_name().to_string())
        .collect();
    assert_eq!(shown, names, "{}", std::any::type_name::<E>());
    for (v, name) in E::value_variants().iter().zip(names) {
        assert_eq!(&E::from_str(name, false).unwrap(), v);
    }
}

/// A set named by serde alone (a configuration's): each variant is written as its name
/// and read back from it.
fn serde_round_trip<E>(named: &[(E, &str)])
where
    E: Serialize + serde::de::DeserializeOwned + PartialEq + Debug,
{
    for (e, name) in named {
        let json = serde_json::to_value(e).unwrap();
        assert_eq!(json, serde_json::Value::String(name.to_string()));
        assert_eq!(&serde_json::from_value::<E>(json).unwrap(), e);
    }
}

#[test]
fn simulator_unit_model_and_interpolation() {
    use host_fit::simulate::config::{Interp, UnitModel};
    serde_round_trip(&[(UnitModel::Paper, "paper"), (UnitModel::Table, "table")]);
    serde_round_trip(&[(Interp::Poly, "poly"), (Interp::Pwl, "pwl")]);
    // a configuration naming another is refused at its line
    let e = host_fit::simulate::parse_config(
        std::path::Path::new("u.toml"),
        "[unit]\nmodel = \"paper\"\ninterp = \"spline\"\n",
    )
    .unwrap_err();
    assert_eq!(e.kind(), host_fit::error::ErrorKind::Malformed);
    assert!(e.to_string().starts_with("u.toml:3:"), "{e}");
}

#[test]
fn unit_status() {
    // the summary's and the acceptance verdict's `not_judged` (serde once said `notjudged`)
    round_trip::<host_fit::store::record::UnitStatus>(&["pass", "fail", "not_judged", "error"]);
}

#[test]
fn what_a_discovered_term_corrects() {
    round_trip::<host_fit::diagnose::findings::Corrects>(&["unit", "calibration"]);
}

#[test]
fn test_record_outcomes() {
    // the OpenHTF-like test record's spellings
    use host_fit::store::test_document::{MeasurementOutcome, Outcome};
    round_trip::<Outcome>(&["PASS", "FAIL", "ERROR"]);
    round_trip::<MeasurementOutcome>(&["PASS", "FAIL", "UNSET"]);
}

#[test]
fn acceptance() {
    round_trip::<host_fit::acceptance::Verdict>(&["pass", "fail", "not_judged"]);
    round_trip::<host_fit::acceptance::Band>(&["near_t0", "over_range"]);
    round_trip::<host_fit::acceptance::OutsideRange>(&["fail", "report"]);
}

#[test]
fn compensation_reads_back_from_summary_json() {
    use host_fit::analysis::Compensation;
    round_trip::<Compensation>(&["none", "1", "2"]);
    for c in Compensation::iter() {
        let back: Compensation = serde_json::from_value(serde_json::to_value(c).unwrap()).unwrap();
        assert_eq!(back, c);
    }
    assert!(serde_json::from_str::<Compensation>("\"3\"").is_err());
}

#[test]
fn diagnosis_contract() {
    round_trip::<host_fit::model::effects::EffectId>(&[
        "temp_curvature",
        "thermal_lag",
        "temp_rate",
        "hysteresis",
        "nonlinearity_k2",
        "scale_asymmetry",
        "fixture_error",
        "warmup_drift",
        "discovered",
    ]);
    round_trip::<host_fit::diagnose::contract::Verdict>(&[
        "none",
        "explained",
        "partly_explained",
        "unexplained",
    ]);
    round_trip::<host_fit::diagnose::search::Termination>(&[
        "candidates_used_up",
        "research_rounds_spent",
        "at_floor",
        "not_located",
        "nothing_passed",
        "library_rounds_spent",
        "library_nothing_passed",
    ]);
    round_trip::<host_fit::diagnose::quality::NoteKind>(&[
        "spikes",
        "gaps",
        "coloured_noise",
        "sensor_vs_chamber",
        "one_sample_per_dwell",
        "one_temperature",
        "quantised",
    ]);
    use host_fit::diagnose::location::Grouping;
    round_trip::<Grouping>(&["position", "temperature", "time", "dT/dt", "direction"]);
    // the text report aligns it as a string
    assert_eq!(format!("[{:>8}]", Grouping::Rate), "[   dT/dt]");
    assert_eq!(format!("[{:<9}]", Grouping::Time), "[time     ]");
}

#[test]
fn positions_roles_read_either_case_and_short() {
    use host_fit::data::positions::Role;
    round_trip::<Role>(&["calibration", "verification"]);
    for (s, r) in [
        ("Calibration", Role::Calibration),
        ("cal", Role::Calibration),
        ("CHECK", Role::Verification),
    ] {
        assert_eq!(s.parse::<Role>().ok(), Some(r), "{s}");
    }
    assert!("calib".parse::<Role>().is_err());
}

#[test]
fn demo_plan_target() {
    round_trip::<host_fit::demo_plan::TargetFrom>(&["paper_prediction", "paper_hours"]);
}

#[test]
fn routes_and_plot_styles() {
    text_round_trip::<host_fit::fit::route::Route>(&["static", "joint", "per-stop", "dynamic"]);
    text_round_trip::<host_fit::report::plot::Marker>(&[
        "circle", "square", "triangle", "diamond", "cross", "ring", "none",
    ]);
    text_round_trip::<host_fit::report::plot::Dash>(&["solid", "dashed", "dotted", "dashdot"]);
}

#[test]
fn blind_classes_by_their_command_line_names() {
    use host_fit::blind::forms::Class;
    let all = text_round_trip::<Class>(&[
        "catalogue",
        "other-forms",
        "outside",
        "nuisances",
        "slow",
        "digital",
        "re-clamped",
        "mixtures",
        "discovery-targets",
        "discovery-blind-spots",
        "discovery-controls",
    ]);
    // the report's names stay distinct
    let reported: std::collections::BTreeSet<&str> = all.iter().map(|c| c.name()).collect();
    assert_eq!(reported.len(), all.len());
}

#[test]
fn store_commands() {
    use host_fit::store::record::Command;
    round_trip::<Command>(&["fit", "verify", "diagnose", "batch", "demo"]);
    for c in Command::iter() {
        assert_eq!(Command::from_name(c.name()), Some(c));
    }
}

#[test]
fn trend_rules_by_nelson_number() {
    use host_fit::store::trend::Rule;
    for (i, r) in Rule::ALL.into_iter().enumerate() {
        assert_eq!(usize::from(r.number()), i + 1);
        assert_eq!(Rule::from_number(r.number()), Some(r));
        assert!(r.name().starts_with(&format!("Nelson {}: ", i + 1)));
    }
    let json: Vec<String> = Rule::ALL
        .iter()
        .map(|r| {
            serde_json::to_value(r)
                .unwrap()
                .as_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert_eq!(
        json,
        [
            "BeyondThree",
            "NineOneSide",
            "SixTrending",
            "FourteenAlternating",
            "TwoOfThreeBeyondTwo",
            "FourOfFiveBeyondOne",
            "FifteenWithinOne",
            "EightBeyondOne"
        ]
    );
}

#[test]
fn output_units_keep_an_unknown_label() {
    use host_fit::data::output_unit::OutputUnit;
    for (label, unit) in [
        ("V", OutputUnit::Volt),
        ("mV", OutputUnit::Millivolt),
        ("m/s2", OutputUnit::MetresPerS2),
        ("g", OutputUnit::G),
        ("mg", OutputUnit::MilliG),
        ("counts", OutputUnit::Counts),
        ("LSB", OutputUnit::Other("LSB".into())),
    ] {
        assert_eq!(OutputUnit::parse(label), unit, "{label}");
        assert_eq!(unit.to_string(), label);
        let json = serde_json::to_value(&unit).unwrap();
        assert_eq!(json, serde_json::Value::String(label.into()));
        assert_eq!(serde_json::from_value::<OutputUnit>(json).unwrap(), unit);
    }
    // the format's other spelling reads as the unit, written the one way
    assert_eq!(OutputUnit::parse("m/s^2").to_string(), "m/s2");
}

#[test]
fn command_line_enums() {
    use clap::ValueEnum;
    use host_fit::cli::args::{AllowArg, ErrModel, MethodArg, ModelArg, OutsideArg, RouteArg};
    clap_round_trip::<AllowArg>(&["output-scale", "temperature-scale", "partial"]);
    clap_round_trip::<ErrModel>(&["full", "simplified"]);
    clap_round_trip::<MethodArg>(&["1", "2"]);
    assert_eq!(MethodArg::Two.name(), "2");
    clap_round_trip::<ModelArg>(&["pwl", "poly"]);
    clap_round_trip::<RouteArg>(&["auto", "static", "joint", "per-stop", "dynamic"]);
    clap_round_trip::<OutsideArg>(&["fail", "report"]);
    // the routes the command line names are the ones the outputs name
    for r in RouteArg::value_variants() {
        let name = r.to_possible_value().unwrap().get_name().to_string();
        let route: Option<host_fit::fit::route::Route> = (*r).into();
        assert_eq!(route.map_or("auto", |r| r.name()), name);
    }
}
