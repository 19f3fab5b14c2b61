//! The twin's configuration read from TOML and checked before it runs: every number
//! finite, every width, time constant and state in its range. A value out of range is
//! refused with the field it is in (and, read from a file, its line), never taken
//! silently as "none".
use crate::error::{ErrorKind, HostError, Result};
use crate::simulate::config::SimConfig;
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
    not_finite(cfg).or_else(|| effects(cfg))
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
    // a configuration that does not serialise has nothing non-finite this walk could see
    let v = toml::Value::try_from(cfg).ok()?;
    walk(&v, "").map(|f| Refusal::new(f, "must be a finite number (not nan or inf)"))
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
    // a time constant of 0 on one axis is that axis without the lag; below 0 is nothing
    let lags = [
        ("thermal_lag.value", e.thermal_lag.map(|l| l.value)),
        ("thermal_lag2.value", e.thermal_lag2.map(|l| l.value)),
    ];
    for (name, v) in lags {
        if let Some(i) = v.and_then(|v| v.iter().position(|&x| x < 0.0)) {
            return Some(Refusal::new(
                format!("effects.{name}[{i}]"),
                "a time constant must be >= 0 s (0: that axis follows the case)",
            ));
        }
    }
    let non_negative = [
        ("temp_gradient.tau_s", e.temp_gradient.map(|g| g.tau_s), "s"),
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
    if let Some(s) = e.hysteresis_initial.filter(|s| !(-1.0..=1.0).contains(s)) {
        return Some(Refusal::new(
            "effects.hysteresis_initial",
            format!(
                "the state before the first change is +1 (heated), -1 (cooled) or between, not {s}"
            ),
        ));
    }
    None
}

/// The 1-based line of `text` that sets `field` (a dotted TOML path, indices dropped):
/// the line `key = ...` under its table, the line that opens its table (`[a.b]`), or an
/// inline table (`b = { ... }`) that holds it. None when the field is not written (a
/// default, or a form this simple reading does not follow).
pub fn line_of(text: &str, field: &str) -> Option<usize> {
    let field: String = field
        .split('.')
        .map(|k| k.split('[').next().unwrap_or(k))
        .collect::<Vec<_>>()
        .join(".");
    let mut table = String::new();
    let mut best: Option<(usize, usize)> = None;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let path = if let Some(h) = line.strip_prefix('[') {
            let h = h.trim_start_matches('[');
            table = h.split(']').next().unwrap_or("").trim().to_string();
            table.clone()
        } else if let Some((k, _)) = line.split_once('=') {
            let k = k.trim();
            if table.is_empty() {
                k.to_string()
            } else {
                format!("{table}.{k}")
            }
        } else {
            continue;
        };
        // the longest written path that is the field or holds it
        let holds = field == path || field.starts_with(&format!("{path}."));
        if holds && best.is_none_or(|(len, _)| path.len() > len) {
            best = Some((path.len(), n + 1));
        }
    }
    best.map(|(_, n)| n)
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
        ];
        for (text, field, line) in cases {
            let e = refused(text);
            assert_eq!(e.kind(), ErrorKind::Invalid, "{text}");
            assert_eq!(
                (e.field.as_deref(), e.line),
                (Some(field), Some(line)),
                "{text}: {e}"
            );
        }
    }

    #[test]
    fn every_setting_in_range_runs_and_the_shipped_examples_pass() {
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
    }
}
