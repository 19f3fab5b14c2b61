//! The digital twin: recordings parse with the project's reader, a clean recording gives
//! back the truth within the standard errors, and each effect of physics-catalogue.md
//! changes the data the way the catalogue says. Effects are isolated by simulating the
//! same seed with and without them: the noise is identical, the difference is the effect.
use host_fit::data::positions::Positions;
use host_fit::data::recording::{Recording, Row};
use host_fit::data::stops::stops;
use host_fit::error::ErrorKind;
use host_fit::fit::identify::identify_stop;
use host_fit::fit::noise::noise;
use host_fit::simulate::{
    parse_config, simulate, Curvature, Effects, Fixture, Interp, PerAxis, SimConfig, Stop,
    TrueUnit, UnitModel, Warmup,
};
use std::path::Path;

fn run(cfg: &SimConfig) -> Recording {
    let sim = simulate(cfg, |_| {}).unwrap();
    Recording::from_reader(
        Path::new("sim.csv"),
        sim.csv.as_bytes(),
        Positions::default(),
    )
    .unwrap()
}

fn stop(t: f64, soak: f64, pos: &[&str]) -> Stop {
    Stop {
        temp_c: t,
        soak_s: soak,
        ramp_c_per_min: 1.0,
        positions: Some(pos.iter().map(|s| s.to_string()).collect()),
    }
}

/// A short profile: 20 -> 50 -> 20, TP and PP at each stop, no quantisation.
fn base() -> SimConfig {
    let mut c = SimConfig::default();
    c.unit.resolution_v = 0.0;
    c.sensor.quantum_c = 0.0;
    let all = [
        "TP1", "TP2", "TP3", "TP4", "TP5", "TP6", "PP1", "PP3", "PP5",
    ];
    c.schedule.stops = vec![
        stop(20.0, 600.0, &all),
        stop(50.0, 1200.0, &all),
        stop(20.0, 1200.0, &all),
    ];
    c
}

fn with(effects: Effects) -> (Recording, Recording) {
    let a = base();
    let mut b = base();
    b.effects = effects;
    (run(&a), run(&b))
}

fn diffs(a: &Recording, b: &Recording) -> Vec<(Row, [f64; 3])> {
    a.rows
        .iter()
        .zip(&b.rows)
        .map(|(x, y)| (*x, [y.u[0] - x.u[0], y.u[1] - x.u[1], y.u[2] - x.u[2]]))
        .collect()
}

fn rows_in(rec: &Recording, name: &str) -> Vec<usize> {
    let p = rec.positions.index(name).unwrap();
    (0..rec.rows.len())
        .filter(|&i| rec.rows[i].position == Some(p))
        .collect()
}

#[test]
fn toml_config_with_every_effect_parses_and_the_recording_reads() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/sim/all-effects.toml"
    ))
    .unwrap();
    let cfg = parse_config(Path::new("all-effects.toml"), &text).unwrap();
    assert!(
        cfg.effects.thermal_lag.is_some()
            && cfg.effects.warmup_drift.is_some()
            && cfg.effects.fixture_error.is_some()
    );
    let rec = run(&cfg);
    assert!(rec.rows.len() > 1000);
    assert!(rec.dwells.len() > 10);
    let e = parse_config(Path::new("bad.toml"), "seed = 1\n[unit]\nnoise = 3\n").unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Malformed, "{e}");
    assert!(
        e.to_string().contains("bad.toml:3") && e.to_string().contains("noise"),
        "{e}"
    );
}

