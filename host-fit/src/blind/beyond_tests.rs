//! Tests of the classes beyond the catalogue: the class table lists every form, every
//! form conceals its physics and the truth its terms, the designs' recordings read with
//! their positions, and the pass rules fail what they must.
use crate::blind::beyond::{expected_terms, Expressed, Plain, Unexpressed};
use crate::blind::cases::{discovery_cases as cases, Case};
use crate::blind::config::configure;
use crate::blind::designs::positions_of;
use crate::blind::designs::{PositionSet, Power};
use crate::blind::forms::{Class, Form, Outside};
use crate::blind::outcome::{DiscoveredClaim, Outcome};
use crate::blind::report::report;
use crate::data::recording::Recording;
use crate::diagnose::contract::Verdict;
use crate::diagnose::EffectId;
use crate::simulate::simulate;

fn all() -> Vec<Form> {
    cases(true)
        .iter()
        .filter_map(|c| c.form)
        .fold(Vec::new(), |mut v, f| {
            if !v.contains(&f) {
                v.push(f);
            }
            v
        })
}

/// Every form of the three classes is in the long suite on 4 seeds, each list in the
/// order of its exhaustive index, and the report lists every form under its class.
#[test]
fn the_class_table_lists_every_form() {
    for (i, f) in Expressed::ALL.iter().enumerate() {
        assert_eq!(f.index(), i);
    }
    for (i, f) in Unexpressed::ALL.iter().enumerate() {
        assert_eq!(f.index(), i);
    }
    for (i, f) in Plain::ALL.iter().enumerate() {
        assert_eq!(f.index(), i);
    }
    let forms = all();
    assert_eq!(
        forms.len(),
        Expressed::ALL.len() + Unexpressed::ALL.len() + Plain::ALL.len()
    );
    let long = cases(true);
    for f in &forms {
        assert_eq!(long.iter().filter(|c| c.form == Some(*f)).count(), 4);
    }
    assert!(Expressed::ALL.len() >= 8 && Unexpressed::ALL.len() >= 3);
    let outcomes: Vec<Outcome> = long.iter().map(|c| outcome(c.clone(), &[])).collect();
    let text = report(&outcomes);
    for class in [Class::Expressed, Class::Unexpressed, Class::NoDiscovery] {
        assert!(
            text.contains(&format!("\n{}: ", class.name())),
            "{}",
            class.name()
        );
    }
    for f in &forms {
        assert!(text.contains(&format!("  {} ", f.name())), "{}", f.name());
    }
    let short = cases(false);
    let classes: Vec<Class> = short.iter().map(Case::class).collect();
    assert_eq!(
        classes,
        [Class::Expressed, Class::Unexpressed, Class::NoDiscovery]
    );
}

/// Every form conceals something on its design (a clean one nothing), each expressed
/// form holds a term of the vocabulary on one axis, the others none; the sizes are
/// drawn per seed.
#[test]
fn every_form_conceals_its_physics_and_the_truth_its_terms() {
    for f in all() {
        let c = configure(&Case::of_form(f, 1));
        let mut bare = c.clone();
        bare.effects = crate::simulate::Effects::default();
        let clean = matches!(
            f,
            Form::Plain(Plain::CleanProducts | Plain::CleanPowerCycles | Plain::CleanTurning)
        );
        assert_eq!(c == bare, clean, "{}", f.name());
        let terms = expected_terms(&c);
        match f {
            Form::Expressed(_) => {
                assert_eq!(terms.len(), 1, "{}: {terms:?}", f.name());
                assert!(terms[0].term.degree() <= 3);
            }
            Form::Unexpressed(_) | Form::Plain(_) => {
                assert!(terms.is_empty(), "{}: {terms:?}", f.name())
            }
            Form::Other(_)
            | Form::Outside(_)
            | Form::Nuisance(_)
            | Form::Slow(_)
            | Form::Digital(_)
            | Form::Refixed(_)
            | Form::Mixture(_) => unreachable!("not a form of these classes"),
        }
        if !clean {
            let other = configure(&Case::of_form(f, 2));
            assert_ne!(c.effects, other.effects, "{}: the same sizes", f.name());
        }
    }
    // the cubic of the outside class and an ageing scale are terms too
    let cubic = configure(&Case::of_form(Form::Outside(Outside::CubicResponse), 1));
    assert_eq!(expected_terms(&cubic).len(), 1);
}

/// The recording of a product design is read with its positions, every one of its
/// positions dwelt at every stop; a power-cycled one states its power-offs.
#[test]
fn the_designs_recordings_read_with_their_positions() {
    for f in [
        Form::Expressed(Expressed::CrossCoupling),
        Form::Unexpressed(Unexpressed::Telegraph),
    ] {
        let cfg = configure(&Case::of_form(f, 1));
        let sim = simulate(&cfg, |_| {}).unwrap();
        let design = f.design(1).unwrap();
        assert_eq!(
            sim.csv.contains("# power_off_s="),
            design.power != Power::Steady,
            "{}",
            f.name()
        );
        // the positions file `simulate --positions-out` writes is the suite's
        assert_eq!(
            sim.positions_csv.is_some(),
            design.positions != PositionSet::Standard
        );
        let text = sim.positions_csv.as_deref().unwrap_or("name,fx,fy,fz\n");
        let (file, _) =
            crate::data::positions::Positions::parse(std::path::Path::new("p.csv"), text).unwrap();
        let mine = positions_of(&cfg);
        for (a, b) in file.list.iter().zip(&mine.list) {
            assert_eq!((&a.name, a.role), (&b.name, b.role));
            assert!((0..3).all(|k| (a.a[k] - b.a[k]).abs() < 1e-8), "{}", a.name);
        }
        assert_eq!(file.list.len(), mine.list.len());
        let rec =
            Recording::from_reader(std::path::Path::new("blind.csv"), sim.csv.as_bytes(), file)
                .unwrap();
        for name in design.positions.names() {
            let p = rec.positions.index(&name).unwrap();
            let dwells = rec.dwells.iter().filter(|d| d.position == p).count();
            assert!(dwells >= 5, "{name}: {dwells} dwells");
        }
    }
}

