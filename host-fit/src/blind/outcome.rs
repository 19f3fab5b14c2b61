//! The outcome of a blind case and the rule it passes by, per class.
use crate::blind::cases::Case;
use crate::blind::config::configure;
use crate::blind::forms;
use crate::blind::forms::Class;
use crate::diagnose::contract::Verdict;
use crate::diagnose::quality::NoteKind;
use crate::diagnose::EffectId;

/// The outcome of a case.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The case.
    pub case: Case,
    /// Effects found.
    pub found: Vec<EffectId>,
    /// Ambiguous groups.
    pub ambiguous: Vec<Vec<EffectId>>,
    /// Found exactly the concealed set (ambiguity counts when expected).
    pub exact: bool,
    /// Parameters within 3 sigma (None when not checked).
    pub params_ok: Option<bool>,
    /// Final residual over the floor.
    pub final_over_noise: f64,
    /// The verdict (None when the case could not be diagnosed).
    pub verdict: Option<Verdict>,
    /// The axis where the final residual is largest, when unexplained.
    pub unexplained_axis: Option<String>,
    /// Data-quality note kinds.
    pub quality: Vec<NoteKind>,
    /// Notes for the report.
    pub note: String,
}

impl Outcome {
    /// Every effect named, found or ambiguous.
    pub fn named(&self) -> Vec<EffectId> {
        let mut named: Vec<EffectId> = self.found.clone();
        named.extend(self.ambiguous.iter().flatten().copied());
        named
    }

    /// The case passed, by its class's rule (see the module doc).
    pub fn passed(&self) -> bool {
        match self.case.class() {
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
            None => self.verdict == Some(Verdict::None),
        }
    }

    /// A nuisance: the data-quality note it should raise is there.
    pub fn noted(&self) -> bool {
        let note = self.case.form.and_then(forms::Form::note);
        note.is_none_or(|k| self.quality.contains(&k))
    }
}
