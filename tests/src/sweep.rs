//! The chamber-time twins (issue 19): one unit recorded three ways, a continuous sweep of
//! at most 2 h (the tilter turning while the chamber heats and cools, no soaks), the
//! classic 6-h stop-and-soak test, and an equilibrium verification block (long soaks at
//! three temperatures, nothing logged while the chamber moves) used only to judge; each
//! blob verified through firmware-core.
use crate::time_true::{s, verify, write};
use crate::{cli, cli_json};
use host_fit::simulate::{Leg, Logger, PerAxis, SimConfig, Stop, Sweep};
use std::path::Path;

/// The unit: the paper unit, its element lagging its temperature sensor by `lag_s`
/// (0: none), on the given seed.
pub fn unit(lag_s: f64, seed: u64) -> SimConfig {
    let mut c = SimConfig {
        seed,
        ..SimConfig::default()
    };
    c.unit.serial = format!("SW-{lag_s:.0}");
    if lag_s > 0.0 {
        c.effects.thermal_lag = Some(PerAxis { value: [lag_s; 3] });
    }
    c
}

/// The sweep: soaked at -40 C, heat to +70 C at 3 C/min, 30 min there, cool to -40 C at
/// 3.5 C/min, 20 min there; the tilter turning through the 12 positions (50-s dwells,
/// 10-s moves) the whole time: 118 min of chamber time. (Slower ramps with shorter holds,
/// 2 C/min and 10 min, leave the element of a 20-min lag short of the hot end: 0.046 mg
/// at +55 C against 0.012 mg on one unit.)
pub fn sweep(mut c: SimConfig) -> SimConfig {
    c.chamber.start_c = -40.0;
    c.schedule.dwell_s = 50.0;
    c.schedule.sweep = Some(Sweep {
        legs: vec![
            Leg {
                to_c: 70.0,
                c_per_min: 3.0,
                hold_s: 1800.0,
            },
            Leg {
                to_c: -40.0,
                c_per_min: 3.5,
                hold_s: 1200.0,
            },
        ],
    });
    c
}

/// The equilibrium verification block: soaked 2.5 h at each of -25, +20 and +55 C
/// (longer than seven of the slowest lag's time constants), then the 12 positions; the
/// logger writes a row every 10 s while the unit rests, unnamed, so the firmware sees
/// the whole temperature history and every dwell judged is in equilibrium.
pub fn judge(mut c: SimConfig) -> SimConfig {
    c.chamber.start_c = -25.0;
    c.seed ^= 0x5EED;
    c.schedule.stops = [-25.0, 20.0, 55.0]
        .iter()
        .map(|t| Stop {
            temp_c: *t,
            soak_s: 9000.0,
            ramp_c_per_min: 2.0,
            positions: None,
        })
        .collect();
    c.logger = Logger {
        rest_rate_hz: 0.1,
        rest_unnamed: true,
        ..Logger::default()
    };
    c
}

/// What one recording's `fit` blob does on the verification block.
#[derive(Debug, Clone, Copy)]
pub struct Judged {
    /// Worst |dg| over the verification dwells, mg.
    pub worst_mg: f64,
    /// Acceptance passed.
    pub pass: bool,
    /// The thermal lag the blob carries, s (None: none).
    pub lag_s: Option<f64>,
}

/// `fit` of `rec` (extra arguments `args`), then `verify` on `judge`.
pub fn fit_and_judge(dir: &Path, rec: &Path, judge: &Path, args: &[&str]) -> Judged {
    let b = dir.join("b.blob");
    let mut all = vec!["fit", s(rec), "--out", s(&b), "--force", "--json"];
    all.extend(args);
    let j = cli_json(&all);
    let (worst_mg, _) = verify(judge, None, &b);
    let (code, _, _) = cli(&["verify", s(judge), "--blob", s(&b)]);
    Judged {
        worst_mg,
        pass: code == 0,
        lag_s: j["thermal_lag_tau_s"].as_f64(),
    }
}

/// The last `t_s` of a recording, h.
pub fn hours(rec: &Path) -> f64 {
    let text = std::fs::read_to_string(rec).unwrap();
    let last = text.lines().last().unwrap();
    last.split(',').next().unwrap().parse::<f64>().unwrap() / 3600.0
}

/// A unit with lag `lag_s` recorded three ways: the sweep's default `fit`, the 6-h
/// test's `fit --route static`, and the 6-h test's default `fit` (the route chosen by
/// the data: dynamic where its dwells still settle and the held-out blocks keep the
/// lag), each judged; and the sweep's chamber hours.
pub fn three_ways(dir: &Path, lag_s: f64, seed: u64) -> ([Judged; 3], f64) {
    let u = unit(lag_s, seed);
    let (sw, _) = write(dir, "sweep", &sweep(u.clone()));
    let (long, _) = write(dir, "long", &u);
    let (jd, _) = write(dir, "judge", &judge(u));
    (
        [
            fit_and_judge(dir, &sw, &jd, &[]),
            fit_and_judge(dir, &long, &jd, &["--route", "static"]),
            fit_and_judge(dir, &long, &jd, &[]),
        ],
        hours(&sw),
    )
}