/// The flight block of all-effects.toml, uncommented, writes a flight recording whose
/// attitudes its positions file names, with the power-off stated.
#[test]
fn the_documented_flight_block_writes_a_flight() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/sim/all-effects.toml"
    ))
    .unwrap();
    let at = text.find("# [flight]").unwrap();
    let flight: String = text[at..]
        .lines()
        .map(|l| l.strip_prefix("# ").unwrap_or(l))
        .collect::<Vec<_>>()
        .join("\n");
    let mut cfg = parse_config(
        Path::new("flight.toml"),
        &format!("{}{flight}", &text[..at]),
    )
    .unwrap();
    let f = cfg.flight.as_mut().unwrap();
    assert_eq!(f.legs.len(), 4);
    // a shorter flight for the test: the first two legs
    f.legs.truncate(2);
    f.legs[1].hold_s = 60.0;
    let sim = simulate(&cfg, |_| {}).unwrap();
    assert!(
        sim.csv.contains("# power_off_s=300-420\n"),
        "{}",
        &sim.csv[..300]
    );
    let dir = tempfile::tempdir().unwrap();
    let pos = dir.path().join("attitudes.csv");
    std::fs::write(&pos, sim.positions_csv.as_ref().unwrap()).unwrap();
    let (positions, _) = host_fit::data::positions::Positions::with_file(&pos).unwrap();
    let rec =
        Recording::from_reader(Path::new("flight.csv"), sim.csv.as_bytes(), positions).unwrap();
    // 20 Hz, the two minutes off not logged
    let dt = rec.rows[1].t_s - rec.rows[0].t_s;
    assert!((dt - 0.05).abs() < 1e-9, "{dt}");
    assert!(rec.rows.iter().all(|r| !(300.0..420.0).contains(&r.t_s)));
    // attitudes all over the sphere, each held 40 s (800 rows)
    let names: std::collections::BTreeSet<&str> = rec
        .dwells
        .iter()
        .map(|d| rec.positions.name(d.position))
        .collect();
    assert!(names.len() >= 20, "{names:?}");
    assert!(rec.dwells.iter().filter(|d| d.len() == 800).count() > 20);
    let temps: Vec<f64> = rec.rows.iter().map(|r| r.temp_c).collect();
    let (lo, hi) = temps
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), t| {
            (l.min(*t), h.max(*t))
        });
    // the case lags the warming air: 35 C after a minute at 45 C
    assert!(lo < -29.0 && hi > 30.0, "{lo} {hi}");
}

/// The logger's clock: rows at 0.1 Hz at rest and at 1 Hz in the dwells, each up to
/// 0.3 s late, 1 % lost, a power-off stated; the physics underneath is the same.
#[test]
fn the_logger_writes_an_uneven_clock() {
    let mut cfg = base();
    cfg.schedule.power_offs = vec![[2000.0, 300.0]];
    cfg.logger = host_fit::simulate::Logger {
        rest_rate_hz: 0.1,
        jitter_s: 0.3,
        drop_rate: 0.01,
        power_off_metadata: true,
        ..Default::default()
    };
    let sim = simulate(&cfg, |_| {}).unwrap();
    assert!(sim.csv.contains("# power_off_s=2000-2300\n"));
    let rec =
        Recording::from_reader(Path::new("u.csv"), sim.csv.as_bytes(), Default::default()).unwrap();
    let steps: Vec<f64> = rec.rows.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    let near = |a: f64, b: f64| (a - b).abs() <= 0.31;
    assert!(
        steps.iter().any(|d| near(*d, 10.0)),
        "rows every 10 s at rest"
    );
    assert!(steps.iter().filter(|d| near(**d, 1.0)).count() > steps.len() / 2);
    assert!(
        steps.iter().any(|d| d.fract().abs() > 0.01),
        "jittered stamps"
    );
    assert!(steps.iter().all(|d| *d > 0.0));
    assert_eq!(rec.power_off, [[2000.0, 2300.0]]);
    let plain = simulate(&base(), |_| {}).unwrap();
    assert!(
        sim.rows < plain.rows * 9 / 10,
        "{} vs {}",
        sim.rows,
        plain.rows
    );
    let bad = host_fit::simulate::Logger {
        jitter_s: 2.0,
        ..cfg.logger.clone()
    };
    cfg.logger = bad;
    assert!(
        simulate(&cfg, |_| {}).is_err(),
        "jitter of more than a tick"
    );
}

#[test]
fn same_seed_same_recording() {
    let a = simulate(&base(), |_| {}).unwrap().csv;
    let b = simulate(&base(), |_| {}).unwrap().csv;
    assert_eq!(a, b);
    let mut c = base();
    c.seed = 2;
    assert_ne!(a, simulate(&c, |_| {}).unwrap().csv);
}

