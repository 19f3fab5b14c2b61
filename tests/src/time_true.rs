//! The twins and the figures of the time-true tests (issue 22): a unit's production test
//! on an uneven logger clock and its flight, a diagnosed blob verified on both, through
//! the CLI. Shared by `tests/tests/time_true.rs` and the book's `time-true` figure.
use crate::{cli, cli_json};
use host_fit::model::effects::EffectId;
use host_fit::simulate::{
    simulate, Curvature, Fixture, Flight, Logger, PerAxis, SimConfig, Warmup,
};
use std::path::{Path, PathBuf};

/// The catalogue's effects, each concealed alone at its nominal size, a clean unit, and
/// the two pairs whose split decides the flight (issue 27: a lag acts on all 12
/// coefficients through their slopes, a rate term does not; hysteresis beside a rate).
pub const EFFECTS: [&str; 11] = [
    "clean",
    "thermal_lag",
    "temp_rate",
    "hysteresis",
    "nonlinearity_k2",
    "scale_asymmetry",
    "fixture_error",
    "warmup_drift",
    "temp_curvature",
    "thermal_lag+temp_rate",
    "hysteresis+temp_rate",
];

/// The production test of a unit with `effect`, on an uneven logger clock.
pub fn production(effect: &str, seed: u64) -> SimConfig {
    let mut c = SimConfig {
        seed,
        ..SimConfig::default()
    };
    c.unit.serial = format!("TT-{}", effect.replace('+', "-"));
    c.logger = Logger {
        rest_rate_hz: 0.1,
        jitter_s: 0.3,
        drop_rate: 0.01,
        power_off_metadata: true,
        ..Default::default()
    };
    // the unit is switched off for 10 minutes in the soak at -10 C
    c.schedule.power_offs = vec![[8400.0, 600.0]];
    // a pair ("thermal_lag+temp_rate") conceals both
    for one in effect.split('+') {
        conceal(&mut c, one);
    }
    c
}

/// Conceal one catalogue `effect` at its nominal size in `c`.
fn conceal(c: &mut SimConfig, effect: &str) {
    let e = &mut c.effects;
    let axes = |v: [f64; 3]| Some(PerAxis { value: v });
    match effect {
        "thermal_lag" => e.thermal_lag = axes([600.0; 3]),
        "temp_rate" => e.temp_rate = axes([0.02, 0.0, -0.012]),
        "hysteresis" => e.hysteresis = axes([1e-4, -0.8e-4, 0.0]),
        "nonlinearity_k2" => e.nonlinearity_k2 = axes([1e-4, 0.0, -1.2e-4]),
        "scale_asymmetry" => e.scale_asymmetry = axes([2e-4, 0.0, 0.0]),
        "fixture_error" => {
            e.fixture_error = Some(Fixture {
                position: "TP3".into(),
                angles_rad: [4e-4, 1e-4],
            })
        }
        "warmup_drift" => {
            e.warmup_drift = Some(Warmup {
                d_v: [2e-4, 0.0, -1.5e-4],
                tau_s: 1200.0,
            })
        }
        "temp_curvature" => {
            e.temp_curvature = Some(Curvature {
                u0_v: [1e-4, 0.0, -0.8e-4],
                k_rel: [0.0; 3],
                period_c: 25.0,
            })
        }
        _ => {}
    }
}

/// The same unit in flight (the default flight: 73 minutes at 20 Hz).
pub fn in_flight(mut c: SimConfig) -> SimConfig {
    c.flight = Some(Flight::default());
    c
}

/// A path as the CLI takes it.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Write the twin's recording (and its positions file, for a flight) into `dir`.
pub fn write(dir: &Path, name: &str, cfg: &SimConfig) -> (PathBuf, Option<PathBuf>) {
    let sim = simulate(cfg, |_| {}).unwrap();
    let p = dir.join(format!("{name}.csv"));
    std::fs::write(&p, &sim.csv).unwrap();
    let pos = sim.positions_csv.map(|text| {
        let q = dir.join(format!("{name}-positions.csv"));
        std::fs::write(&q, text).unwrap();
        q
    });
    (p, pos)
}

