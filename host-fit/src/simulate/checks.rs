//! The twin's configuration read from TOML and checked before it runs: every number
//! finite, and every width, time constant and state of the effects (and the flight's
//! initial state) in its range. A value out of range is refused with the field it is in
//! (and, read from a file, its line), never taken silently as "none"; so are the
//! schedule's, the logger's and the flight's rates, durations and legs.
use crate::error::{ErrorKind, HostError, Result};
use crate::simulate::config::{Flight, Leg, SimConfig};
use std::path::Path;

/// Why a setting cannot be run: the TOML path of the field, and what it must be.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// The field, as its TOML path (`effects.hysteresis_play_c`).
    pub field: String,
    /// What the value must be.
    pub why: String,
}

impl Refusal {
    fn new(field: impl Into<String>, why: impl Into<String>) -> Self {
        Refusal {
            field: field.into(),
            why: why.into(),
        }
    }

    /// The refusal as an error of the tool (no file).
    pub fn error(&self) -> HostError {
        // the field is shown by the error's Display (`field `...`: why`)
        let mut e = HostError::new(ErrorKind::Invalid, self.why.clone());
        e.field = Some(self.field.clone());
        e
    }
}

/// The first setting of `cfg` that cannot be run, if any.
pub fn refusal(cfg: &SimConfig) -> Option<Refusal> {
    not_finite(cfg)
        .or_else(|| effects(cfg))
        .or_else(|| schedule(cfg))
        .or_else(|| cfg.flight.as_ref().and_then(flight))
}

/// `cfg` as it will run, or the error naming the first field that cannot.
pub fn check(cfg: &SimConfig) -> Result<()> {
    refusal(cfg).map_or(Ok(()), |r| Err(r.error()))
}

/// Parse a TOML configuration and check it ([`check_file`]); the message names the
/// file, the line and the field.
pub fn parse_config(path: &Path, text: &str) -> Result<SimConfig> {
    let cfg: SimConfig = toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text.get(..s.start).unwrap_or(text).matches('\n').count() + 1);
        match line {
            Some(l) => HostError::at(ErrorKind::Malformed, path, l, e.message().to_string()),
            None => HostError::in_file(ErrorKind::Malformed, path, e.message().to_string()),
        }
    })?;
    check_file(&cfg, path, text)?;
    Ok(cfg)
}

/// [`check`] of a configuration read from `path` (its `text`): the error names the file
/// and the line the field is set on.
pub fn check_file(cfg: &SimConfig, path: &Path, text: &str) -> Result<()> {
    match refusal(cfg) {
        None => Ok(()),
        Some(r) => Err(match line_of(text, &r.field) {
            Some(l) => HostError::at_field(ErrorKind::Invalid, path, l, &r.field, r.why),
            None => r.error().within(path),
        }),
    }
}

/// A number that is NaN or infinite anywhere in the configuration (TOML writes both as
/// `nan` and `inf`): found by walking the configuration as TOML, so a field added later
/// is covered without being listed here.
fn not_finite(cfg: &SimConfig) -> Option<Refusal> {
    fn walk(v: &toml::Value, path: &str) -> Option<String> {
        match v {
            toml::Value::Float(x) if !x.is_finite() => Some(path.to_string()),
            toml::Value::Array(a) => a
                .iter()
                .enumerate()
                .find_map(|(i, v)| walk(v, &format!("{path}[{i}]"))),
            toml::Value::Table(t) => t.iter().find_map(|(k, v)| {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                walk(v, &p)
            }),
            _ => None,
        }
    }
    // the seed is the one number TOML cannot hold above i64::MAX (and it is no float)
    let mut c = cfg.clone();
    c.seed = 0;
    match toml::Value::try_from(&c) {
        Ok(v) => walk(&v, "").map(|f| Refusal::new(f, "must be a finite number (not nan or inf)")),
        Err(e) => Some(Refusal::new(
            "(the whole configuration)",
            format!("cannot be checked: {e}"),
        )),
    }
}

