//! The `at-diagnosis/1` JSON contract as typed structs (the text output is rendered from
//! the same structs). Fields beyond the first version: `floor`, `dispersion`, `quality`,
//! `unexplained`, the verdict `unexplained`, and per finding `form`, `share`,
//! `heldout_gain`.
use crate::data::output_unit::OutputUnit;
use crate::diagnose::findings::{Ambiguity, Finding};
use crate::diagnose::location::Hotspot;
use crate::diagnose::quality::QualityNote;
use crate::diagnose::search::Research;
use crate::diagnose::Diagnosis;
use crate::model::metrics::{dispersion, max_dg, normalized_rms, residual_rms};
use firmware_core::model::AXES;
use serde::Serialize;

/// What the diagnosis concludes.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    serde::Deserialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Verdict {
    /// At the floor, nothing found: the model fits to the noise.
    None,
    /// Findings bring the residual to the floor.
    Explained,
    /// Findings, but the residual stays above the floor.
    PartlyExplained,
    /// Above the floor, and nothing in the catalogue explains it.
    Unexplained,
}

impl Verdict {
    /// The verdict of a diagnosis with (or without) findings, at (or above) the floor.
    pub fn of(found: bool, at_floor: bool) -> Verdict {
        match (found, at_floor) {
            (false, true) => Verdict::None,
            (false, false) => Verdict::Unexplained,
            (true, true) => Verdict::Explained,
            (true, false) => Verdict::PartlyExplained,
        }
    }

    /// The contract's name.
    pub fn as_str(self) -> &'static str {
        self.into()
    }

    /// What it means, in words.
    pub fn meaning(self) -> &'static str {
        match self {
            Verdict::None => "nothing beyond the floor: the model fits to the noise",
            Verdict::Explained => "the findings bring the residual to the floor",
            Verdict::PartlyExplained => "the findings explain part; what is left is located above",
            Verdict::Unexplained => {
                "above the floor, and nothing in the catalogue explains it; located above"
            }
        }
    }
}

/// The whole contract.
#[derive(Debug, Clone, Serialize)]
pub struct Contract {
    /// Always `at-diagnosis/1`.
    pub format: &'static str,
    /// Residual RMS expected from the floor alone, per window (output units).
    pub noise_rms: f64,
    /// Per-sample noise per axis (output units; the baseline's scatter when the floor is
    /// not measurable).
    pub noise_sigma_per_sample: [f64; 3],
    /// The recording's output unit.
    pub output_unit: OutputUnit,
    /// The error floor.
    pub floor: FloorFigures,
    /// Residual chi-square per degree of freedom in floor units (at least 1).
    pub dispersion: Dispersion,
    /// The baseline model.
    pub baseline: ModelFigures,
    /// Where the baseline residual exceeds the floor (at most 12 groups, worst first).
    pub located: Vec<Hotspot>,
    /// Findings of the final joint model.
    pub findings: Vec<Finding>,
    /// Candidates the data cannot tell apart.
    pub ambiguous: Vec<Ambiguity>,
    /// Effects found together whose split the design pins only through its ramps (a
    /// hysteresis beside a rate or a lag, no temperature seen at rest from both
    /// directions): the correlation of their estimates and what separates them.
    pub coupled: Vec<crate::diagnose::coupled::Coupling>,
    /// What this recording cannot identify.
    pub not_identifiable: Vec<String>,
    /// Notes on the data (spikes, gaps, coloured noise, sensor against chamber, ...).
    pub quality: Vec<QualityNote>,
    /// What the final model leaves above the floor, located; none at the floor.
    pub unexplained: Option<Unexplained>,
    /// After the effects accepted, each look again where the rest was located: the
    /// region, the effects tried there, the one found (null: nothing passed the rules).
    pub research: Vec<Research>,
    /// The library search for discovered terms after the catalogue's, round by round:
    /// the columns tried, the terms proposed (with the share of resamples choosing them),
    /// the one found (empty: the rest was at the floor).
    pub library: Vec<crate::diagnose::search::LibraryRound>,
    /// Why the search ended: the catalogue's (`candidates_used_up`,
    /// `research_rounds_spent`, `at_floor`, `not_located`, `nothing_passed`) and then the
    /// library's phase (`at_floor`, `library_rounds_spent`, `library_nothing_passed`).
    pub search_ended: crate::diagnose::search::Ended,
    /// The final model.
    #[serde(rename = "final")]
    pub final_model: FinalFigures,
    /// The model `--out` writes into the blob: the final one in the firmware's forms.
    pub flashed: FlashedFigures,
    /// `none` (at the floor, nothing found), `explained` (findings bring it to the
    /// floor), `partly_explained` (findings, but above the floor), `unexplained` (above
    /// the floor, nothing in the catalogue explains it).
    pub verdict: Verdict,
    /// The blob written with `--out`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blob: Option<BlobNote>,
}