/// An outcome of `case` with nothing named and these discovered claims, explained at
/// the floor when something was discovered, else unexplained on the first axis the
/// form is on.
fn outcome(case: Case, claims: &[(&str, &str, bool)]) -> Outcome {
    let axis = crate::blind::forms::axes(&configure(&case))[0];
    Outcome {
        exact: case.effects.is_empty(),
        found: Vec::new(),
        ambiguous: Vec::new(),
        params_ok: None,
        final_over_noise: if claims.is_empty() { 3.0 } else { 1.1 },
        verdict: Some(if claims.is_empty() {
            Verdict::Unexplained
        } else {
            Verdict::Explained
        }),
        unexplained_axis: claims.is_empty().then(|| ["x", "y", "z"][axis].to_string()),
        quality: Vec::new(),
        fixture_claims: Vec::new(),
        discovered: claims
            .iter()
            .map(|(t, a, r)| DiscoveredClaim {
                term: t.to_string(),
                axes: vec![a.to_string()],
                reproduced: *r,
            })
            .collect(),
        note: String::new(),
        case,
    }
}

/// The truth's term and axis as written by a diagnosis.
fn truth(case: &Case) -> (String, &'static str) {
    let w = &expected_terms(&configure(case))[0];
    (w.term.to_string(), ["x", "y", "z"][w.axis])
}

#[test]
fn a_target_passes_only_on_its_term_and_axis_reproduced_at_the_floor() {
    for f in Expressed::ALL {
        let case = Case::of_form(Form::Expressed(f), 1);
        let (term, axis) = truth(&case);
        let other = ["x", "y", "z"].into_iter().find(|a| *a != axis).unwrap();
        assert!(
            outcome(case.clone(), &[(&term, axis, true)]).passed(),
            "{}",
            f.name()
        );
        assert!(!outcome(case.clone(), &[]).passed());
        assert!(!outcome(case.clone(), &[(&term, other, true)]).passed());
        assert!(!outcome(case.clone(), &[(&term, axis, false)]).passed());
        let extra = [(term.as_str(), axis, true), ("t", axis, true)];
        assert!(!outcome(case.clone(), &extra).passed());
        let mut high = outcome(case.clone(), &[(&term, axis, true)]);
        high.final_over_noise = 1.6;
        assert!(!high.passed());
        let mut named = outcome(case, &[(&term, axis, true)]);
        named.found = vec![EffectId::WarmupDrift];
        named.exact = false;
        assert!(!named.passed());
    }
    // a decay's time constant ten times off is another term
    let case = Case::of_form(Form::Expressed(Expressed::MoveSettle), 1);
    let (_, axis) = truth(&case);
    assert!(!outcome(case, &[("decay(position,400s)", axis, true)]).passed());
}

#[test]
fn blind_spots_and_controls_fail_on_any_discovered_term() {
    for f in Unexpressed::ALL {
        let case = Case::of_form(Form::Unexpressed(f), 1);
        assert!(outcome(case.clone(), &[]).passed(), "{}", f.name());
        assert!(!outcome(case.clone(), &[("t", "x", true)]).passed());
        let mut unseen = outcome(case, &[]);
        unseen.verdict = Some(Verdict::None);
        unseen.unexplained_axis = None;
        assert!(!unseen.passed(), "{}: not seen", f.name());
    }
    for f in Plain::ALL {
        let case = Case::of_form(Form::Plain(f), 1);
        let mut o = outcome(case.clone(), &[]);
        o.exact = true;
        assert!(o.passed(), "{}", f.name());
        let mut o = outcome(case, &[("a_x^2", "x", true)]);
        o.exact = true;
        assert!(!o.passed(), "{}", f.name());
    }
}

/// A cubic outside the catalogue passes unexplained (as before the term search) or
/// named as its term, never as another term.
#[test]
fn an_outside_effect_that_a_term_expresses_may_be_named_by_it() {
    let case = Case::of_form(Form::Outside(Outside::CubicResponse), 1);
    let (term, axis) = truth(&case);
    assert!(term.ends_with("^3"), "{term}");
    assert!(outcome(case.clone(), &[]).passed());
    assert!(outcome(case.clone(), &[(&term, axis, true)]).passed());
    assert!(!outcome(case, &[("a_x*a_y", axis, true)]).passed());
    let walk = Case::of_form(Form::Outside(Outside::BiasWander), 1);
    assert!(!outcome(walk, &[("t", "x", true)]).passed());
}