/// The effects' widths, time constants and states (the ranges each one's physics has).
fn effects(cfg: &SimConfig) -> Option<Refusal> {
    let e = &cfg.effects;
    let positive = [
        ("hysteresis_width_c", e.hysteresis_width_c, "C of travel"),
        ("hysteresis_play_c", e.hysteresis_play_c, "C of travel"),
        (
            "hysteresis_preisach_c",
            e.hysteresis_preisach_c,
            "C of travel",
        ),
        ("warmup_drift.tau_s", e.warmup_drift.map(|w| w.tau_s), "s"),
        ("warmup_drift2.tau_s", e.warmup_drift2.map(|w| w.tau_s), "s"),
        ("bias_settle.tau_s", e.bias_settle.map(|s| s.tau_s), "s"),
        ("temp_gradient.tau_s", e.temp_gradient.map(|g| g.tau_s), "s"),
        ("periodic.period_s", e.periodic.map(|p| p.period_s), "s"),
        ("move_settle.tau_s", e.move_settle.map(|r| r.tau_s), "s"),
        ("stop_settle.tau_s", e.stop_settle.map(|r| r.tau_s), "s"),
        ("warmup_temp.tau_s", e.warmup_temp.map(|w| w.tau_s), "s"),
        ("telegraph.mean_s", e.telegraph.map(|g| g.mean_s), "s"),
    ];
    for (name, v, unit) in positive {
        if let Some(v) = v {
            if v <= 0.0 {
                return Some(Refusal::new(
                    format!("effects.{name}"),
                    format!("must be > 0 {unit} (leave the setting out for none), not {v}"),
                ));
            }
        }
    }
    // a time constant of 0 on one axis is that axis without the stage; below 0 is nothing
    let lags = [
        (
            "thermal_lag.value",
            e.thermal_lag.map(|l| l.value),
            "the case",
        ),
        (
            "thermal_lag2.value",
            e.thermal_lag2.map(|l| l.value),
            "the first stage",
        ),
    ];
    for (name, v, follows) in lags {
        let Some(v) = v else { continue };
        if let Some((i, x)) = v.iter().enumerate().find(|(_, &x)| x < 0.0) {
            return Some(Refusal::new(
                format!("effects.{name}[{i}]"),
                format!("a time constant must be >= 0 s (0: that axis follows {follows}), not {x}"),
            ));
        }
    }
    let non_negative = [
        ("bias_step.rise_s", e.bias_step.map(|b| b.rise_s), "s"),
        (
            "tilter_repeatability.sigma_rad",
            e.tilter_repeatability.map(|r| r.sigma_rad),
            "rad",
        ),
    ];
    for (name, v, unit) in non_negative {
        if let Some(v) = v.filter(|&v| v < 0.0) {
            return Some(Refusal::new(
                format!("effects.{name}"),
                format!("must be >= 0 {unit}, not {v}"),
            ));
        }
    }
    if let Some(p) = e.temp_curvature.map(|c| c.period_c).filter(|&p| p == 0.0) {
        return Some(Refusal::new(
            "effects.temp_curvature.period_c",
            format!("the period of the shape must not be {p} C"),
        ));
    }
    e.hysteresis_initial
        .and_then(|s| state("effects.hysteresis_initial", s))
}

/// A hysteresis state before the first change at `field` out of [-1, 1] (NaN too).
fn state(field: &str, s: f64) -> Option<Refusal> {
    (!(-1.0..=1.0).contains(&s)).then(|| {
        Refusal::new(
            field,
            format!(
                "the state before the first change is +1 (heated), -1 (cooled) or between, not {s}"
            ),
        )
    })
}