#[test]
fn clean_recording_identifies_the_truth_within_standard_errors() {
    let mut cfg = base();
    // long soaks: the case has settled, so the stop temperature is one temperature
    for s in &mut cfg.schedule.stops {
        s.soak_s = 9000.0;
    }
    let unit = TrueUnit::new(&cfg).unwrap();
    let rec = run(&cfg);
    let nz = noise(&rec);
    assert!(
        (nz.sigma[0] / 2e-5 - 1.0).abs() < 0.1,
        "noise estimate {:?}",
        nz.sigma
    );
    let tp = |p: usize| rec.positions.name(p).starts_with("TP");
    let st = stops(&rec, &tp, 3.0);
    assert_eq!(st.len(), 3);
    let mut worst: f64 = 0.0;
    for s in &st {
        let got = identify_stop(&rec, s, &nz).unwrap();
        let truth = unit.coeffs(s.temp_c);
        for c in 0..12 {
            let z = (got.coeffs[c] - truth[c]) / got.stderr[c];
            worst = worst.max(z.abs());
        }
    }
    assert!(worst < 4.5, "worst z-score {worst}");
}

#[test]
fn nonlinearity_k2_grows_as_a_squared() {
    let k2 = [3e-4, -2e-4, 1e-4];
    let (a, b) = with(Effects {
        nonlinearity_k2: Some(PerAxis { value: k2 }),
        ..Default::default()
    });
    for (row, d) in diffs(&a, &b).iter().filter(|(r, _)| r.position.is_some()) {
        let v = a.positions.vector(row.position.unwrap());
        for i in 0..3 {
            // the recording prints 8 decimals
            assert!((d[i] - k2[i] * v[i] * v[i]).abs() < 1.1e-8, "{:?}", d);
        }
    }
}

#[test]
fn scale_asymmetry_grows_as_abs_a() {
    let delta = [2e-4, 0.0, -3e-4];
    let (a, b) = with(Effects {
        scale_asymmetry: Some(PerAxis { value: delta }),
        ..Default::default()
    });
    let unit = TrueUnit::new(&base()).unwrap();
    for (row, d) in diffs(&a, &b).iter().filter(|(r, _)| r.position.is_some()) {
        let v = a.positions.vector(row.position.unwrap());
        let c = unit.coeffs(row.temp_c);
        for (i, kii) in [(0, c[0]), (2, c[2])] {
            let want = kii * delta[i] * v[i].abs();
            // the sensor reads the case with noise: coefficients at the true case temperature
            assert!(
                (d[i] - want).abs() < 1e-9 + want.abs() * 1e-3,
                "{} vs {want}",
                d[i]
            );
        }
        assert_eq!(d[1], 0.0);
    }
}

#[test]
fn temp_rate_follows_dt_dt_not_the_temperature() {
    let r = [0.05, -0.03, 0.0];
    let (a, b) = with(Effects {
        temp_rate: Some(PerAxis { value: r }),
        ..Default::default()
    });
    let d = diffs(&a, &b);
    // heating and cooling ramps: the bias has the sign of dT/dt; settled: ~0
    let chamber: Vec<f64> = a.rows.iter().map(|r| r.chamber_c.unwrap()).collect();
    let mut heating = 0;
    let mut cooling = 0;
    for k in 60..d.len() {
        if chamber[k] - chamber[k - 60] > 0.5 {
            assert!(d[k].1[0] > 0.0 && d[k].1[1] < 0.0);
            heating += 1;
        } else if chamber[k] - chamber[k - 60] < -0.5 {
            assert!(d[k].1[0] < 0.0 && d[k].1[1] > 0.0);
            cooling += 1;
        }
    }
    assert!(heating > 100 && cooling > 100);
    assert!(
        d.last().unwrap().1[0].abs() < 0.05 * 1e-3,
        "settled at the end: {:?}",
        d.last().unwrap().1
    );
}

#[test]
fn thermal_lag_shows_after_temperature_changes_and_vanishes_when_settled() {
    let mut plain = base();
    plain.schedule.stops[2].soak_s = 20_000.0;
    let mut lagged = plain.clone();
    lagged.effects.thermal_lag = Some(PerAxis {
        value: [900.0, 900.0, 900.0],
    });
    let (a, b) = (run(&plain), run(&lagged));
    let d = diffs(&a, &b);
    let (k_max, max) = d
        .iter()
        .enumerate()
        .map(|(k, x)| (k, x.1[0].abs()))
        .fold((0, 0.0), |m, x| if x.1 > m.1 { x } else { m });
    assert!(max > 1e-4, "lag visible during the change: {max}");
    // the largest effect is while the temperature moves, and it has settled at the end
    // ... right after a temperature change: the sensor moved in the 15 minutes before
    let moved = a.rows[k_max].temp_c - a.rows[k_max.saturating_sub(900)].temp_c;
    assert!(
        moved.abs() > 1.0,
        "largest lag error right after a change ({moved} C in 15 min)"
    );
    let end = d.last().unwrap().1[0].abs();
    assert!(end < 0.01 * max, "{end} vs {max}");
}

