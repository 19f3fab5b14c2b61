//! The outcome of a blind case and the rule it passes by, per class.
use crate::blind::cases::{Case, Class};
use crate::blind::config::configure;
use crate::blind::forms;

/// The outcome of a case.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The case.
    pub case: Case,
    /// Effects found.
    pub found: Vec<String>,
    /// Ambiguous groups.
    pub ambiguous: Vec<Vec<String>>,
    /// Found exactly the concealed set (ambiguity counts when expected).
    pub exact: bool,
    /// Parameters within 3 sigma (None when not checked).
    pub params_ok: Option<bool>,
    /// Final residual over the floor.
    pub final_over_noise: f64,
    /// The verdict.
    pub verdict: String,
    /// The axis where the final residual is largest, when unexplained.
    pub unexplained_axis: Option<String>,
    /// Data-quality note kinds.
    pub quality: Vec<String>,
    /// Notes for the report.
    pub note: String,
}

impl Outcome {
    /// Every effect named, found or ambiguous.
    pub fn named(&self) -> Vec<String> {
        let mut named: Vec<String> = self.found.clone();
        named.extend(self.ambiguous.iter().flatten().cloned());
        named
    }

    /// The case passed, by its class's rule (see the module doc).
    pub fn passed(&self) -> bool {
        match self.case.class {
            Class::Catalogue | Class::OtherForm => self.exact,
            Class::Outside => self.named().is_empty() && self.located(),
            Class::Nuisance => self.named().is_empty() && self.noted(),
        }
    }

    /// Outside the catalogue: the unexplained residual sits on an axis the effect is on
    /// (or nothing was seen at all).
    pub fn located(&self) -> bool {
        let axes = forms::axes(&configure(&self.case));
        match &self.unexplained_axis {
            Some(a) => axes.iter().any(|i| ["x", "y", "z"][*i] == a),
            None => self.verdict == "none",
        }
    }

    /// A nuisance: the data-quality note it should raise is there.
    pub fn noted(&self) -> bool {
        forms::note(&self.case).is_none_or(|k| self.quality.iter().any(|q| q == k))
    }
}