/// The floor per axis.
#[derive(Debug, Clone, Serialize)]
pub struct FloorFigures {
    /// Measured inside the dwells (false: the baseline's scatter stands in).
    pub measured: bool,
    /// Per axis x, y, z.
    pub axes: Vec<AxisFloorFigures>,
}

/// The floor of one axis.
#[derive(Debug, Clone, Serialize)]
pub struct AxisFloorFigures {
    /// Axis.
    pub axis: &'static str,
    /// Scatter of one sample (output units).
    pub sample_sigma: f64,
    /// Scatter of the mean of a typical window (output units).
    pub window_sigma: f64,
    /// Samples in a typical (median) window.
    pub window_samples: f64,
    /// How much more that mean scatters than white noise predicts (1 = white).
    pub colour: f64,
    /// The step of the outputs when their noise is below it (the floor is then the
    /// step's, `step / sqrt(12)`); null otherwise.
    pub quantum: Option<f64>,
}

/// Dispersions.
#[derive(Debug, Clone, Serialize)]
pub struct Dispersion {
    /// Of the baseline.
    pub baseline: f64,
    /// Of the final model.
    pub final_model: f64,
}

/// Figures of the baseline model.
#[derive(Debug, Clone, Serialize)]
pub struct ModelFigures {
    /// e.g. `poly5, cross-sensitivities fixed at 0`, or `poly4, offsets poly5` (the
    /// offsets one order above the K rows, which ramps logged at rest allow).
    pub temperature_model: String,
    /// Residual RMS (output units).
    pub residual_rms: f64,
    /// Residual RMS in floor units.
    pub residual_rms_over_noise: f64,
    /// Worst |dg| in the static windows, mg.
    pub max_abs_dg_mg: f64,
}

/// What stays above the floor.
#[derive(Debug, Clone, Serialize)]
pub struct Unexplained {
    /// Final residual RMS in floor units.
    pub residual_rms_over_noise: f64,
    /// Where it sits (at most 12 groups, worst first).
    pub located: Vec<Hotspot>,
}

/// Figures of the final model.
#[derive(Debug, Clone, Serialize)]
pub struct FinalFigures {
    /// Its temperature model (as the baseline's: `poly4, offsets poly5` when the
    /// offsets carry an order above the K rows').
    pub temperature_model: String,
    /// The effects in it, with their forms.
    pub model: Vec<String>,
    /// Residual RMS (output units).
    pub residual_rms: f64,
    /// Residual RMS in floor units.
    pub residual_rms_over_noise: f64,
    /// Worst |dg| in the static windows, mg.
    pub max_abs_dg_mg: f64,
    /// Held-out chi-square of the baseline: every time chunk predicted from the others
    /// (over the chunks both models predict, not extrapolate).
    pub heldout_chi2_before: f64,
    /// Held-out chi-square of the final model.
    pub heldout_chi2_after: f64,
}

