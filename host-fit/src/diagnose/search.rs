//! The search for the physics the baseline leaves out, written as a solver's loop of
//! named steps: [`Forward::propose`] every open catalogue effect in its best profiled form
//! on top of the current model, [`Forward::rank`] them by the quasi-BIC each fit gains,
//! [`Forward::judge`] the best ranked in full by the acceptance rules ([`Judgement`]),
//! [`Forward::accept`] the first that passes (the rivals within the ambiguity margin are
//! named as ambiguous), [`Forward::stop`] when none passes or none is left; then the
//! [`backward`] check of the joint model, and [`keep_adequate`]: each effect must explain
//! the data where it acts.
//!
//! Every rule is a field of [`crate::diagnose::rules::Rules`] (all scaled by the
//! dispersion phi of the larger model, so a model still far from the data cannot buy
//! findings with small improvements): the quasi-BIC drops by more than `q_margin`; the
//! effect explains at least `material_share` of the chi-square above the floor; one of
//! its parameters is at least `z_significant` scaled sigmas from zero; the held-out time
//! chunks improve by more than `heldout_gain` per parameter (in floor units); its
//! profiled structure (time constant, bend) is determined by the data.
use crate::diagnose::baseline::reorder;
use crate::diagnose::data::Data;
use crate::diagnose::effects::{EffectId, Extra};
use crate::diagnose::fit::{Depth, Fit};
use crate::diagnose::metrics::{adequate, dispersion, judge, qbic, Judgement};
use crate::diagnose::profile;

/// What the data can identify.
pub struct Scope {
    /// Temperature-dependent effects (more than one temperature).
    pub temperature: bool,
    /// Time-series effects (the floor is measurable and the temperature moves).
    pub dynamics: bool,
    /// The direction of temperature changes reverses (hysteresis).
    pub reversals: bool,
    /// Highest polynomial order of the baseline the temperatures support.
    pub max_order: usize,
}

/// Where the search ended.
pub struct Outcome {
    /// The joint model with the effects accepted, checked backward and for adequacy.
    pub joint: Fit,
    /// Groups of candidates that explained the data equally well (the best of each group
    /// was in the model, none is named).
    pub ambiguous: Vec<Vec<EffectId>>,
}

/// Search from `baseline` (see the module doc).
pub fn run(data: &Data, baseline: &Fit, scope: &Scope) -> Outcome {
    let mut s = Forward {
        data,
        scope,
        current: baseline.clone(),
        used: Vec::new(),
        ambiguous: Vec::new(),
    };
    loop {
        let proposals = s.propose();
        let ranked = s.rank(proposals);
        let Some(step) = s.judge(ranked) else {
            break;
        };
        s.accept(step);
        if s.stop() {
            break;
        }
    }
    Outcome {
        joint: keep_adequate(data, backward(data, s.current)),
        ambiguous: s.ambiguous,
    }
}

/// The forward search's state between rounds.
struct Forward<'s, 'a> {
    data: &'s Data<'a>,
    scope: &'s Scope,
    /// The model so far.
    current: Fit,
    /// Effects no longer proposed: at their most, or named in an ambiguity.
    used: Vec<EffectId>,
    /// The ambiguities met.
    ambiguous: Vec<Vec<EffectId>>,
}

/// A proposal with the quasi-BIC it gains in its own dispersion.
struct Ranked {
    gain: f64,
    id: EffectId,
    fit: Fit,
}

/// One round's decision: the effect accepted (fitted in full) and its rivals.
struct Step {
    id: EffectId,
    fit: Fit,
    rivals: Vec<EffectId>,
}

impl Forward<'_, '_> {
    /// Whether effect `id` may still be proposed.
    fn open(&self, id: EffectId) -> bool {
        let count = self
            .current
            .spec
            .extras
            .iter()
            .filter(|e| e.id() == id)
            .count();
        !self.used.contains(&id) && count < id.max_count()
    }