/// The first of `legs` (at `field[i]`) that does not ramp (`c_per_min` > 0) or holds
/// for a negative time, or goes nowhere finite.
// The negated comparisons are the point: NaN fails them.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn legs(field: &str, legs: &[Leg]) -> Option<Refusal> {
    legs.iter().enumerate().find_map(|(i, l)| {
        if !l.to_c.is_finite() {
            Some(Refusal::new(
                format!("{field}[{i}].to_c"),
                format!("must be a finite temperature, not {}", l.to_c),
            ))
        } else if !(l.c_per_min > 0.0 && l.c_per_min.is_finite()) {
            Some(Refusal::new(
                format!("{field}[{i}].c_per_min"),
                format!(
                    "a leg ramps at > 0 C/min (a hold is `hold_s` after it), not {}",
                    l.c_per_min
                ),
            ))
        } else if !(l.hold_s >= 0.0 && l.hold_s.is_finite()) {
            Some(Refusal::new(
                format!("{field}[{i}].hold_s"),
                format!("must be >= 0 s, not {}", l.hold_s),
            ))
        } else {
            None
        }
    })
}

/// The schedule's rates and durations, its stops' ramps and soaks, its sweep's legs, its
/// extra positions, and the logger's clock (every number is finite by now).
// The negated comparisons are the point: NaN fails them.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn schedule(cfg: &SimConfig) -> Option<Refusal> {
    let s = &cfg.schedule;
    let refuse = |field: &str, why: String| Some(Refusal::new(field, why));
    if s.rate_hz <= 0.0 {
        return refuse(
            "schedule.rate_hz",
            format!("must be > 0 Hz, not {}", s.rate_hz),
        );
    }
    // what runs: a program (its own steps), else a sweep, else the stops
    let program = !s.program.is_empty();
    let sweep = s.sweep.as_ref().filter(|_| !program);
    let stops = if program || sweep.is_some() {
        &[][..]
    } else {
        &s.stops[..]
    };
    if (sweep.is_some() || !stops.is_empty()) && s.dwell_s <= 0.0 {
        return refuse(
            "schedule.dwell_s",
            format!("must be > 0 s, not {}", s.dwell_s),
        );
    }
    if s.move_s < 0.0 {
        return refuse(
            "schedule.move_s",
            format!("must be >= 0 s, not {}", s.move_s),
        );
    }
    for (i, stop) in stops.iter().enumerate() {
        if stop.ramp_c_per_min <= 0.0 {
            return refuse(
                &format!("schedule.stops[{i}].ramp_c_per_min"),
                format!(
                    "the ramp to {} C must be > 0 C/min, not {}",
                    stop.temp_c, stop.ramp_c_per_min
                ),
            );
        }
        if stop.soak_s < 0.0 {
            return refuse(
                &format!("schedule.stops[{i}].soak_s"),
                format!(
                    "the soak at {} C must be >= 0 s, not {}",
                    stop.temp_c, stop.soak_s
                ),
            );
        }
    }
    if let Some(r) = sweep.and_then(|w| legs("schedule.sweep.legs", &w.legs)) {
        return Some(r);
    }
    for (i, (name, v)) in s.extra_positions.iter().enumerate() {
        // its length divides it: one that under- or overflows is no direction either
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return refuse(
                &format!("schedule.extra_positions[{i}]"),
                format!(
                    "position `{name}`: the direction of gravity needs a vector other than zero"
                ),
            );
        }
    }
    let l = &cfg.logger;
    if l.rest_rate_hz < 0.0 {
        return refuse(
            "logger.rest_rate_hz",
            format!("must be >= 0 Hz (0: every tick), not {}", l.rest_rate_hz),
        );
    }
    if !(0.0..1.0).contains(&l.drop_rate) {
        return refuse(
            "logger.drop_rate",
            format!(
                "a probability from 0 up to (not including) 1, not {}",
                l.drop_rate
            ),
        );
    }
    // the logger takes the schedule's ticks (a flight writes every one of its own)
    let rate = s.rate_hz;
    if !(l.jitter_s >= 0.0 && l.jitter_s < 1.0 / rate) {
        return refuse(
            "logger.jitter_s",
            format!(
                "must be >= 0 s and less than one tick (1 / {rate} Hz), not {}",
                l.jitter_s
            ),
        );
    }
    None
}