#[test]
fn hysteresis_splits_heating_from_cooling() {
    let h = [4e-4, 0.0, -2e-4];
    let (a, b) = with(Effects {
        hysteresis: Some(PerAxis { value: h }),
        ..Default::default()
    });
    let d = diffs(&a, &b);
    // first 20 C stop: initial direction heating (+h/2); final 20 C stop reached by cooling (-h/2)
    let tp2 = rows_in(&a, "TP2");
    let (first, last) = (tp2[0], *tp2.last().unwrap());
    assert!((d[first].1[0] - h[0] / 2.0).abs() < 1.1e-8);
    assert!((d[last].1[0] + h[0] / 2.0).abs() < 1.1e-8);
    assert!((d[last].1[2] - h[2] / -2.0).abs() < 1.1e-8);
}

#[test]
fn fixture_error_moves_one_position_only() {
    let (a, b) = with(Effects {
        fixture_error: Some(Fixture {
            position: "TP3".into(),
            angles_rad: [2e-3, -1e-3],
        }),
        ..Default::default()
    });
    let tp3 = a.positions.index("TP3").unwrap();
    for (row, d) in diffs(&a, &b) {
        let moved = d.iter().any(|x| x.abs() > 1e-12);
        match row.position {
            Some(p) if p == tp3 => assert!(moved),
            Some(_) => assert!(!moved),
            None => {}
        }
    }
}

/// Every axis settles by its own amount with the one time constant since power-on (an
/// axis without a drift does not move).
#[test]
fn warmup_drift_decays_with_time_since_power_on() {
    let d_v = [1e-3, -5e-4, 0.0];
    let (a, b) = with(Effects {
        warmup_drift: Some(Warmup { d_v, tau_s: 600.0 }),
        ..Default::default()
    });
    let mut rows = 0;
    for (row, d) in diffs(&a, &b) {
        for axis in 0..3 {
            let want = d_v[axis] * (-row.t_s / 600.0).exp();
            assert!(
                (d[axis] - want).abs() < 1.1e-8,
                "axis {axis} at t {}: {} vs {want}",
                row.t_s,
                d[axis]
            );
        }
        rows += 1;
    }
    assert!(rows > 100, "{rows} rows compared");
}

#[test]
fn temp_curvature_changes_the_coefficients_between_stops() {
    let mut cfg = base();
    cfg.effects.temp_curvature = Some(Curvature {
        u0_v: [5e-4, 0.0, 0.0],
        k_rel: [0.0; 3],
        period_c: 60.0,
    });
    let plain = TrueUnit::new(&base()).unwrap();
    let curved = TrueUnit::new(&cfg).unwrap();
    assert_eq!(plain.coeffs(20.0), curved.coeffs(20.0));
    let dt = curved.coeffs(35.0)[9] - plain.coeffs(35.0)[9];
    assert!(
        (dt - 5e-4).abs() < 1e-12,
        "a quarter period above T0: full amplitude ({dt})"
    );
}

#[test]
fn the_paper_unit_passes_through_the_papers_tables() {
    let unit = TrueUnit::new(&SimConfig::default()).unwrap();
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../testdata/paper/paper-tables.csv"
    ))
    .unwrap();
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("temp"))
    {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let c = unit.coeffs(v[0]);
        for k in 0..12 {
            assert!((c[k] - v[k + 1]).abs() < 1e-12, "{} C coeff {k}", v[0]);
        }
    }
}