/// The model the blob carries.
#[derive(Debug, Clone, Serialize)]
pub struct FlashedFigures {
    /// Whether it is the final model itself (else refitted in the firmware's forms).
    pub same_as_final: bool,
    /// Its effects, with their forms.
    pub model: Vec<String>,
    /// Residual RMS in floor units.
    pub residual_rms_over_noise: f64,
    /// Worst |dg| in the static windows, mg.
    pub max_abs_dg_mg: f64,
}

/// The blob written with `diagnose --out`.
#[derive(Debug, Clone, Serialize)]
pub struct BlobNote {
    /// Where.
    pub path: String,
    /// Size, bytes.
    pub bytes: usize,
    /// Whether it carries in-flight physics terms.
    pub physics: bool,
    /// The discovered terms of the unit's state in its term table (format 5 when any).
    pub discovered_terms: usize,
    /// Largest f32-vs-f64 departure, g.
    pub f32_departure_g: f64,
}

impl Diagnosis<'_> {
    fn floor_figures(&self) -> FloorFigures {
        let mut ns: Vec<f64> = self.data.obs.iter().map(|o| o.n as f64).collect();
        ns.sort_by(f64::total_cmp);
        let n = ns.get(ns.len() / 2).copied().unwrap_or(1.0);
        FloorFigures {
            measured: self.floor_measured,
            axes: (0..3)
                .map(|i| {
                    let f = &self.floor.axes[i];
                    AxisFloorFigures {
                        axis: AXES[i],
                        sample_sigma: f.sample_sigma().unwrap_or(f64::NAN),
                        window_sigma: f.var_of_mean(n).map(f64::sqrt).unwrap_or(f64::NAN),
                        window_samples: n,
                        colour: f.colour(n).unwrap_or(f64::NAN),
                        quantum: f.quantum,
                    }
                })
                .collect(),
        }
    }

    /// The verdict (see [`Contract::verdict`]).
    pub fn verdict(&self) -> Verdict {
        let found = !(self.findings.is_empty() && self.ambiguous.is_empty());
        let at_floor = normalized_rms(&self.data, &self.final_fit) <= self.data.rules.at_floor_rms;
        Verdict::of(found, at_floor)
    }

    /// The contract of this diagnosis.
    pub fn contract(&self) -> Contract {
        let data = &self.data;
        let rec = data.rec;
        let (b, f) = (&self.baseline, &self.final_fit);
        let final_rms = normalized_rms(data, f);
        let (held_before, held_after) = data.heldout_pair(b, f);
        let sigma: [f64; 3] = std::array::from_fn(|i| match self.floor.axes[i].sample_sigma() {
            Some(s) if self.floor_measured => s,
            _ => (1.0 / data.w[i]).sqrt(),
        });
        Contract {
            format: "at-diagnosis/1",
            noise_rms: self.noise_rms,
            noise_sigma_per_sample: sigma,
            output_unit: rec.output_unit.clone(),
            floor: self.floor_figures(),
            dispersion: Dispersion {
                baseline: dispersion(data, b),
                final_model: dispersion(data, f),
            },
            baseline: ModelFigures {
                temperature_model: format!(
                    "{}{}",
                    b.spec.temperature_model(),
                    if b.spec.cross {
                        ""
                    } else {
                        ", cross-sensitivities fixed at 0"
                    }
                ),
                residual_rms: residual_rms(b),
                residual_rms_over_noise: normalized_rms(data, b),
                max_abs_dg_mg: max_dg(data, b),
            },
            located: self.hotspots.iter().take(12).cloned().collect(),
            findings: self.findings.clone(),
            ambiguous: self.ambiguous.clone(),
            coupled: self.coupled.clone(),
            not_identifiable: self.not_identifiable.clone(),
            quality: self.quality.clone(),
            unexplained: (!self.unexplained.is_empty()).then(|| Unexplained {
                residual_rms_over_noise: final_rms,
                located: self.unexplained.iter().take(12).cloned().collect(),
            }),
            research: self.research.clone(),
            library: self.library.clone(),
            search_ended: self.search_ended,
            final_model: FinalFigures {
                temperature_model: f.spec.temperature_model(),
                model: f
                    .spec
                    .extras
                    .iter()
                    .map(|e| format!("{}: {}", e.id(), e.form()))
                    .collect(),
                residual_rms: residual_rms(f),
                residual_rms_over_noise: final_rms,
                max_abs_dg_mg: max_dg(data, f),
                heldout_chi2_before: held_before,
                heldout_chi2_after: held_after,
            },
            flashed: FlashedFigures {
                same_as_final: self.flashed.fit.spec == f.spec,
                model: self
                    .flashed
                    .fit
                    .spec
                    .extras
                    .iter()
                    .map(|e| format!("{}: {}", e.id(), e.form()))
                    .collect(),
                residual_rms_over_noise: normalized_rms(data, &self.flashed.fit),
                max_abs_dg_mg: max_dg(data, &self.flashed.fit),
            },
            verdict: self.verdict(),
            blob: None,
        }
    }
}