/// A flight's rate, legs, attitudes and holds, each finite (also for a flight given
/// apart from a configuration, which the finiteness walk does not see).
// The negated comparisons are the point: NaN fails them.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn flight(f: &Flight) -> Option<Refusal> {
    let refuse = |field: &str, why: String| Some(Refusal::new(field, why));
    let numbers = [
        ("flight.start_c", f.start_c),
        ("flight.tau_air_s", f.tau_air_s),
        ("flight.tau_case_s", f.tau_case_s),
    ];
    if let Some((field, v)) = numbers.iter().find(|(_, v)| !v.is_finite()) {
        return refuse(field, format!("must be a finite number, not {v}"));
    }
    if let Some(r) = state("flight.initial_direction", f.initial_direction) {
        return Some(r);
    }
    if let Some(i) = f
        .power_offs
        .iter()
        .position(|s| !s.iter().all(|x| x.is_finite()))
    {
        return refuse(
            &format!("flight.power_offs[{i}]"),
            "must be finite numbers".to_string(),
        );
    }
    if !(f.rate_hz > 0.0 && f.rate_hz.is_finite()) {
        return refuse(
            "flight.rate_hz",
            format!("must be > 0 Hz, not {}", f.rate_hz),
        );
    }
    if f.legs.is_empty() {
        return refuse("flight.legs", "a flight needs at least one leg".to_string());
    }
    if let Some(r) = legs("flight.legs", &f.legs) {
        return Some(r);
    }
    if f.attitudes == 0 {
        return refuse(
            "flight.attitudes",
            "a flight needs at least one attitude".to_string(),
        );
    }
    if !(f.hold_s > 0.0 && f.hold_s.is_finite()) {
        return refuse("flight.hold_s", format!("must be > 0 s, not {}", f.hold_s));
    }
    if !(f.move_s >= 0.0 && f.move_s.is_finite()) {
        return refuse("flight.move_s", format!("must be >= 0 s, not {}", f.move_s));
    }
    None
}

/// The 1-based line of `text` that sets `field` (a dotted TOML path as the checks name
/// it, `schedule.stops[2].soak_s`, `effects.thermal_lag.value[1]`): the line `key = ...`
/// under its table, the line that opens its table (`[a.b]`, the (i+1)-th `[[a.b]]` for
/// `a.b[i]`), or the key whose value (an inline table or array, over one line or many)
/// holds it. Keys may be quoted or dotted. None when the field is not written (a
/// default).
pub fn line_of(text: &str, field: &str) -> Option<usize> {
    let mut table = String::new();
    // how many `[[a.b]]` of each array of tables have been opened
    let mut arrays: std::collections::HashMap<String, usize> = Default::default();
    // brackets still open in a value written over several lines (its rows are not headers)
    let mut depth: i64 = 0;
    let mut best: Option<(usize, usize)> = None;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if depth > 0 {
            depth += balance(line);
            continue;
        }
        let path = if let Some(h) = line.strip_prefix("[[") {
            let name = key_path(h.split("]]").next().unwrap_or(""));
            let seen = arrays.entry(name.clone()).or_insert(0);
            table = format!("{name}[{seen}]");
            *seen += 1;
            table.clone()
        } else if let Some(h) = line.strip_prefix('[') {
            table = key_path(h.split(']').next().unwrap_or(""));
            table.clone()
        } else if let Some((k, v)) = line.split_once('=') {
            depth = balance(v).max(0);
            let k = key_path(k);
            if table.is_empty() {
                k
            } else {
                format!("{table}.{k}")
            }
        } else {
            continue;
        };
        // the longest written path that is the field or holds it
        let holds = field == path
            || field.starts_with(&format!("{path}."))
            || field.starts_with(&format!("{path}["));
        if holds && best.is_none_or(|(len, _)| path.len() > len) {
            best = Some((path.len(), n + 1));
        }
    }
    best.map(|(_, n)| n)
}

/// A key as written (`a . "b"`) as a path (`a.b`).
fn key_path(k: &str) -> String {
    k.split('.')
        .map(|p| p.trim().trim_matches(|c| c == '"' || c == '\''))
        .collect::<Vec<_>>()
        .join(".")
}