/// A sweep: the tilter turns through the positions the whole time while the set point
/// ramps up and back (no soaks), so most dwells move in temperature, the profile's
/// duration is the legs', and the temperature turns at the hot end.
#[test]
fn a_sweep_turns_the_tilter_while_the_chamber_ramps() {
    use host_fit::fit::route::detect::Shape;
    use host_fit::simulate::{Leg, Sweep};
    let mut cfg = SimConfig::default();
    cfg.chamber.start_c = 0.0;
    cfg.schedule.dwell_s = 50.0;
    cfg.schedule.move_s = 10.0;
    cfg.schedule.sweep = Some(Sweep {
        legs: vec![
            Leg {
                to_c: 60.0,
                c_per_min: 4.0,
                hold_s: 120.0,
            },
            Leg {
                to_c: 0.0,
                c_per_min: 4.0,
                hold_s: 0.0,
            },
        ],
    });
    let rec = run(&cfg);
    let last = rec.rows.last().unwrap().t_s;
    // 900 s up, 120 s held, 900 s down: 32 whole move+dwell cycles of 60 s, then the
    // move back to rest
    assert!(last > 1915.0 && last < 1930.0, "{last}");
    let shape = Shape::of(&rec);
    assert!(shape.is_sweep(), "{shape:?}");
    let (hot_i, hot) = rec
        .rows
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.temp_c.total_cmp(&b.1.temp_c))
        .unwrap();
    // the case lags the air (10 min): it turns short of the set point
    assert!(hot.temp_c > 30.0 && hot.temp_c < 60.5, "{}", hot.temp_c);
    assert!(hot_i > rec.rows.len() / 3 && hot_i < rec.rows.len() * 5 / 6);
    assert!(rec.rows.last().unwrap().temp_c < hot.temp_c - 5.0);
    let names: std::collections::BTreeSet<usize> = rec.dwells.iter().map(|d| d.position).collect();
    assert_eq!(names.len(), 12, "every position visited");
    // a stop-and-soak test is not a sweep
    assert!(!Shape::of(&run(&base())).is_sweep());
}

/// A chamber program (`simulate --plan`): the set point runs linearly from row to row,
/// the tilter holds each row's position (or moves, `-`), the unit starts soaked at the
/// first set point; a bad program is refused naming the line and the field.
#[test]
fn a_program_drives_the_chamber_and_the_tilter() {
    use host_fit::simulate::program::{parse_program, to_csv};
    let text = "time_s,setpoint_c,position\n0,10,TP1\n300,10,-\n310,10,TP3\n400,40,TP3\n1000,40,PP2\n1100,40,PP2\n";
    let p = Path::new("plan.csv");
    let steps = parse_program(p, text).unwrap();
    assert_eq!(to_csv(&steps), text);
    let mut cfg = SimConfig::default();
    cfg.chamber.start_c = 10.0;
    cfg.schedule.program = steps;
    let rec = run(&cfg);
    let pos = |n: &str| rec.positions.index(n).unwrap();
    let at = |t: f64| rec.rows.iter().find(|r| r.t_s >= t).unwrap();
    assert_eq!(rec.rows.last().unwrap().t_s, 1099.0);
    let d: Vec<(usize, usize)> = rec
        .dwells
        .iter()
        .map(|d| (d.position, d.end - d.start))
        .collect();
    assert_eq!(
        d,
        vec![(pos("TP1"), 300), (pos("TP3"), 690), (pos("PP2"), 100)]
    );
    // soaked at 10 C until the ramp starts at 310 s; 40 C set from 400 s, the case lags
    assert!((at(300.0).temp_c - 10.0).abs() < 0.15);
    let (t700, t1090) = (at(700.0).temp_c, at(1090.0).temp_c);
    assert!(
        t700 > 15.0 && t700 < t1090 && t1090 < 40.0,
        "{t700} {t1090}"
    );
    for (bad, line, field) in [
        (
            "time_s,setpoint_c,position\n0,10,TP1\n0,20,TP2\n",
            3,
            "time_s",
        ),
        (
            "time_s,setpoint_c,position\n0,10,TP1\n5,hot,TP2\n",
            3,
            "setpoint_c",
        ),
        (
            "time,setpoint_c,position\n0,10,TP1\n5,10,TP2\n",
            1,
            "header",
        ),
    ] {
        let e = parse_program(p, bad).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Malformed, "{e}");
        let e = e.to_string();
        assert!(
            e.contains(&format!("plan.csv:{line}")) && e.contains(field),
            "{e}"
        );
    }
    let mut bad = SimConfig::default();
    bad.schedule.program = parse_program(
        p,
        "time_s,setpoint_c,position\n0,10,TP1\n5,10,XX9\n9,10,TP1\n",
    )
    .unwrap();
    let e = simulate(&bad, |_| {}).err().unwrap();
    assert_eq!(e.kind(), ErrorKind::Invalid, "{e}");
    assert!(e.to_string().contains("XX9"), "{e}");
}

