//! The outcome of a blind case and the rule it passes by, per class.
use crate::blind::beyond::{expected_terms, Expect};
use crate::blind::cases::Case;
use crate::blind::config::configure;
use crate::blind::forms;
use crate::blind::forms::Class;
use crate::blind::terms::Term;
use crate::diagnose::contract::Verdict;
use crate::diagnose::findings::Finding;
use crate::diagnose::parameters::Quantity;
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
    /// What each fixture_error finding says about where and from when.
    pub fixture_claims: Vec<FixtureClaim>,
    /// The `discovered` findings: terms of the library the diagnosis named.
    pub discovered: Vec<DiscoveredClaim>,
    /// Notes for the report.
    pub note: String,
}

/// What a fixture_error finding claims: its position, its form and evidence, and a stop
/// it names among its parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct FixtureClaim {
    /// The position named.
    pub position: Option<String>,
    /// The finding's form and evidence, as written.
    pub text: String,
    /// The stop the change is from (its `from_stop` parameter), if any.
    pub from_stop: Option<f64>,
}

/// A `discovered` finding as the blind suite judges it, filled from the diagnosis's
/// finding (`"effect": "discovered"`, its `"term"` in the catalogue's canonical text,
/// its `"axes"` and `"reproduced"`): `DiscoveredClaim { term: f.term.as_ref()?.to_string(), axes:
/// f.axes.clone(), reproduced: f.reproduced }`. The suite reads the term with its own
/// parser ([`crate::blind::terms`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DiscoveredClaim {
    /// The term, as the vocabulary writes it (`a_x*a_y`, `decay(position,25s)`).
    pub term: String,
    /// The outputs it enters (`x`, `y`, `z`).
    pub axes: Vec<String>,
    /// It reproduced on both halves of the recording.
    pub reproduced: bool,
}

impl DiscoveredClaim {
    /// Its term on each of its axes (`None` for a term the vocabulary does not read or
    /// an axis that is not x, y or z: never a right term).
    pub fn pairs(&self) -> Vec<Option<(Term, usize)>> {
        let term = Term::parse(&self.term).ok();
        self.axes
            .iter()
            .map(|a| {
                let i = ["x", "y", "z"].iter().position(|x| x == a)?;
                Some((term.clone()?, i))
            })
            .collect()
    }

    /// It names `want`: the same term on that axis, reproduced.
    pub fn names(&self, want: &Expect) -> bool {
        self.reproduced
            && self
                .pairs()
                .iter()
                .flatten()
                .any(|(t, i)| *i == want.axis && t.same(&want.term))
    }
}

impl FixtureClaim {
    /// The claim of a finding (None for another effect).
    pub fn of(f: &Finding) -> Option<FixtureClaim> {
        (f.effect == EffectId::FixtureError).then(|| FixtureClaim {
            position: f.position.clone(),
            text: format!("{} {}", f.form, f.evidence),
            from_stop: f.parameters.get(Quantity::FromStop).map(|p| p.value),
        })
    }

    /// It puts the change at `position` from stop `n` (1-based) on, in a parameter or in
    /// its words ("from stop N on").
    pub fn says(&self, position: &str, n: usize) -> bool {
        self.position.as_deref() == Some(position)
            && (self.from_stop == Some(n as f64)
                || self.text.contains(&format!("from stop {n} on")))
    }
}

impl Outcome {
    /// Every effect named, found or ambiguous.
    pub fn named(&self) -> Vec<EffectId> {
        let mut named: Vec<EffectId> = self.found.clone();
        named.extend(self.ambiguous.iter().flatten().copied());
        named
    }

    /// The case passed, by its class's rule (see the module doc). Nothing may be
    /// discovered where the physics is the catalogue's or no term's; an effect outside
    /// the catalogue that a term expresses (a cubic, an ageing scale, a linear drift)
    /// passes left unexplained or named as its term.
    pub fn passed(&self) -> bool {
        let none = self.discovered.is_empty();
        match self.case.class() {
            Class::Catalogue | Class::OtherForm => self.exact && none,
            Class::Outside => self.named().is_empty() && self.unexplained_or_termed(),
            Class::Nuisance => self.named().is_empty() && none && self.noted(),
            Class::SlowDisturbance => self.named().is_empty() && self.unexplained_or_termed(),
            Class::Digital => self.verdict.is_some() && self.exact && none,
            Class::FixtureChange => self.exact && none && self.right_stop(),
            Class::Mixture => self.exact && none,
            Class::Expressed => self.term_right(),
            Class::Unexpressed => self.named().is_empty() && none && self.unexplained_here(),
            Class::NoDiscovery => self.exact && none,
        }
    }