/// Brackets and braces opened minus those closed in `s`.
fn balance(s: &str) -> i64 {
    s.chars()
        .map(|c| match c {
            '[' | '{' => 1,
            ']' | '}' => -1,
            _ => 0,
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(text: &str) -> HostError {
        parse_config(Path::new("unit.toml"), text).unwrap_err()
    }

    #[test]
    fn a_play_that_is_not_positive_is_refused_on_its_line() {
        let e = refused("seed = 3\n\n[effects]\nhysteresis = { value = [1e-4, 0, 0] }\nhysteresis_play_c = -8\n");
        assert_eq!(e.kind(), ErrorKind::Invalid);
        assert_eq!(e.line, Some(5));
        assert_eq!(e.field.as_deref(), Some("effects.hysteresis_play_c"));
        assert!(e.to_string().contains("unit.toml"), "{e}");
        assert!(e.message.contains("> 0 C"), "{e}");
        let e = refused("[effects]\nhysteresis_preisach_c = 0.0\n");
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(2), Some("effects.hysteresis_preisach_c"))
        );
        let e = refused("[effects]\nhysteresis_width_c = 0\n");
        assert_eq!(e.field.as_deref(), Some("effects.hysteresis_width_c"));
    }

    #[test]
    fn a_number_that_is_not_finite_is_refused_wherever_it_is() {
        let e = refused("[chamber]\ntau_air_s = 30\ntau_case_s = nan\n");
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(3), Some("chamber.tau_case_s"))
        );
        let e = refused("[effects.thermal_lag]\nvalue = [500, inf, 300]\n");
        assert_eq!(e.field.as_deref(), Some("effects.thermal_lag.value[1]"));
        assert_eq!(e.line, Some(2));
    }

    #[test]
    fn time_constants_and_states_out_of_range_are_refused() {
        let cases = [
            (
                "[effects.thermal_lag]\nvalue = [500, -1, 300]\n",
                "effects.thermal_lag.value[1]",
                2,
            ),
            (
                "[effects]\nwarmup_drift = { d_v = [1e-3, 0, 0], tau_s = 0 }\n",
                "effects.warmup_drift.tau_s",
                2,
            ),
            (
                "[effects]\nhysteresis_initial = 2\n",
                "effects.hysteresis_initial",
                2,
            ),
            (
                "[effects.temp_gradient]\nvalue = [1e-4, 0, 0]\ntau_s = -5\n",
                "effects.temp_gradient.tau_s",
                3,
            ),
            (
                "[effects.periodic]\nperiod_s = 0\nvalue = [1e-4, 0, 0]\n",
                "effects.periodic.period_s",
                2,
            ),
            (
                "[effects.move_settle]\nd_v = [1e-4, 0, 0]\ntau_s = -3\n",
                "effects.move_settle.tau_s",
                3,
            ),
            (
                "[effects.temp_gradient]\nvalue = [1e-4, 0, 0]\ntau_s = 0\n",
                "effects.temp_gradient.tau_s",
                3,
            ),
            (
                "[flight]\ninitial_direction = -2\n",
                "flight.initial_direction",
                2,
            ),
            (
                "[[schedule.stops]]\ntemp_c = 0\nsoak_s = 600\n[[schedule.stops]]\ntemp_c = 20\nsoak_s = nan\n",
                "schedule.stops[1].soak_s",
                6,
            ),
        ];
        refused_on_their_lines(&cases);
    }

    /// `cases` (text, field, line) each refused as invalid, naming the field and line.
    fn refused_on_their_lines(cases: &[(&str, &str, usize)]) {
        for &(text, field, line) in cases {
            let e = refused(text);
            assert_eq!(e.kind(), ErrorKind::Invalid, "{text}");
            assert_eq!(
                (e.field.as_deref(), e.line),
                (Some(field), Some(line)),
                "{text}: {e}"
            );
        }
    }

    /// The schedule's and the logger's rates, durations and legs: refused on their line,
    /// in every form they are written (a key, the n-th `[[array]]`, a value over several
    /// lines: the line of its key).
    #[test]
    fn schedule_and_logger_settings_out_of_range_are_refused_on_their_line() {
        refused_on_their_lines(&[
            ("[schedule]\nrate_hz = 0\n", "schedule.rate_hz", 2),
            (
                "[[schedule.stops]]\ntemp_c = 0\n[[schedule.stops]]\ntemp_c = 20\nramp_c_per_min = 0\n",
                "schedule.stops[1].ramp_c_per_min",
                5,
            ),
            (
                "[[schedule.stops]]\ntemp_c = -20\nsoak_s = -60\n",
                "schedule.stops[0].soak_s",
                3,
            ),
            (
                "[schedule]\ndwell_s = 0\n[[schedule.stops]]\ntemp_c = 0\n",
                "schedule.dwell_s",
                2,
            ),
            ("[schedule]\nmove_s = -1\n", "schedule.move_s", 2),
            (
                "[schedule.sweep]\nlegs = [\n  { to_c = -20, c_per_min = 1 },\n  { to_c = 40, c_per_min = 0 },\n]\n",
                "schedule.sweep.legs[1].c_per_min",
                2,
            ),
            (
                "[schedule]\nextra_positions = [[\"E1\", [0.7, 0.7, 0]], [\"E2\", [0, 0, 0]]]\n",
                "schedule.extra_positions[1]",
                2,
            ),
            ("[logger]\ndrop_rate = 1\n", "logger.drop_rate", 2),
            ("[logger]\nrest_rate_hz = -0.1\n", "logger.rest_rate_hz", 2),
            (
                "[schedule]\nrate_hz = 10\n[logger]\njitter_s = 0.2\n",
                "logger.jitter_s",
                4,
            ),
        ]);
    }

    /// The flight's rate, legs, attitudes and holds, on their line.
    #[test]
    fn flight_settings_out_of_range_are_refused_on_their_line() {
        refused_on_their_lines(&[
            ("[flight]\nrate_hz = 0\n", "flight.rate_hz", 2),
            ("[flight]\nlegs = []\n", "flight.legs", 2),
            (
                "[flight]\nrate_hz = 20\n[[flight.legs]]\nto_c = 40\nc_per_min = 6\n[[flight.legs]]\nto_c = 0\nc_per_min = 5\nhold_s = -1\n",
                "flight.legs[1].hold_s",
                9,
            ),
            ("[flight]\nattitudes = 0\n", "flight.attitudes", 2),
            ("[flight]\nhold_s = 0\n", "flight.hold_s", 2),
        ]);
    }

    /// A flight given apart from a configuration (which the finiteness walk does not
    /// see), a direction too short to divide by, and what does not run.
    #[test]
    fn a_flight_apart_a_vanishing_direction_and_settings_that_do_not_run() {
        let f = Flight {
            move_s: -2.0,
            ..Flight::default()
        };
        assert_eq!(flight(&f).map(|r| r.field), Some("flight.move_s".into()));
        // an infinite rate would never end
        let f = Flight {
            rate_hz: f64::INFINITY,
            ..Flight::default()
        };
        assert_eq!(flight(&f).map(|r| r.field), Some("flight.rate_hz".into()));
        assert_eq!(flight(&Flight::default()), None);
        // a vector whose length underflows is no direction
        let e = refused("[schedule]\nextra_positions = [[\"E1\", [1e-200, 0, 0]]]\n");
        assert_eq!(e.field.as_deref(), Some("schedule.extra_positions[0]"));
        // what does not run is not judged: the stops under a sweep
        let sweep = "[schedule.sweep]\nlegs = [{ to_c = 40, c_per_min = 1 }]\n\
                     [[schedule.stops]]\ntemp_c = 0\nramp_c_per_min = 0\n";
        parse_config(Path::new("sweep.toml"), sweep).unwrap();
    }

    #[test]
    fn every_setting_in_range_passes_the_shipped_examples_and_the_blind_suite_too() {
        // zero lag on an axis, a cooled initial state and a play are all meaningful
        let ok = "[effects]\nhysteresis = { value = [1e-4, 0, 0] }\nhysteresis_play_c = 8\n\
                  hysteresis_initial = -1\nthermal_lag = { value = [0, 300, 0] }\n";
        parse_config(Path::new("ok.toml"), ok).unwrap();
        assert_eq!(check(&SimConfig::default()), Ok(()));
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/sim");
        let mut n = 0;
        for f in std::fs::read_dir(&dir).unwrap() {
            let p = f.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml") {
                let text = std::fs::read_to_string(&p).unwrap();
                parse_config(&p, &text).unwrap_or_else(|e| panic!("{e}"));
                n += 1;
            }
        }
        assert!(n >= 2, "the examples in {}", dir.display());
        // every configuration of the long blind suite (its production and flight twins)
        for case in crate::blind::suite(true) {
            let c = crate::blind::config::configure(&case);
            assert_eq!(check(&c), Ok(()), "{case:?}");
            let f = crate::blind::flight::flight_config(&case);
            assert_eq!(check(&f), Ok(()), "{case:?}");
        }
    }

    #[test]
    fn a_seed_beyond_what_toml_holds_still_has_its_numbers_checked() {
        let mut c = SimConfig {
            seed: u64::MAX,
            ..SimConfig::default()
        };
        assert_eq!(check(&c), Ok(()));
        c.chamber.tau_case_s = f64::INFINITY;
        assert_eq!(
            refusal(&c).map(|r| r.field),
            Some("chamber.tau_case_s".to_string())
        );
    }

    #[test]
    fn a_configuration_built_in_code_is_checked_too() {
        let mut c = SimConfig::default();
        c.effects.hysteresis_play_c = Some(-3.0);
        let Err(e) = crate::simulate::simulate(&c, |_| {}) else {
            panic!("a play of -3 C ran")
        };
        assert_eq!(e.field.as_deref(), Some("effects.hysteresis_play_c"));
        assert_eq!(e.line, None);
    }

    #[test]
    fn the_line_of_a_field_is_found_in_each_toml_form() {
        let t = "seed = 1\n[effects]\nx = 1\n[effects.lag]\nvalue = [1, 2]\n[[flight.legs]]\nto_c = 3\n";
        assert_eq!(line_of(t, "seed"), Some(1));
        assert_eq!(line_of(t, "effects.x"), Some(3));
        assert_eq!(line_of(t, "effects.lag.value[1]"), Some(5));
        assert_eq!(line_of(t, "effects.lag.tau"), Some(4));
        assert_eq!(line_of(t, "effects.y"), Some(2));
        assert_eq!(line_of(t, "chamber.tau"), None);
        // the second element of an array of tables, not the first's key
        let t = "[[schedule.stops]]\ntemp_c = 0\nsoak_s = 10\n[[schedule.stops]]\ntemp_c = 5\nsoak_s = nan\n";
        assert_eq!(line_of(t, "schedule.stops[1].soak_s"), Some(6));
        assert_eq!(line_of(t, "schedule.stops[0].soak_s"), Some(3));
        // rows of a value over several lines are not table headers
        let t =
            "[schedule]\npower_offs = [\n  [5000.0, 300.0],\n  [9000.0, 60.0],\n]\nrate_hz = 0\n";
        assert_eq!(line_of(t, "schedule.rate_hz"), Some(6));
        assert_eq!(line_of(t, "schedule.power_offs[1][0]"), Some(2));
        // quoted and dotted keys, spaces around the dots
        let t =
            "[effects . \"thermal_lag\"]\n\"value\" = [1, 2, 3]\neffects.hysteresis_play_c = -1\n";
        assert_eq!(line_of(t, "effects.thermal_lag.value[2]"), Some(2));
        let t = "effects.hysteresis_play_c = -1\n";
        assert_eq!(line_of(t, "effects.hysteresis_play_c"), Some(1));
        // a comment with `=` or `[` is no key and no header
        let t = "[effects] # see [docs] = here\n# x = 3\nx = 4\n";
        assert_eq!(line_of(t, "effects.x"), Some(3));
    }
}