/// A configuration with every option set (every `Option` `Some`, every list non-empty),
/// written without `..Default::default()`: a new field does not compile until it is
/// added here, and then [`all_effects_toml_documents_every_option`] fails until the
/// example documents it.
fn every_option() -> SimConfig {
    use host_fit::data::output_unit::OutputUnit;
    use host_fit::simulate::{Chamber, Flight, Leg, Logger, Output, Schedule, Sensor, Unit};
    SimConfig {
        seed: 1,
        t0_c: 20.0,
        chamber: Chamber {
            start_c: 20.0,
            tau_air_s: 120.0,
            tau_case_s: 600.0,
        },
        sensor: Sensor {
            noise_c: 0.02,
            quantum_c: 0.0625,
            offset_c: 0.1,
            gain_error: 1e-3,
        },
        schedule: Schedule {
            rate_hz: 1.0,
            dwell_s: 60.0,
            move_s: 10.0,
            rest_position: "TP1".into(),
            positions: vec!["TP1".into()],
            stops: vec![Stop {
                temp_c: 20.0,
                soak_s: 600.0,
                ramp_c_per_min: 1.0,
                positions: Some(vec!["TP1".into()]),
            }],
            extra_positions: vec![("W1".into(), [1.0, 0.0, 0.0])],
            dropouts: vec![[10.0, 1.0]],
            power_offs: vec![[20.0, 1.0]],
            dwell_means: true,
            sweep: Some(host_fit::simulate::Sweep {
                legs: vec![Leg {
                    to_c: 30.0,
                    c_per_min: 2.0,
                    hold_s: 60.0,
                }],
            }),
            program: vec![host_fit::simulate::program::Step {
                time_s: 0.0,
                setpoint_c: 20.0,
                position: "TP1".into(),
            }],
        },
        unit: Unit {
            serial: "S".into(),
            model: UnitModel::Table,
            temps_c: vec![20.0],
            coeffs: vec![[0.0; 12]],
            interp: Interp::Pwl,
            noise_v: 2e-5,
            resolution_v: 1e-7,
            noise_corr_s: 1.0,
            spike_rate: 1e-4,
            spike_v: 1e-3,
        },
        effects: every_effect(),
        logger: Logger {
            rest_rate_hz: 0.1,
            jitter_s: 0.1,
            drop_rate: 0.01,
            power_off_metadata: true,
            rest_unnamed: true,
        },
        flight: Some(Flight {
            legs: vec![Leg {
                to_c: 20.0,
                c_per_min: 1.0,
                hold_s: 60.0,
            }],
            ..Flight::default()
        }),
        output: Output {
            unit: OutputUnit::Counts,
            per_v: 7.0,
            quantum: 1.0,
        },
    }
}