impl Contract {
    /// As text for a terminal.
    pub fn text(&self) -> String {
        let b = &self.baseline;
        let mut s = format!(
            "floor (window means, {}): {:.3e} {}\nbaseline {}: residual {:.3e} {} ({:.1}x the floor), max |dg| {:.3} mg\n",
            if self.floor.measured { "measured in the dwells" } else { "the scatter the most general static model leaves: not measurable" },
            self.noise_rms,
            self.output_unit,
            b.temperature_model,
            b.residual_rms,
            self.output_unit,
            b.residual_rms_over_noise,
            b.max_abs_dg_mg
        );
        for q in &self.quality {
            s.push_str(&format!("data: {}: {}\n", q.kind, q.text));
        }
        if !self.located.is_empty() {
            s.push_str("where the baseline residual exceeds the floor (RMS in floor units):\n");
        }
        for x in self.located.iter().take(8) {
            s.push_str(&hotspot_line(x, self.output_unit.as_str()));
        }
        s.extend(
            self.not_identifiable
                .iter()
                .map(|n| format!("not identifiable: {n}\n")),
        );
        for x in &self.findings {
            s.push_str(&finding_lines(x));
        }
        for x in &self.ambiguous {
            let what = if x.terms.is_empty() {
                serde_json::to_string(&x.candidates).unwrap_or_default()
            } else {
                format!("the discovered terms {}", x.terms.join(", "))
            };
            s.push_str(&format!(
                "ambiguous: {what} cannot be told apart; needed: {}\n",
                x.needed
            ));
        }
        for x in &self.coupled {
            let r: Vec<String> = x
                .correlation
                .iter()
                .zip(["x", "y", "z"])
                .filter_map(|(r, a)| r.map(|r| format!("{r:.2} on {a}")))
                .collect();
            let r = if r.is_empty() {
                String::new()
            } else {
                format!(" (correlation of their estimates {})", r.join(", "))
            };
            s.push_str(&format!(
                "coupled: {} and {}{r}: {}; needed: {}\n",
                x.effects[0], x.effects[1], x.why, x.needed
            ));
        }
        if let Some(u) = &self.unexplained {
            s.push_str(&format!(
                "unexplained: the final residual is {:.1}x the floor; nothing in the catalogue explains it here:\n",
                u.residual_rms_over_noise
            ));
            for x in u.located.iter().take(6) {
                s.push_str(&hotspot_line(x, self.output_unit.as_str()));
            }
        }
        for r in &self.research {
            let found = match r.found {
                Some(id) => format!("found {id}"),
                None => "nothing passed the rules".to_string(),
            };
            let tried: Vec<&str> = r.tried.iter().map(|e| e.as_str()).collect();
            s.push_str(&format!(
                "re-search where the rest is located (tried: {}): {found}\n",
                if tried.is_empty() {
                    "none".to_string()
                } else {
                    tried.join(", ")
                }
            ));
            for x in r.region.iter().take(4) {
                s.push_str(&hotspot_line(x, self.output_unit.as_str()));
            }
        }
        for r in &self.library {
            s.push_str(&library_line(r));
        }
        let fl = &self.flashed;
        if !fl.same_as_final {
            s.push_str(&format!(
                "flashed (the firmware's forms, refitted): {}; residual {:.1}x the floor, max |dg| {:.3} mg\n",
                fl.model.join("; "),
                fl.residual_rms_over_noise,
                fl.max_abs_dg_mg
            ));
        }
        let f = &self.final_model;
        s.push_str(&format!(
            "final: residual {:.3e} {} ({:.1}x the floor), max |dg| {:.3} mg; held-out chi2 (floor units) {:.0} -> {:.0}\nverdict: {} ({})",
            f.residual_rms,
            self.output_unit,
            f.residual_rms_over_noise,
            f.max_abs_dg_mg,
            f.heldout_chi2_before,
            f.heldout_chi2_after,
            self.verdict,
            self.verdict.meaning()
        ));
        s
    }
}

