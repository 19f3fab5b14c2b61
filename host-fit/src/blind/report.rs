//! The blind suite's report: every case, the catalogue class's confusion matrix,
//! detection by magnitude and scores, and the other classes form by form.
use crate::blind::cases::EFFECTS;
use crate::blind::forms::Class;
use crate::blind::outcome::Outcome;
use crate::diagnose::contract::Verdict;
use crate::diagnose::EffectId;

/// Effect ids joined by `sep`.
fn ids(v: &[EffectId], sep: &str) -> String {
    v.iter().map(|e| e.as_str()).collect::<Vec<_>>().join(sep)
}

/// The discovered terms of a case (` + term@axis ...`; empty when none).
fn terms(o: &Outcome) -> String {
    o.discovered
        .iter()
        .map(|c| format!(" + {}@{}", c.term, c.axes.join("")))
        .collect()
}

/// One line per case: what was concealed and what was named.
fn case_lines(outcomes: &[Outcome]) -> String {
    let mut s = String::from("case                                          scale seed  found / ambiguous                         pass   params  final/floor  verdict\n");
    for o in outcomes {
        let name = o.case.name();
        let amb = o
            .ambiguous
            .iter()
            .map(|a| format!("{{{}}}", ids(a, "|")))
            .collect::<Vec<_>>()
            .join(" ");
        s.push_str(&format!(
            "{name:<45} {:>5.2} {:>4}  {:<40} {:<6} {:<7} {:>6.2}       {} {}\n",
            o.case.scale,
            o.case.seed,
            format!(
                "{} {amb}{}",
                if o.found.is_empty() {
                    "none".to_string()
                } else {
                    ids(&o.found, ",")
                },
                terms(o)
            ),
            if o.passed() { "yes" } else { "NO" },
            match o.params_ok {
                Some(true) => "ok",
                Some(false) => "off",
                None => "-",
            },
            o.final_over_noise,
            o.verdict.map(|v| v.as_str()).unwrap_or(""),
            o.note
        ));
    }
    s
}

/// Concealed single effect (rows) against the effects named (columns); `None` is the
/// clean row and the "none named" column.
fn confusion(outcomes: &[Outcome]) -> String {
    let all = || std::iter::once(None).chain(EFFECTS.map(Some));
    let legend: Vec<String> = EFFECTS
        .iter()
        .map(|e| format!("{} = {e}", e.short()))
        .collect();
    let mut s = format!(
        "\nconfusion (concealed single effect -> effects named, counts; {}):\n",
        legend.join(", ")
    );
    s.push_str(&format!("{:<16}", ""));
    for c in all() {
        s.push_str(&format!("{:>6}", c.map_or("none", EffectId::short)));
    }
    s.push('\n');
    for row in all() {
        let cases: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| !o.case.tp_only && o.case.effects == Vec::from_iter(row))
            .collect();
        if cases.is_empty() {
            continue;
        }
        s.push_str(&format!("{:<16}", row.map_or("clean", EffectId::as_str)));
        for c in all() {
            let n = cases
                .iter()
                .filter(|o| {
                    let named = o.named();
                    match c {
                        None => named.is_empty(),
                        Some(c) => named.contains(&c),
                    }
                })
                .count();
            s.push_str(&format!("{n:>6}"));
        }
        s.push('\n');
    }
    s
}

/// Where detection stops: the concealed effect named, by magnitude.
fn by_magnitude(outcomes: &[Outcome]) -> String {
    let mut scales: Vec<f64> = outcomes
        .iter()
        .filter(|o| !o.case.effects.is_empty())
        .map(|o| o.case.scale)
        .collect();
    scales.sort_by(|a, b| b.total_cmp(a));
    scales.dedup();
    let mut s = String::from(
        "\ndetection by magnitude (1 = the nominal size; effect named / exactly right / cases):\n",
    );
    for sc in &scales {
        let at: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| !o.case.effects.is_empty() && o.case.scale == *sc)
            .collect();
        let hit = at
            .iter()
            .filter(|o| {
                let named = o.named();
                o.case.effects.iter().all(|e| named.iter().any(|f| f == e))
            })
            .count();
        let ex = at.iter().filter(|o| o.exact).count();
        s.push_str(&format!("  {sc:>5.2}: {hit}/{ex}/{}\n", at.len()));
    }
    s
}