    /// Every open effect's best form on top of the current model, for profiling (no
    /// held-out chunks).
    fn propose(&self) -> Vec<Fit> {
        let (data, scope, current) = (self.data, self.scope, &self.current);
        let spec = &current.spec;
        let mut out = Vec::new();
        let single = |e: Extra| data.fit(&spec.with(e), Some(current), Depth::Profile);
        if scope.temperature && self.open(EffectId::TempCurvature) {
            let broad = !spec.extras.iter().any(|e| matches!(e, Extra::Curvature(_)));
            out.extend(choose_form(
                data,
                current,
                profile::curvature(data, spec, current, broad),
            ));
        }
        if scope.dynamics && self.open(EffectId::ThermalLag) {
            out.extend(choose_form(
                data,
                current,
                profile::lag(data, spec, current),
            ));
        }
        if scope.dynamics && self.open(EffectId::TempRate) {
            out.extend(profile::rate(data, spec, current));
        }
        if scope.dynamics && scope.reversals && self.open(EffectId::Hysteresis) {
            out.extend(choose_form(
                data,
                current,
                profile::hysteresis(data, spec, current),
            ));
        }
        if scope.dynamics && self.open(EffectId::WarmupDrift) {
            out.extend(choose_form(
                data,
                current,
                profile::warmup(data, spec, current),
            ));
        }
        for e in [Extra::K2, Extra::Asymmetry] {
            if self.open(e.id()) {
                out.extend(single(e));
            }
        }
        if self.open(EffectId::FixtureError) {
            let mut positions: Vec<usize> = data.obs.iter().map(|o| o.position).collect();
            positions.sort_unstable();
            positions.dedup();
            let taken = |changed: bool| -> Vec<usize> {
                spec.extras
                    .iter()
                    .filter_map(|e| {
                        if let Extra::Fixture(p, from) = e {
                            (from.is_some() == changed).then_some(*p)
                        } else {
                            None
                        }
                    })
                    .collect()
            };
            let (whole, changed) = (taken(false), taken(true));
            // a position re-clamped between two stops: the stop it changed at is profiled
            // (every stop but the first; none in a recording of many stops, a sweep)
            let stops = data.stop_starts.len();
            for p in positions {
                if !whole.contains(&p) {
                    out.extend(single(Extra::Fixture(p, None)));
                }
                if !changed.contains(&p) && (2..=data.rules.max_fixture_stops).contains(&stops) {
                    out.extend(
                        (2..=stops)
                            .filter_map(|n| single(Extra::Fixture(p, Some(n))))
                            .min_by(|a, b| a.chi2.total_cmp(&b.chi2)),
                    );
                }
            }
        }
        out
    }

    /// The proposals that gain more than the margin, each in its own dispersion, best
    /// first.
    fn rank(&self, proposals: Vec<Fit>) -> Vec<Ranked> {
        let data = self.data;
        let mut ranked: Vec<Ranked> = proposals
            .into_iter()
            .filter_map(|fit| {
                let phi = dispersion(data, &fit);
                let id = fit.spec.extras.last()?.id();
                let gain = qbic(data, &self.current, phi) - qbic(data, &fit, phi);
                Some(Ranked { gain, id, fit })
            })
            .filter(|r| r.gain > data.rules.q_margin)
            .collect();
        ranked.sort_by(|a, b| b.gain.total_cmp(&a.gain));
        ranked
    }

    /// The best ranked proposal that passes every acceptance rule, fitted in full, and
    /// the others of the ranking that gain within the ambiguity margin of it.
    fn judge(&self, ranked: Vec<Ranked>) -> Option<Step> {
        let rules = &self.data.rules;
        let mut accepted: Option<(f64, Step)> = None;
        for r in ranked.into_iter().take(rules.judged_per_round) {
            match &mut accepted {
                Some((best_gain, best)) => {
                    if r.id != best.id
                        && *best_gain - r.gain < rules.ambiguity_margin
                        && !best.rivals.contains(&r.id)
                    {
                        best.rivals.push(r.id);
                    }
                }
                None => {
                    if let Some(fit) = self.judged(&r.fit) {
                        let step = Step {
                            id: r.id,
                            fit,
                            rivals: Vec::new(),
                        };
                        accepted = Some((r.gain, step));
                    }
                }
            }
        }
        accepted.map(|(_, s)| s)
    }

