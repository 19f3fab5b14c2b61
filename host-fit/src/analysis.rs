//! The demo's comparison, pure: a recording fitted with the paper's model (when it has
//! stops near -40, +20, +70 C), with the model the data choose and with the pwl through
//! every stop, each built into a blob, its verification positions compensated through
//! firmware-core with methods 1 and 2, and judged against the acceptance specification.
use crate::acceptance::{judge, Acceptance, Spec};
use crate::blob::build_blob;
use crate::data::positions::Role;
use crate::data::recording::Recording;
use crate::data::table::TableRow;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::equilibrium::static_observations;
use crate::fit::identify::StopCoeffs;
use crate::fit::noise::noise;
use crate::fit::pipeline::{fit_chosen, identify_stops, stop_temperatures, ModelRequest};
use crate::fit::select::Selection;
use crate::fit::temperature::{fit_joint, fit_table, Frame, ModelFit, Setting};
use crate::model::basis::Basis;
use crate::simulate::TrueUnit;
use crate::verify::{verify, Verification};
use firmware_core::compensate::{ErrorModel, Method};
use serde::{Deserialize, Serialize};

/// How a row's outputs were compensated.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str", try_from = "String")]
pub enum Compensation {
    /// Not at all: the T0 constants.
    #[strum(serialize = "none")]
    None,
    /// Method 1: correct the constants.
    #[strum(serialize = "1")]
    Method1,
    /// Method 2: correct the result.
    #[strum(serialize = "2")]
    Method2,
}

impl Compensation {
    /// `none`, `1` or `2`, as summary.json and the table write it.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl TryFrom<String> for Compensation {
    type Error = strum::ParseError;
    fn try_from(s: String) -> std::result::Result<Self, Self::Error> {
        s.parse()
    }
}

/// One row of summary.json.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SummaryRow {
    /// `t0-constants`, `paper-pwl2`, `polyN`, `pwl-all`.
    pub model: String,
    /// `none`, `1` or `2`.
    pub method: Compensation,
    /// Verification temperature, C.
    pub temp_c: f64,
    /// Max |dg| over the verification positions, mg.
    pub max_abs_dg_mg: f64,
}

/// A model of the comparison, by what it is: its name in the summary and its blob's
/// file follow from it (never the other way round).
#[derive(Debug, Clone, PartialEq)]
pub enum Compared {
    /// The paper's: piecewise-linear through its stops near -40, 20 and 70 C.
    PaperPwl2,
    /// The model the data chose on held-out dwells.
    Chosen(Basis),
    /// Piecewise-linear through every stop.
    PwlAll,
}

impl Compared {
    /// Its blob's file name.
    pub fn file(&self) -> &'static str {
        match self {
            Compared::PaperPwl2 => "paper-pwl2.blob",
            Compared::Chosen(_) => "chosen.blob",
            Compared::PwlAll => "pwl-all.blob",
        }
    }

    /// Its family and parameter count: `pwl2`, `poly3`, `pwl5`.
    pub fn family(&self) -> String {
        match self {
            Compared::PaperPwl2 => "pwl2".to_string(),
            Compared::Chosen(Basis::Poly { order }) => format!("poly{order}"),
            Compared::Chosen(Basis::Pwl { breakpoints }) => format!("pwl{}", breakpoints.len()),
            Compared::PwlAll => "pwl-all".to_string(),
        }
    }

    /// Every blob file a comparison may write, in the order of the table.
    pub fn files() -> [&'static str; 3] {
        [
            Compared::PaperPwl2.file(),
            Compared::Chosen(Basis::Poly { order: 0 }).file(),
            Compared::PwlAll.file(),
        ]
    }
}

/// The name in the summary and the table: `paper-pwl2`, `chosen-` and the family
/// (`chosen-poly3`), `pwl-all`.
impl std::fmt::Display for Compared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = match self {
            Compared::PaperPwl2 => "paper-pwl2".to_string(),
            Compared::Chosen(_) => format!("chosen-{}", self.family()),
            Compared::PwlAll => "pwl-all".to_string(),
        };
        // padding and alignment as for a string
        f.pad(&name)
    }
}