/// The scores over the whole suite.
fn scores(outcomes: &[Outcome]) -> String {
    let exact = outcomes.iter().filter(|o| o.exact).count();
    let detectable: Vec<&Outcome> = outcomes.iter().filter(|o| o.case.scale >= 0.1).collect();
    let det_exact = detectable.iter().filter(|o| o.exact).count();
    let mut s = format!(
        "exactly the right set at magnitudes >= 0.1: {det_exact}/{} ({:.0}%)\n",
        detectable.len(),
        100.0 * det_exact as f64 / detectable.len().max(1) as f64
    );
    let clean: Vec<&Outcome> = outcomes
        .iter()
        .filter(|o| o.case.effects.is_empty())
        .collect();
    let false_on_clean = clean
        .iter()
        .filter(|o| !o.found.is_empty() || !o.ambiguous.is_empty())
        .count();
    let p: Vec<bool> = outcomes.iter().filter_map(|o| o.params_ok).collect();
    let resid_ok = outcomes
        .iter()
        .filter(|o| o.exact && o.final_over_noise <= 1.5)
        .count();
    s.push_str(&format!(
        "\nexactly the right set: {exact}/{} ({:.0}%); false findings on clean recordings: {false_on_clean}/{}; parameters within 3 sigma: {}/{}; final residual <= 1.5x noise (exact cases): {resid_ok}/{exact}\n",
        outcomes.len(),
        100.0 * exact as f64 / outcomes.len().max(1) as f64,
        clean.len(),
        p.iter().filter(|b| **b).count(),
        p.len()
    ));
    s
}

/// Per form of the other classes: cases passed, and what was named or noted.
fn by_form(outcomes: &[Outcome]) -> String {
    let mut s = String::new();
    for class in [
        Class::OtherForm,
        Class::Outside,
        Class::Nuisance,
        Class::SlowDisturbance,
        Class::Digital,
        Class::FixtureChange,
        Class::Mixture,
        Class::Expressed,
        Class::Unexpressed,
        Class::NoDiscovery,
    ] {
        let of: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.case.class() == class)
            .collect();
        if of.is_empty() {
            continue;
        }
        let passed = of.iter().filter(|o| o.passed()).count();
        s.push_str(&format!(
            "\n{}: {passed}/{} passed{}\n",
            class.name(),
            of.len(),
            class_summary(class, &of)
        ));
        let mut forms: Vec<_> = Vec::new();
        for o in &of {
            if !forms.contains(&o.case.form) {
                forms.push(o.case.form);
            }
        }
        for f in forms {
            let cases: Vec<&&Outcome> = of.iter().filter(|o| o.case.form == f).collect();
            let ok = cases.iter().filter(|o| o.passed()).count();
            let mut named: Vec<EffectId> = cases.iter().flat_map(|o| o.named()).collect();
            // by name, as the report always listed them
            named.sort_by_key(|e| e.as_str());
            named.dedup();
            let named_list = if named.is_empty() {
                "nothing".to_string()
            } else {
                ids(&named, ", ")
            };
            let detail = match class {
                Class::Outside => format!(
                    "{} with no catalogue name, {} located on the right axis",
                    cases.iter().filter(|o| o.named().is_empty()).count(),
                    cases.iter().filter(|o| o.located()).count()
                ),
                Class::Nuisance => format!(
                    "{} with no physics, {} with the data note",
                    cases.iter().filter(|o| o.named().is_empty()).count(),
                    cases.iter().filter(|o| o.noted()).count()
                ),
                Class::OtherForm | Class::Catalogue => format!("named: {named_list}"),
                Class::SlowDisturbance => format!(
                    "{} with no catalogue name, {} named warmup_drift, {} located on the right axis; named: {named_list}",
                    cases.iter().filter(|o| o.named().is_empty()).count(),
                    cases
                        .iter()
                        .filter(|o| o.named().contains(&EffectId::WarmupDrift))
                        .count(),
                    cases.iter().filter(|o| o.located()).count()
                ),
                Class::Digital => format!(
                    "{} diagnosed, {} exactly right; named: {named_list}",
                    cases.iter().filter(|o| o.verdict.is_some()).count(),
                    cases.iter().filter(|o| o.exact).count()
                ),
                Class::FixtureChange => format!(
                    "{} named fixture_error, {} with the right position and stop; named: {named_list}",
                    cases
                        .iter()
                        .filter(|o| o.named().contains(&EffectId::FixtureError))
                        .count(),
                    cases.iter().filter(|o| o.right_stop()).count()
                ),
                Class::Expressed | Class::Unexpressed | Class::NoDiscovery => String::new(),
                Class::Mixture => format!(
                    "{} exact, {} of the {} concealed named, {} wrong names",
                    cases.iter().filter(|o| o.exact).count(),
                    cases.iter().map(|o| o.hits()).sum::<usize>(),
                    cases.iter().map(|o| o.case.effects.len()).sum::<usize>(),
                    cases.iter().map(|o| o.wrong_names().len()).sum::<usize>()
                ),
            };
            let detail = match class {
                Class::Expressed | Class::Unexpressed | Class::NoDiscovery => {
                    discovery_detail(class, &cases, &named_list)
                }
                Class::Catalogue
                | Class::OtherForm
                | Class::Outside
                | Class::Nuisance
                | Class::SlowDisturbance
                | Class::Digital
                | Class::FixtureChange
                | Class::Mixture => detail,
            };
            let name = f.map_or("", |f| f.name());
            s.push_str(&format!("  {name:<44} {ok}/{}  ({detail})\n", cases.len()));
        }
    }
    s
}