    /// The proposal `f` fitted in full, when it passes every acceptance rule against the
    /// current model.
    fn judged(&self, f: &Fit) -> Option<Fit> {
        let data = self.data;
        let full = data.fit(&f.spec, Some(&self.current), Depth::Full)?;
        let j = judge(data, &self.current, &full, full.spec.extras.len() - 1);
        let ok = j.accepted(data);
        log::debug!("  {:?}: {j:?} accepted {ok}", full.spec.extras.last());
        ok.then_some(full)
    }

    /// The step's effect joins the model (its polynomial order chosen again); its rivals
    /// are named as ambiguous and no longer proposed, nor is an effect at its most.
    fn accept(&mut self, step: Step) {
        let Step { id, fit, rivals } = step;
        if !rivals.is_empty() {
            let mut group = vec![id];
            group.extend(rivals.iter().copied());
            self.used.extend(rivals);
            self.ambiguous.push(group);
        }
        if fit.spec.extras.iter().filter(|e| e.id() == id).count() >= id.max_count() {
            self.used.push(id);
        }
        self.current = reorder(self.data, &fit, self.scope.max_order);
    }

    /// Every effect has been used up.
    fn stop(&self) -> bool {
        self.used.len() >= EffectId::ALL.len()
    }
}

/// Of several forms of one effect on top of `current`, the simplest, unless a richer one
/// fits better AND passes every acceptance rule against it (a richer form must earn its
/// parameters as an effect must).
fn choose_form(data: &Data, current: &Fit, mut forms: Vec<Fit>) -> Option<Fit> {
    forms.sort_by_key(|f| f.params());
    let mut pick: Option<Fit> = None;
    for f in forms {
        let Some(p) = &pick else {
            pick = Some(f);
            continue;
        };
        if f.chi2 >= p.chi2 {
            continue;
        }
        let (Some(pf), Some(ff)) = (
            data.fit(&p.spec, Some(current), Depth::Full),
            data.fit(&f.spec, Some(current), Depth::Full),
        ) else {
            continue;
        };
        let e = ff.spec.extras.len() - 1;
        if judge(data, &pf, &ff, e).accepted(data) {
            pick = Some(f);
        }
    }
    pick
}

/// The joint model without extra `e`, refitted.
pub fn without(data: &Data, f: &Fit, e: usize) -> Option<Fit> {
    data.fit(&f.spec.without(e), None, Depth::Full)
}

/// The backward check: drop, one at a time, the effect the joint model needs least while
/// one of them no longer passes the acceptance rules against the model without it.
pub fn backward(data: &Data, mut current: Fit) -> Fit {
    loop {
        let mut weakest: Option<(Judgement, Fit)> = None;
        for e in 0..current.spec.extras.len() {
            let Some(reduced) = without(data, &current, e) else {
                continue;
            };
            let j = judge(data, &reduced, &current, e);
            if !j.accepted(data) && weakest.as_ref().is_none_or(|(w, _)| j.gain < w.gain) {
                weakest = Some((j, reduced));
            }
        }
        match weakest {
            Some((_, reduced)) => current = reduced,
            None => return current,
        }
    }
}

/// Drop every effect that does not explain the data where it acts (its region is
/// reported as unexplained instead); refits after each drop.
pub fn keep_adequate(data: &Data, mut current: Fit) -> Fit {
    'again: loop {
        for e in 0..current.spec.extras.len() {
            let Some(reduced) = without(data, &current, e) else {
                continue;
            };
            if !adequate(data, &current, &reduced) {
                log::debug!("  not adequate: {:?}", current.spec.extras[e]);
                current = reduced;
                continue 'again;
            }
        }
        return current;
    }
}