/// `verify --json` of `rec` with `blob`: the worst |dg| of its dwells, mg, and the
/// dwells' |dg| in order.
pub fn verify(rec: &Path, pos: Option<&Path>, blob: &Path) -> (f64, Vec<f64>) {
    let mut args = vec!["verify", s(rec), "--blob", s(blob), "--json"];
    if let Some(p) = pos {
        args.extend(["--positions", s(p)]);
    }
    let (code, out, err) = cli(&args);
    // the figures are the |dg| themselves; the verdict (pass 0, fail 3, or 4: a short
    // flight may hold no attitude near T0, so that band is not judged) is not measured here
    assert!(
        matches!(code, 0 | 3 | 4),
        "verify exit {code}: {}",
        err.lines()
            .filter(|l| !l.starts_with("note") && !l.starts_with("warning"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let dg: Vec<f64> = j["dwells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["dg_mg"].as_f64().unwrap().abs())
        .collect();
    (dg.iter().copied().fold(0.0, f64::max), dg)
}

/// Per effect: the diagnosis's own final max |dg|, the diagnosed blob's worst verification
/// |dg| on the same recording, then on the flight recording the diagnosed blob's and the
/// plain `fit` blob's worst |dg| (mg).
pub fn figures(effect: &str, dir: &Path) -> [f64; 4] {
    let cfg = production(effect, 11);
    let (rec, _) = write(dir, effect, &cfg);
    let diagnosed = dir.join(format!("{effect}-diagnosed.blob"));
    let plain = dir.join(format!("{effect}-plain.blob"));
    let d = cli_json(&[
        "diagnose",
        s(&rec),
        "--out",
        s(&diagnosed),
        "--json",
        "--force",
    ]);
    let own = d["final"]["max_abs_dg_mg"].as_f64().unwrap();
    // a pair's split, for the book (`-- --nocapture` shows it)
    if effect.contains('+') {
        for f in d["findings"].as_array().into_iter().flatten() {
            println!("{effect}: named {} {}", f["effect"], f["parameters"]);
        }
    }
    // this test reaches every stop from below: the split of a hysteresis beside a rate
    // rests on its ramps, and the diagnosis says so (of that pair only)
    let coupled: Vec<String> = d["coupled"]
        .as_array()
        .unwrap_or_else(|| panic!("{effect}: no `coupled` in the diagnosis"))
        .iter()
        .map(|c| c["effects"].to_string())
        .collect();
    let want: &[&str] = if effect == "hysteresis+temp_rate" {
        &[r#"["hysteresis","temp_rate"]"#]
    } else {
        &[]
    };
    assert_eq!(coupled, want, "{effect}: coupled {}", d["coupled"]);
    cli_json(&["fit", s(&rec), "--out", s(&plain), "--json", "--force"]);
    let (fw, _) = verify(&rec, None, &diagnosed);
    let (flight, pos) = write(dir, &format!("{effect}-flight"), &in_flight(cfg));
    let (fl_diag, _) = verify(&flight, pos.as_deref(), &diagnosed);
    let (fl_plain, _) = verify(&flight, pos.as_deref(), &plain);
    [own, fw, fl_diag, fl_plain]
}

/// The per-effect table (the book's `time-true` figure, docs/diagnosis.md): every catalogue effect's
/// figures ([`figures`]), and the table as text.
pub fn table() -> (Vec<(&'static str, [f64; 4])>, String) {
    let dir = tempfile::tempdir().unwrap();
    let mut rows = Vec::new();
    let mut text = String::from(
        "worst |dg|, mg         diagnosis  blob, production (uneven clock)  blob in flight  fit blob in flight\n",
    );
    for effect in EFFECTS {
        let f = figures(effect, dir.path());
        text.push_str(&format!(
            "{effect:<22} {:9.4} {:32.4} {:15.4} {:19.4}\n",
            f[0], f[1], f[2], f[3]
        ));
        rows.push((effect, f));
    }
    (rows, text)
}

/// `c` flying a short flight at `rate_hz` through `legs` (`(to_c, C/min, hold_s)`), 12
/// attitudes held 20 s, the power cycles `power_offs`; the voltmeter and the temperature
/// sensor noiseless, so that flights at different MCU rates differ only by their clock.
pub fn noiseless_flight(
    mut c: SimConfig,
    rate_hz: f64,
    legs: &[(f64, f64, f64)],
    power_offs: Vec<[f64; 2]>,
) -> SimConfig {
    c.unit.noise_v = 0.0;
    c.unit.resolution_v = 0.0;
    c.sensor.noise_c = 0.0;
    c.sensor.quantum_c = 0.0;
    c.flight = Some(Flight {
        rate_hz,
        legs: legs
            .iter()
            .map(|&(to_c, c_per_min, hold_s)| host_fit::simulate::Leg {
                to_c,
                c_per_min,
                hold_s,
            })
            .collect(),
        attitudes: 12,
        hold_s: 20.0,
        move_s: 2.0,
        power_offs,
        ..Flight::default()
    });
    c
}

/// `diagnose --out` of a unit's production test `test`, its blob flown in the unit's
/// flight (`unit` in flight): the worst |dg| in flight, mg, and the diagnosis's JSON.
/// The files are written in `dir`.
pub fn diagnosed_in_flight(
    dir: &Path,
    test: &SimConfig,
    unit: SimConfig,
) -> (f64, serde_json::Value) {
    let (rec, _) = write(dir, "p", test);
    let blob = dir.join("d.blob");
    let j = cli_json(&["diagnose", s(&rec), "--out", s(&blob), "--json", "--force"]);
    let (f, pos) = write(dir, "f", &in_flight(unit));
    (verify(&f, pos.as_deref(), &blob).0, j)
}

/// The effects a `diagnose --json` found, in its order (an effect the contract does not
/// know fails the test that reads it, naming it).
pub fn found(j: &serde_json::Value) -> Vec<EffectId> {
    j["findings"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|f| f["effect"].as_str())
                .map(|e| EffectId::parse(e).unwrap_or_else(|| panic!("unknown effect {e:?}")))
                .collect()
        })
        .unwrap_or_default()
}

/// The production test of `unit` replaced by `plan`'s continuous sweep at `c_per_min`
/// with holds of `hold_min` at each end, on the default chamber and tilter (-40..70 C,
/// the 12 built-in positions, 50-s dwells, 10-s moves); the unit starts soaked at the cold end
/// after cooling there (hysteresis branch -1), its power-offs where the unit's schedule
/// has them.
pub fn on_plan_sweep(unit: &SimConfig, c_per_min: f64, hold_min: f64) -> SimConfig {
    use host_fit::data::positions::{Positions, Role};
    use host_fit::plan::{program, Kind, Limits, DEFAULT_MAX_RAMP_C_PER_MIN};
    let builtin = Positions::default();
    let mut positions = builtin.names_with(Role::Calibration);
    positions.extend(builtin.names_with(Role::Verification));
    let l = Limits {
        lo_c: -40.0,
        hi_c: 70.0,
        max_ramp_c_per_min: DEFAULT_MAX_RAMP_C_PER_MIN,
        positions,
        dwell_s: 50.0,
        move_s: 10.0,
        rate_hz: 1.0,
        noise_v: 2e-5,
        tau_s: 0.0,
        separate: Vec::new(),
    };
    let kind = Kind::Sweep {
        c_per_min,
        hold_min,
        end_hold_min: hold_min,
    };
    let (steps, _) = program(kind, &l);
    let mut c = unit.clone();
    c.chamber.start_c = l.lo_c;
    c.schedule.program = steps;
    c.effects.hysteresis_initial = Some(-1.0);
    c
}