/// A class's line beyond its pass count: mixtures count the cases by how many of their
/// three effects were named, and the wrong names apart (a missed small effect is a miss,
/// a wrong name worse); digital outputs count the cases the diagnosis refused.
fn class_summary(class: Class, of: &[&Outcome]) -> String {
    match class {
        Class::Mixture => {
            let with = |k: usize| of.iter().filter(|o| o.hits() == k).count();
            let wrong = of.iter().filter(|o| !o.wrong_names().is_empty()).count();
            let mut names: Vec<EffectId> = of.iter().flat_map(|o| o.wrong_names()).collect();
            names.sort();
            names.dedup();
            format!(
                " (exactly the set); of the three named: 3 in {}, 2 in {}, 1 in {}, 0 in {}; cases with a wrong name: {wrong} ({})",
                with(3),
                with(2),
                with(1),
                with(0),
                if names.is_empty() {
                    "none".to_string()
                } else {
                    ids(&names, ", ")
                }
            )
        }
        Class::Digital => format!(
            "; refused by the diagnosis: {}",
            of.iter().filter(|o| o.verdict.is_none()).count()
        ),
        Class::Expressed => {
            let mut forms = Vec::new();
            for o in of {
                if !forms.contains(&o.case.form) {
                    forms.push(o.case.form);
                }
            }
            let held = forms
                .iter()
                .filter(|f| {
                    let cases: Vec<_> = of.iter().filter(|o| o.case.form == **f).collect();
                    4 * cases.iter().filter(|o| o.passed()).count() >= 3 * cases.len()
                })
                .count();
            format!(
                "; forms named right in at least 3 of 4 cases: {held}/{}",
                forms.len()
            )
        }
        Class::Unexpressed | Class::NoDiscovery => format!(
            "; cases with a discovered term: {}",
            of.iter().filter(|o| !o.discovered.is_empty()).count()
        ),
        Class::Catalogue
        | Class::OtherForm
        | Class::Outside
        | Class::Nuisance
        | Class::SlowDisturbance
        | Class::FixtureChange => String::new(),
    }
}

/// A form's detail in the classes beyond the catalogue: seen at all, the right term,
/// wrong terms, catalogue names and the residual (targets); seen, no term, no name,
/// located (blind spots); no term, the catalogue's set (controls).
fn discovery_detail(class: Class, cases: &[&&Outcome], named: &str) -> String {
    let count = |f: &dyn Fn(&Outcome) -> bool| cases.iter().filter(|o| f(o)).count();
    // above the floor before any finding: a term there to be found
    let seen = |o: &Outcome| o.verdict.is_some_and(|v| v != Verdict::None);
    let mut wrong: Vec<String> = cases.iter().flat_map(|o| o.wrong_terms()).collect();
    wrong.sort();
    wrong.dedup();
    let wrong = if wrong.is_empty() {
        "none".to_string()
    } else {
        wrong.join(", ")
    };
    match class {
        Class::Expressed => format!(
            "{} seen, {} with the right term and axis, {} at <= 1.5x the floor, {} with a catalogue name; wrong terms: {wrong}; named: {named}",
            count(&seen),
            count(&|o| o.terms_named() == o.expected_terms().len()),
            count(&|o| o.final_over_noise <= 1.5),
            count(&|o| !o.named().is_empty()),
        ),
        Class::Unexpressed => format!(
            "{} seen, {} with no term, {} with no catalogue name, {} unexplained on the right axis; terms: {wrong}; named: {named}",
            count(&seen),
            count(&|o| o.discovered.is_empty()),
            count(&|o| o.named().is_empty()),
            count(&|o| o.unexplained_here()),
        ),
        Class::NoDiscovery
        | Class::Catalogue
        | Class::OtherForm
        | Class::Outside
        | Class::Nuisance
        | Class::SlowDisturbance
        | Class::Digital
        | Class::FixtureChange
        | Class::Mixture => format!(
            "{} with no term, {} with exactly the catalogue's set; terms: {wrong}; named: {named}",
            count(&|o| o.discovered.is_empty()),
            count(&|o| o.exact),
        ),
    }
}

/// The whole report: every case, then the catalogue class's confusion, magnitudes and
/// scores, then the other classes form by form.
pub fn report(outcomes: &[Outcome]) -> String {
    let cat: Vec<Outcome> = outcomes
        .iter()
        .filter(|o| o.case.class() == Class::Catalogue)
        .cloned()
        .collect();
    case_lines(outcomes)
        + &format!("\n{}:", Class::Catalogue.name())
        + &confusion(&cat)
        + &by_magnitude(&cat)
        + &scores(&cat)
        + &by_form(outcomes)
}