    /// The terms the truth holds ([`expected_terms`] of the case's configuration).
    pub fn expected_terms(&self) -> Vec<Expect> {
        expected_terms(&configure(&self.case))
    }

    /// Every expected term named on its axis and reproduced, nothing else discovered or
    /// named from the catalogue, and the residual brought to 1.5x the floor.
    pub fn term_right(&self) -> bool {
        let want = self.expected_terms();
        !want.is_empty()
            && self.terms_named() == want.len()
            && self.wrong_terms().is_empty()
            && self.exact
            && self.final_over_noise <= 1.5
    }

    /// How many of the expected terms are named on their axes.
    pub fn terms_named(&self) -> usize {
        let want = self.expected_terms();
        want.iter()
            .filter(|w| self.discovered.iter().any(|c| c.names(w)))
            .count()
    }

    /// The discovered terms (on an axis) that the truth does not hold, as written.
    pub fn wrong_terms(&self) -> Vec<String> {
        let want = self.expected_terms();
        let mut v = Vec::new();
        for c in &self.discovered {
            for (p, a) in c.pairs().into_iter().zip(&c.axes) {
                let right =
                    p.is_some_and(|(t, i)| want.iter().any(|w| w.axis == i && w.term.same(&t)));
                if !right {
                    v.push(format!("{} on {a}", c.term));
                }
            }
        }
        v
    }

    /// Left unexplained and located on the right axis (something was seen: these forms
    /// are 5-20x the floor).
    pub fn unexplained_here(&self) -> bool {
        self.verdict == Some(Verdict::Unexplained) && self.located()
    }

    /// Outside the catalogue: located and nothing discovered, or every term the truth
    /// holds named and nothing else.
    fn unexplained_or_termed(&self) -> bool {
        let want = self.expected_terms();
        let termed =
            !want.is_empty() && self.terms_named() == want.len() && self.wrong_terms().is_empty();
        (self.discovered.is_empty() && self.located()) || termed
    }

    /// A re-clamped fixture: a fixture_error finding names its position and the stop
    /// from which on it is off (true for the other classes).
    pub fn right_stop(&self) -> bool {
        let Some(forms::Form::Refixed(r)) = self.case.form else {
            return true;
        };
        let (position, n) = r.where_when();
        self.fixture_claims.iter().any(|c| c.says(position, n))
    }

    /// The concealed effects it named (mixtures: how many of the three).
    pub fn hits(&self) -> usize {
        let named = self.named();
        self.case
            .effects
            .iter()
            .filter(|e| named.contains(e))
            .count()
    }

    /// The effects it named that were not concealed.
    pub fn wrong_names(&self) -> Vec<EffectId> {
        let mut v: Vec<EffectId> = self
            .named()
            .into_iter()
            .filter(|e| !self.case.effects.contains(e))
            .collect();
        v.sort();
        v.dedup();
        v
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blind::forms::Form;
    use crate::blind::kinds::{Digital, Mixture, Refixed, Slow};
    use crate::blind::profiles::Profile;

    /// The outcome of `form` (seed 1) had the diagnosis named `found`, judged `verdict`
    /// and left the largest residual on `axis`.
    fn outcome(
        form: Form,
        found: &[EffectId],
        verdict: Option<Verdict>,
        axis: Option<&str>,
        claims: Vec<FixtureClaim>,
    ) -> Outcome {
        let case = Case::of_form(form, 1);
        let mut named = found.to_vec();
        named.sort();
        let mut want = case.effects.clone();
        want.sort();
        Outcome {
            exact: named == want,
            case,
            found: found.to_vec(),
            ambiguous: Vec::new(),
            params_ok: None,
            final_over_noise: 1.0,
            verdict,
            unexplained_axis: axis.map(str::to_string),
            quality: Vec::new(),
            fixture_claims: claims,
            discovered: Vec::new(),
            note: String::new(),
        }
    }

    /// The axis the slow form of seed 1 is on.
    fn axis_of(form: Form) -> &'static str {
        let axes = forms::axes(&configure(&Case::of_form(form, 1)));
        assert_eq!(axes.len(), 1, "{}", form.name());
        ["x", "y", "z"][axes[0]]
    }