/// Every effect of [`every_option`] set (a literal without `..`, for the same reason).
fn every_effect() -> Effects {
    use host_fit::simulate::{Bend, BiasStep, FixtureChange, Gradient, Periodic, Settle};
    use host_fit::simulate::{Quadratic, Relaxation, Repeatability, Telegraph, TempWarmup, TurnOn};
    let p = |v: f64| {
        Some(PerAxis {
            value: [v, 0.0, 0.0],
        })
    };
    let fixture = |name: &str| Fixture {
        position: name.into(),
        angles_rad: [1e-3, 0.0],
    };
    let warmup = Warmup {
        d_v: [1e-4, 0.0, 0.0],
        tau_s: 900.0,
    };
    Effects {
        temp_curvature: Some(Curvature {
            u0_v: [1e-4, 0.0, 0.0],
            k_rel: [0.0; 3],
            period_c: 60.0,
        }),
        thermal_lag: p(600.0),
        temp_rate: p(0.01),
        hysteresis: p(1e-4),
        nonlinearity_k2: p(1e-4),
        scale_asymmetry: p(1e-4),
        fixture_error: Some(fixture("TP3")),
        warmup_drift: Some(warmup),
        thermal_lag2: p(300.0),
        temp_gradient: Some(Gradient {
            value: [1e-4, 0.0, 0.0],
            tau_s: 400.0,
        }),
        hysteresis_initial: Some(-1.0),
        hysteresis_width_c: Some(5.0),
        hysteresis_play_c: Some(8.0),
        hysteresis_preisach_c: Some(12.0),
        scale_hysteresis: p(1e-4),
        warmup_drift2: Some(warmup),
        temp_bend: Some(Bend {
            knot_c: 35.0,
            u0_v_per_c: [1e-5, 0.0, 0.0],
            k_rel_per_c: [0.0; 3],
        }),
        fixture_error2: Some(fixture("PP2")),
        bias_step: Some(BiasStep {
            at_s: 100.0,
            value: [1e-4, 0.0, 0.0],
            rise_s: 10.0,
        }),
        bias_walk: p(1e-6),
        nonlinearity_k3: p(1e-4),
        periodic: Some(Periodic {
            period_s: 100.0,
            value: [1e-4, 0.0, 0.0],
            phase_rad: 0.5,
        }),
        scale_aging: p(1e-4),
        fixture_change: Some(FixtureChange {
            position: "TP5".into(),
            before_rad: [0.0; 2],
            angles_rad: [1e-3, 0.0],
            at_s: 100.0,
        }),
        bias_aging: p(1e-5),
        bias_settle: Some(Settle {
            at_s: 100.0,
            value: [1e-4, 0.0, 0.0],
            tau_s: 60.0,
        }),
        quadratic: Some(Quadratic {
            value: [[0.0, 0.0, 0.0, 1e-4, 0.0, 0.0]; 3],
        }),
        k2_temp: p(1e-6),
        scale_rate: p(1e-4),
        warmup_temp: Some(TempWarmup {
            v_per_c: [1e-6, 0.0, 0.0],
            tau_s: 900.0,
        }),
        turn_on_bias: Some(TurnOn {
            value: vec![[1e-4, 0.0, 0.0]],
        }),
        move_settle: Some(Relaxation {
            d_v: [1e-4, 0.0, 0.0],
            tau_s: 25.0,
        }),
        stop_settle: Some(Relaxation {
            d_v: [1e-4, 0.0, 0.0],
            tau_s: 1200.0,
        }),
        tilter_repeatability: Some(Repeatability { sigma_rad: 1e-4 }),
        telegraph: Some(Telegraph {
            value: [1e-4, 0.0, 0.0],
            mean_s: 600.0,
        }),
    }
}

/// The key paths of a TOML value (`schedule.stops[].temp_c`): tables and arrays of tables
/// are walked, anything else is a leaf.
fn key_paths(v: &toml::Value, at: &str, out: &mut std::collections::BTreeSet<String>) {
    let join = |k: &str| {
        if at.is_empty() {
            k.to_string()
        } else {
            format!("{at}.{k}")
        }
    };
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t {
                out.insert(join(k));
                key_paths(x, &join(k), out);
            }
        }
        toml::Value::Array(a) if a.iter().all(|x| x.is_table()) => {
            for x in a {
                key_paths(x, &format!("{at}[]"), out);
            }
        }
        _ => {}
    }
}

/// `examples/sim/all-effects.toml` documents every option of the configuration: each key
/// path of a configuration with every option set (derived from the configuration's own
/// types by serialising it) is a key of the example, active or in one of its commented
/// alternative blocks (a `# [section]` line and the comment lines after it), and each of
/// those blocks is itself a valid configuration.
#[test]
fn all_effects_toml_documents_every_option() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/sim/all-effects.toml"
    ))
    .unwrap();
    let mut documented = std::collections::BTreeSet::new();
    let mut docs = vec![text.clone()];
    let lines: Vec<&str> = text.lines().collect();
    let mut k = 0;
    while k < lines.len() {
        if lines[k].starts_with("# [") {
            let mut block = Vec::new();
            while k < lines.len() && lines[k].starts_with('#') {
                let l = lines[k];
                block.push(l.strip_prefix("# ").unwrap_or(&l[1..]));
                k += 1;
            }
            docs.push(block.join("\n"));
        } else {
            k += 1;
        }
    }
    assert!(docs.len() >= 5, "the alternative blocks: {}", docs.len());
    for d in &docs {
        parse_config(Path::new("all-effects.toml"), d).unwrap_or_else(|e| panic!("{e}\n{d}"));
        key_paths(&toml::from_str(d).unwrap(), "", &mut documented);
    }
    let mut options = std::collections::BTreeSet::new();
    key_paths(
        &toml::Value::try_from(every_option()).unwrap(),
        "",
        &mut options,
    );
    assert!(options.len() > 100, "{options:?}");
    let missing: Vec<&String> = options.difference(&documented).collect();
    assert!(
        missing.is_empty(),
        "all-effects.toml does not document {missing:?}"
    );
}