/// Written as its name.
impl Serialize for Compared {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// A fitted model of the comparison with its verifications.
pub struct DemoModel {
    /// Which model it is (its name and its blob's file).
    pub model: Compared,
    /// The fit.
    pub fit: ModelFit,
    /// Its blob's bytes.
    pub blob: Vec<u8>,
    /// Verification with method 1 and method 2.
    pub verifications: [Verification; 2],
    /// The acceptance of its blob (method 1).
    pub acceptance: Acceptance,
}

/// Everything the comparison produced (also what the report plots).
pub struct DemoOutcome {
    /// The recording.
    pub recording: Recording,
    /// Per-stop identification (calibration positions).
    pub stops: Vec<StopCoeffs>,
    /// The models.
    pub models: Vec<DemoModel>,
    /// summary.json rows.
    pub rows: Vec<SummaryRow>,
    /// The simulated truth, when the recording is simulated.
    pub truth: Option<TrueUnit>,
    /// How the data chose their model.
    pub selection: Selection,
    /// The specification the models are judged by.
    pub spec: Spec,
}

/// Fit the paper's model: formula (10) at the stops near -40, +20, +70 C, then the
/// two-interval piecewise-linear model through them (formula (12)).
pub fn paper_pwl2(stops: &[StopCoeffs], t0: f64) -> Result<ModelFit> {
    let rows: Vec<TableRow> = stops
        .iter()
        .filter(|s| {
            [-40.0, 20.0, 70.0]
                .iter()
                .any(|t| (s.temp_c - t).abs() < 3.0)
        })
        .map(|s| TableRow {
            temp_c: s.temp_c,
            coeffs: s.coeffs,
            stderr: None,
        })
        .collect();
    let bps: Vec<f64> = rows.iter().map(|r| r.temp_c).collect();
    fit_table(&rows, &Basis::Pwl { breakpoints: bps }, t0)
}

/// The models compared: the paper's (when its stops exist), the one the data choose,
/// and the pwl through every stop, the last two from the dwells in equilibrium.
struct Fits {
    /// Each model and its fit.
    models: Vec<Fitted>,
    /// How the data chose theirs.
    selection: Selection,
}

/// One model of the comparison, fitted.
struct Fitted {
    /// Which model.
    model: Compared,
    /// The fit.
    fit: ModelFit,
}

fn fits(rec: &Recording, stops: &[StopCoeffs]) -> Result<Fits> {
    let cal = |p: usize| rec.positions.has_role(p, Role::Calibration);
    let (obs, _) = static_observations(rec, &cal);
    let nz = noise(rec);
    let chosen = fit_chosen(rec, &ModelRequest::default())?;
    let selection = chosen
        .selection
        .clone()
        .ok_or_else(|| HostError::new(ErrorKind::Internal, "internal: no selection"))?;
    let pwl_all = fit_joint(
        &obs,
        &Basis::Pwl {
            breakpoints: stop_temperatures(stops),
        },
        &Setting {
            noise: &nz,
            t0_c: rec.t0_c,
            frame: Frame::Given,
            path: &rec.path,
        },
    )?;
    let fitted = |model, fit| Fitted { model, fit };
    let mut models = Vec::new();
    if let Ok(p) = paper_pwl2(stops, rec.t0_c) {
        models.push(fitted(Compared::PaperPwl2, p));
    }
    models.push(fitted(
        Compared::Chosen(chosen.fit.basis.clone()),
        chosen.fit,
    ));
    models.push(fitted(Compared::PwlAll, pwl_all));
    Ok(Fits { models, selection })
}

/// Compare the models on `rec` (see the module doc).
pub fn analyse(rec: Recording, truth: Option<TrueUnit>) -> Result<DemoOutcome> {
    let stops = identify_stops(&rec)?;
    let serial = rec.serial().to_string();
    let check = |p: usize| rec.positions.has_role(p, Role::Verification);
    let mut models: Vec<DemoModel> = Vec::new();
    let mut rows = Vec::new();
    let spec = Spec::default();
    let Fits {
        models: list,
        selection,
    } = fits(&rec, &stops)?;
    for Fitted { model: which, fit } in list {
        let mut cal = fit.calibration(0.0, false);
        let model = crate::fit::cache::Model {
            rec: &rec,
            positions: &rec.positions,
            fit: &fit,
            noise: &noise(&rec),
        };
        crate::model::cache::Cache::for_model(&model, &mut cal, None);
        let (blob, bytes, _) = build_blob(&serial, &rec.output_unit, &cal)?;
        let run = |m: Method| -> Result<Verification> {
            verify(&rec, &blob, m, &check)
                .ok_or_else(|| HostError::new(ErrorKind::Numerical, "singular K(T0)"))
        };
        let v = [
            run(Method::CorrectConstants)?,
            run(Method::CorrectResult(ErrorModel::Full))?,
        ];
        if models.is_empty() {
            rows.extend(summary_rows(T0_CONSTANTS, Compensation::None, &v[0]));
        }
        let name = which.to_string();
        rows.extend(summary_rows(&name, Compensation::Method1, &v[0]));
        rows.extend(summary_rows(&name, Compensation::Method2, &v[1]));
        let acceptance = judge(&v[0], &spec, cal.t0_c, (cal.t_min_c, cal.t_max_c));
        models.push(DemoModel {
            model: which,
            fit,
            blob: bytes,
            verifications: v,
            acceptance,
        });
    }
    Ok(DemoOutcome {
        recording: rec,
        stops,
        models,
        rows,
        truth,
        selection,
        spec,
    })
}

/// The data's choice and every model's acceptance verdict (method 1), as text lines.
pub fn verdicts(oc: &DemoOutcome) -> String {
    let mut s = format!(
        "data-chosen model: {} by {}\n  {}\nacceptance, method 1 ({}):\n",
        oc.selection.chosen,
        oc.selection.method,
        oc.selection.reason,
        oc.spec.text()
    );
    for m in &oc.models {
        let a = &m.acceptance;
        let line = format!("{}: {}", a.acceptance.name(), a.reason);
        s.push_str(&format!("  {:<14} {line}\n", m.model));
    }
    s
}

/// The summary's name of the uncompensated row.
pub const T0_CONSTANTS: &str = "t0-constants";

fn summary_rows(model: &str, method: Compensation, v: &Verification) -> Vec<SummaryRow> {
    v.max_by_temperature
        .iter()
        .map(|t| SummaryRow {
            model: model.to_string(),
            method,
            temp_c: (t.temp_c * 100.0).round() / 100.0,
            max_abs_dg_mg: match method {
                Compensation::None => t.max_abs_dg_mg_uncompensated,
                Compensation::Method1 | Compensation::Method2 => t.max_abs_dg_mg,
            },
        })
        .collect()
}

/// The verification positions that have dwells in `rec`, in the positions' order (the
/// built-ins, then a positions file's).
pub fn verification_names(rec: &Recording) -> Vec<String> {
    let used: std::collections::BTreeSet<usize> = rec.dwells.iter().map(|d| d.position).collect();
    used.iter()
        .filter(|p| rec.positions.has_role(**p, Role::Verification))
        .map(|p| rec.positions.name(*p).to_string())
        .collect()
}

/// Position names for a heading: runs of consecutive numbers with one prefix shortened
/// (`PP1..PP6`, `V1..V4`), the rest listed; a long list ends with its count.
pub fn names_text(names: &[String]) -> String {
    let split = |n: &str| {
        let digits = n.len() - n.trim_end_matches(|c: char| c.is_ascii_digit()).len();
        let (p, d) = n.split_at(n.len() - digits);
        (p.to_string(), d.parse::<u64>().ok(), d.len())
    };
    let mut runs: Vec<Vec<&String>> = Vec::new();
    for n in names {
        let (p, k, w) = split(n);
        let extends = runs.last().and_then(|r| r.last()).is_some_and(|last| {
            let (lp, lk, lw) = split(last);
            lp == p && lw == w && matches!((lk, k), (Some(a), Some(b)) if b == a + 1)
        });
        match runs.last_mut() {
            Some(r) if extends => r.push(n),
            _ => runs.push(vec![n]),
        }
    }
    let parts: Vec<String> = runs
        .iter()
        .flat_map(|r| match r.as_slice() {
            [a, .., b] if r.len() >= 3 => vec![format!("{a}..{b}")],
            _ => r.iter().map(|n| n.to_string()).collect(),
        })
        .collect();
    match parts.len() {
        0 => "(none)".to_string(),
        n if n > 8 => format!(
            "{}, ... {} ({} positions)",
            parts[..3].join(", "),
            parts[n - 1],
            names.len()
        ),
        _ => parts.join(", "),
    }
}

/// The summary table as text: max |dg| (mg) per temperature, and in brackets the
/// reduction against the uncompensated case; `positions` are the verification
/// positions it is over (named in its heading). Fixed width: every column as wide as
/// its widest entry, the values right-aligned, columns three spaces apart.
pub fn table(rows: &[SummaryRow], positions: &[String]) -> String {
    let mut temps: Vec<f64> = rows.iter().map(|r| r.temp_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let mut keys: Vec<(String, Compensation)> = Vec::new();
    for r in rows {
        let k = (r.model.clone(), r.method);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let get = |m: &str, me: Compensation, t: f64| {
        rows.iter()
            .find(|r| r.model == m && r.method == me && r.temp_c == t)
            .map(|r| r.max_abs_dg_mg)
    };
    // per row and temperature: the value and the bracket
    let cells: Vec<Vec<(String, String)>> = keys
        .iter()
        .map(|(m, me)| {
            temps
                .iter()
                .map(|t| {
                    let v = get(m, *me, *t).unwrap_or(f64::NAN);
                    let compensated = *me != Compensation::None;
                    let ratio = match get(T0_CONSTANTS, Compensation::None, *t) {
                        Some(u) if compensated && v > 0.0 && u >= v => {
                            format!("({:.1}x)", u / v)
                        }
                        Some(u) if compensated && u > 0.0 => format!("({:.1}x worse)", v / u),
                        _ => String::new(),
                    };
                    (format!("{v:.3}"), ratio)
                })
                .collect()
        })
        .collect();
    let heads: Vec<String> = temps.iter().map(|t| format!("{t:.1} C")).collect();
    let width = |it: &mut dyn Iterator<Item = usize>| it.max().unwrap_or(0);
    let wm = width(&mut keys.iter().map(|k| k.0.len()).chain([5]));
    let wme = width(&mut keys.iter().map(|k| k.1.name().len()).chain([6]));
    let wv: Vec<usize> = (0..temps.len())
        .map(|j| width(&mut cells.iter().map(|r| r[j].0.len()).chain([heads[j].len()])))
        .collect();
    let wr: Vec<usize> = (0..temps.len())
        .map(|j| width(&mut cells.iter().map(|r| r[j].1.len())))
        .collect();
    let line = |first: &str, second: &str, cols: &mut dyn Iterator<Item = (usize, String)>| {
        let mut l = format!("{first:<wm$}   {second:<wme$}");
        for (j, c) in cols {
            let (v, r) = c.split_once('\t').unwrap_or((c.as_str(), ""));
            l.push_str(&format!("   {v:>w$}", w = wv[j]));
            if wr[j] > 0 {
                l.push_str(&format!(" {r:<w$}", w = wr[j]));
            }
        }
        format!("{}\n", l.trim_end())
    };
    let mut s = format!(
        "max |dg| in the verification positions {}, mg (in brackets: how many times smaller than with the T0 constants)\n",
        names_text(positions)
    );
    s.push_str(&line(
        "model",
        "method",
        &mut heads.iter().cloned().enumerate(),
    ));
    for ((m, me), row) in keys.iter().zip(&cells) {
        s.push_str(&line(
            m,
            me.name(),
            &mut row.iter().map(|(v, r)| format!("{v}\t{r}")).enumerate(),
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(model: &str, method: Compensation, temp_c: f64, v: f64) -> SummaryRow {
        SummaryRow {
            model: model.into(),
            method,
            temp_c,
            max_abs_dg_mg: v,
        }
    }

    #[test]
    fn the_table_keeps_its_columns_apart_whatever_the_values() {
        let rows = [
            row(T0_CONSTANTS, Compensation::None, -20.0, 3.11),
            row(T0_CONSTANTS, Compensation::None, 25.0, 0.17),
            row("chosen-poly2", Compensation::Method1, -20.0, 0.278),
            row("chosen-poly2", Compensation::Method1, 25.0, 0.19),
            row(
                "a-much-longer-model-name",
                Compensation::Method2,
                -20.0,
                12345.6,
            ),
            row(
                "a-much-longer-model-name",
                Compensation::Method2,
                25.0,
                0.001,
            ),
        ];
        let names = ["F1", "V1", "V2", "V3", "X"].map(String::from);
        let t = table(&rows, &names);
        let lines: Vec<&str> = t.lines().collect();
        assert!(lines[0].contains("positions F1, V1..V3, X, mg"), "{t}");
        // the values end in the same column as their heading, every bracket starts in
        // one column, and at least three spaces lie between two columns
        let end = |l: &str, pat: &str| l.find(pat).map(|i| i + pat.len()).unwrap();
        let head_end = end(lines[1], "25.0 C");
        assert_eq!(end(lines[3], "0.190"), head_end, "{t}");
        assert_eq!(end(lines[4], "0.001"), head_end, "{t}");
        assert_eq!(
            lines[3].find("(1.1x worse)"),
            lines[4].find("(170.0x)"),
            "{t}"
        );
        assert!(lines[3].contains("(11.2x)   "), "{t}");
        assert!(lines[4].contains("(3969.6x worse)   "), "{t}");
    }

    #[test]
    fn names_are_shortened_to_runs() {
        let n = |v: &[&str]| names_text(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>());
        assert_eq!(n(&["PP1", "PP2", "PP3", "PP4", "PP5", "PP6"]), "PP1..PP6");
        assert_eq!(n(&["V1", "V2", "W7", "V3"]), "V1, V2, W7, V3");
        assert_eq!(n(&["V01", "V02", "V03", "V10"]), "V01..V03, V10");
        let many: Vec<String> = (1..=20).map(|k| format!("W{:04}", 10 * k)).collect();
        assert_eq!(
            names_text(&many),
            "W0010, W0020, W0030, ... W0200 (20 positions)"
        );
    }
}