    #[test]
    fn a_slow_disturbance_called_warmup_fails() {
        for slow in Slow::ALL {
            let f = Form::Slow(slow);
            let a = axis_of(f);
            let right = outcome(f, &[], Some(Verdict::Unexplained), Some(a), vec![]);
            assert!(right.passed(), "{}", f.name());
            let warm = outcome(
                f,
                &[EffectId::WarmupDrift],
                Some(Verdict::Explained),
                None,
                vec![],
            );
            assert!(!warm.passed(), "{}", f.name());
            let other = ["x", "y", "z"].into_iter().find(|x| *x != a).unwrap();
            let elsewhere = outcome(f, &[], Some(Verdict::Unexplained), Some(other), vec![]);
            assert!(!elsewhere.passed(), "{}: located on {other}", f.name());
        }
    }

    #[test]
    fn a_re_clamped_fixture_needs_its_position_and_stop() {
        let f = Form::Refixed(Refixed::Pp4FromStop3);
        let claim = |position: &str, text: &str, stop: Option<f64>| FixtureClaim {
            position: Some(position.into()),
            text: text.into(),
            from_stop: stop,
        };
        let fx = [EffectId::FixtureError];
        let ok = Some(Verdict::Explained);
        let pass = |c: FixtureClaim| outcome(f, &fx, ok, None, vec![c]).passed();
        assert!(pass(claim("PP4", "from stop 3 on", None)));
        assert!(pass(claim("PP4", "", Some(3.0))));
        assert!(!pass(claim("PP4", "from stop 2 on", Some(2.0))));
        assert!(!pass(claim("PP4", "a fixed error of the whole test", None)));
        assert!(!pass(claim("TP2", "from stop 3 on", None)));
        // named, but with another effect beside it
        let extra = [EffectId::FixtureError, EffectId::WarmupDrift];
        let c = claim("PP4", "from stop 3 on", None);
        assert!(!outcome(f, &extra, ok, None, vec![c]).passed());
    }

    #[test]
    fn a_mixture_counts_misses_and_wrong_names_apart() {
        let f = Form::Mixture(Mixture::RateHysteresisFixture);
        let ok = Some(Verdict::Explained);
        let all = [
            EffectId::TempRate,
            EffectId::Hysteresis,
            EffectId::FixtureError,
        ];
        let exact = outcome(f, &all, ok, None, vec![]);
        assert!(exact.passed());
        assert_eq!((exact.hits(), exact.wrong_names().len()), (3, 0));
        let missed = outcome(f, &all[..2], ok, None, vec![]);
        assert!(!missed.passed());
        assert_eq!((missed.hits(), missed.wrong_names().len()), (2, 0));
        let wrong = outcome(f, &[all[0], EffectId::WarmupDrift], ok, None, vec![]);
        assert!(!wrong.passed());
        assert_eq!(wrong.hits(), 1);
        assert_eq!(wrong.wrong_names(), [EffectId::WarmupDrift]);
    }

    #[test]
    fn a_digital_output_the_diagnosis_refuses_fails() {
        let clean = Form::Digital(Digital::Clean100);
        assert!(outcome(clean, &[], Some(Verdict::None), None, vec![]).passed());
        assert!(!outcome(clean, &[], None, None, vec![]).passed());
        let fx = Form::Digital(Digital::Fixture500);
        assert!(!outcome(fx, &[], Some(Verdict::Unexplained), Some("x"), vec![]).passed());
        assert!(outcome(
            fx,
            &[EffectId::FixtureError],
            Some(Verdict::Explained),
            None,
            vec![]
        )
        .passed());
    }

    #[test]
    fn the_new_classes_run_on_profiles_the_suite_had_not_used() {
        let seeds = [1, 2, 3, 4].map(Profile::of_seed);
        assert_eq!(
            seeds,
            [
                Profile::ColdFirst,
                Profile::HotFirst,
                Profile::LongSoaks,
                Profile::ColdFirst
            ]
        );
        for form in Form::on_own_profiles() {
            let c = configure(&Case::of_form(form, 2));
            assert_eq!(c.schedule.stops.len(), 4, "{}", form.name());
            assert_eq!(c.t0_c, 25.0, "{}", form.name());
            assert_eq!(c.schedule.stops[0].temp_c, 50.0, "{}", form.name());
        }
    }
}
