//! The `at-diagnosis/1` JSON contract as typed structs (the text output is rendered from
//! the same structs).
use crate::data::recording::Recording;
use crate::diagnose::design::Data;
use crate::diagnose::findings::{Ambiguity, Finding};
use crate::diagnose::location::Hotspot;
use crate::diagnose::metrics::{max_dg, normalized_rms, residual_rms};
use crate::diagnose::Diagnosis;
use serde::Serialize;

/// The whole contract.
#[derive(Debug, Clone, Serialize)]
pub struct Contract {
    /// Always `at-diagnosis/1`.
    pub format: &'static str,
    /// Residual RMS expected from noise alone, per window (output units).
    pub noise_rms: f64,
    /// Per-sample noise per axis (output units).
    pub noise_sigma_per_sample: [f64; 3],
    /// The recording's output unit.
    pub output_unit: String,
    /// The baseline model.
    pub baseline: ModelFigures,
    /// Where the baseline residual exceeds the noise (at most 12 groups, worst first).
    pub located: Vec<Hotspot>,
    /// Accepted findings, in the order they were accepted.
    pub findings: Vec<Finding>,
    /// Candidates the data cannot tell apart.
    pub ambiguous: Vec<Ambiguity>,
    /// What this recording cannot identify.
    pub not_identifiable: Vec<String>,
    /// The final model.
    #[serde(rename = "final")]
    pub final_model: FinalFigures,
    /// `none`, `explained` or `partly_explained`.
    pub verdict: &'static str,
    /// The blob written with `--out`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blob: Option<BlobNote>,
}

/// Figures of the baseline model.
#[derive(Debug, Clone, Serialize)]
pub struct ModelFigures {
    /// e.g. `poly5, cross-sensitivities fixed at 0`.
    pub temperature_model: String,
    /// Residual RMS (output units).
    pub residual_rms: f64,
    /// Residual RMS in noise units.
    pub residual_rms_over_noise: f64,
    /// Worst |dg| in the static windows, mg.
    pub max_abs_dg_mg: f64,
}

/// Figures of the final model.
#[derive(Debug, Clone, Serialize)]
pub struct FinalFigures {
    /// Residual RMS (output units).
    pub residual_rms: f64,
    /// Residual RMS in noise units.
    pub residual_rms_over_noise: f64,
    /// Worst |dg| in the static windows, mg.
    pub max_abs_dg_mg: f64,
    /// Held-out chi-square of the baseline.
    pub heldout_chi2_before: f64,
    /// Held-out chi-square of the final model.
    pub heldout_chi2_after: f64,
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
    /// Largest f32-vs-f64 departure, g.
    pub f32_departure_g: f64,
}

impl Diagnosis {
    /// The contract of this diagnosis of `rec`.
    pub fn contract(&self, rec: &Recording) -> Contract {
        let verdict = if self.findings.is_empty() && self.ambiguous.is_empty() {
            "none"
        } else if residual_rms(&self.final_fit) <= 1.5 * self.noise_rms {
            "explained"
        } else {
            "partly_explained"
        };
        let data = Data {
            rec,
            obs: self.obs.clone(),
            noise: self.noise,
            t0: rec.t0_c,
        };
        let b = &self.baseline;
        Contract {
            format: "at-diagnosis/1",
            noise_rms: self.noise_rms,
            noise_sigma_per_sample: self.noise.sigma,
            output_unit: rec.output_unit.clone(),
            baseline: ModelFigures {
                temperature_model: format!(
                    "{}{}",
                    b.spec.basis.describe(),
                    if b.spec.cross {
                        ""
                    } else {
                        ", cross-sensitivities fixed at 0"
                    }
                ),
                residual_rms: residual_rms(b),
                residual_rms_over_noise: normalized_rms(&data, b),
                max_abs_dg_mg: max_dg(&data, b),
            },
            located: self.hotspots.iter().take(12).cloned().collect(),
            findings: self.findings.clone(),
            ambiguous: self.ambiguous.clone(),
            not_identifiable: self.not_identifiable.clone(),
            final_model: FinalFigures {
                residual_rms: residual_rms(&self.final_fit),
                residual_rms_over_noise: normalized_rms(&data, &self.final_fit),
                max_abs_dg_mg: max_dg(&data, &self.final_fit),
                heldout_chi2_before: b.heldout,
                heldout_chi2_after: self.final_fit.heldout,
            },
            verdict,
            blob: None,
        }
    }
}

impl Contract {
    /// As text for a terminal.
    pub fn text(&self) -> String {
        let b = &self.baseline;
        let mut s = format!(
            "noise (in-dwell, per window): {:.3e}\nbaseline {}: residual {:.3e} ({:.1}x noise), max |dg| {:.3} mg\n",
            self.noise_rms, b.temperature_model, b.residual_rms, b.residual_rms_over_noise, b.max_abs_dg_mg
        );
        if !self.located.is_empty() {
            s.push_str("where the baseline residual exceeds noise (RMS in noise units):\n");
        }
        for x in self.located.iter().take(8) {
            s.push_str(&format!(
                "  {:<12} {:<22} axis {}  {:.1}x  (mean {:.3e}, {} windows)\n",
                x.group, x.value, x.axis, x.rms_sigma, x.mean, x.count
            ));
        }
        for n in &self.not_identifiable {
            s.push_str(&format!("not identifiable: {n}\n"));
        }
        for x in &self.findings {
            s.push_str(&format!(
                "finding: {} on axes {} (dBIC {:.0})\n",
                x.effect,
                serde_json::to_string(&x.axes).unwrap_or_default(),
                x.delta_bic
            ));
            for (k, v) in &x.parameters {
                let u = x.uncertainties.get(k).copied().unwrap_or(f64::NAN);
                s.push_str(&format!("    {k} = {v:.4e} +- {u:.1e}\n"));
            }
            s.push_str(&format!("    {}\n", x.evidence));
        }
        for x in &self.ambiguous {
            s.push_str(&format!(
                "ambiguous: {} cannot be told apart; needed: {}\n",
                serde_json::to_string(&x.candidates).unwrap_or_default(),
                x.needed
            ));
        }
        let f = &self.final_model;
        s.push_str(&format!(
            "final: residual {:.3e} ({:.1}x noise), max |dg| {:.3} mg; held-out chi2 {:.0} -> {:.0}\nverdict: {}",
            f.residual_rms, f.residual_rms_over_noise, f.max_abs_dg_mg, f.heldout_chi2_before, f.heldout_chi2_after, self.verdict
        ));
        s
    }
}