fn hotspot_line(x: &Hotspot, unit: &str) -> String {
    format!(
        "  {:<12} {:<24} axis {}  {:.1}x  ({:.0}% of the sum of squares, mean {:.3e} {unit}, {} windows)\n",
        x.group,
        x.value,
        x.axis,
        x.rms_sigma,
        100.0 * x.share,
        x.mean,
        x.count
    )
}

/// One round of the library search as a line of the text output.
fn library_line(r: &crate::diagnose::search::LibraryRound) -> String {
    let proposed: Vec<String> = r
        .proposed
        .iter()
        .map(|p| {
            format!(
                "{} on {} ({:.0}% of resamples)",
                p.term,
                p.axis,
                100.0 * p.inclusion
            )
        })
        .collect();
    format!(
        "library of discovered terms ({} columns; proposed: {}): {}\n",
        r.tried,
        if proposed.is_empty() {
            "none".to_string()
        } else {
            proposed.join(", ")
        },
        r.found.as_deref().unwrap_or("nothing passed the rules")
    )
}

/// A finding as lines of the text output: what, where and how well, its parameters
/// (the ones fixed by the search said so), the evidence, the terms it cannot be told
/// from.
fn finding_lines(x: &Finding) -> String {
    let mut s = String::new();
    let name = match &x.term {
        Some(t) => format!("{} {t}", x.effect),
        None => x.effect.to_string(),
    };
    s.push_str(&format!(
        "finding: {name} on axes {} ({}; dBIC {:.0}, {:.0}% of the excess, held-out gain {:.1} per parameter; {})\n",
        serde_json::to_string(&x.axes).unwrap_or_default(),
        x.form,
        x.delta_bic,
        100.0 * x.share,
        x.heldout_gain,
        if x.reproduced { "reproduced on both halves" } else { "NOT reproduced on both halves" }
    ));
    for (k, p) in x.parameters.by_name() {
        let unit = x.parameters.unit_text(p);
        // a parameter the search fixes (a threshold, an estimator's constant) has
        // no uncertainty: said, not printed as NaN
        let line = if p.sigma.is_finite() {
            format!("    {k} = {:.4e} +- {:.1e} {unit}", p.value, p.sigma)
        } else {
            format!("    {k} = {:.4e} {unit} (fixed, not fitted)", p.value)
        };
        s.push_str(line.trim_end());
        s.push('\n');
    }
    s.push_str(&format!("    {}\n", x.evidence));
    if !x.equivalent.is_empty() {
        s.push_str(&format!(
            "    named as the simplest; this design cannot tell it from {}\n",
            x.equivalent.join(", ")
        ));
    }
    s
}
