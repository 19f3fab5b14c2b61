//! The search for the physics the baseline leaves out, written as a solver's loop of
//! named steps: [`Forward::propose`] every open catalogue effect in its best profiled form
//! on top of the current model, [`Forward::rank`] them by the quasi-BIC each fit gains,
//! [`Forward::judge`] the best ranked in full by the acceptance rules ([`Judgement`]),
//! [`Forward::accept`] the first that passes (the rivals within the ambiguity margin are
//! named as ambiguous), [`Forward::stop`] when none passes or none is left; then the
//! [`backward`] check of the joint model, and [`keep_adequate`]: each effect must explain
//! the data where it acts. Then the [`Forward::research`]: where the residual of the
//! joint model still stands out (a position, an axis, a time span, ...), every candidate
//! that explains a material share of what is left there is judged by the same rules, the
//! share counted in that region instead of over the whole recording (a small effect
//! beside a large one is diluted by the large one's imperfect fit elsewhere), and it
//! must reproduce on both halves of the recording; an effect found joins the model, the
//! backward and adequacy checks run again until neither drops one, and the search looks
//! again. A hysteresis, a warm-up or a temperature curvature must also beat a linear
//! drift in time in its place ([`beats_drift`]), when added and in the backward check.
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
use crate::diagnose::discover::{discover, Proposal, Unidentifiable};
use crate::diagnose::effects::{EffectId, Extra};
use crate::diagnose::findings::reproduced;
use crate::diagnose::fit::{Depth, Fit};
use crate::diagnose::library::Candidate;
use crate::diagnose::location::{locate, rows_of, Hotspot};
use crate::diagnose::metrics::{
    adequate, adequate_term, dispersion, judge, normalized_rms, qbic, z, Judgement,
};
use crate::diagnose::profile;
use serde::Serialize;

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
    /// The floor is measured (time series can be judged).
    pub measured: bool,
}

/// Where the search ended.
pub struct Outcome {
    /// The joint model with the effects accepted, checked backward and for adequacy.
    pub joint: Fit,
    /// Groups of candidates that explained the data equally well (the best of each group
    /// was in the model, none is named).
    pub ambiguous: Vec<Vec<EffectId>>,
    /// Every re-search, in order: where it looked and what it found.
    pub research: Vec<Research>,
    /// The library search after the catalogue's, round by round (empty: the rest was at
    /// the floor, or the data cannot judge time-series terms).
    pub library: Vec<LibraryRound>,
    /// Discovered terms in the model whose columns the design cannot tell from others'.
    pub term_sets: Vec<TermSet>,
    /// Library terms the design cannot identify, with the positions that would.
    pub unidentifiable: Vec<Unidentifiable>,
}

/// A discovered term in the model and the library terms whose columns this design
/// cannot tell from its own (after the model's columns are projected out).
#[derive(Debug, Clone, PartialEq)]
pub struct TermSet {
    /// The term in the model.
    pub extra: Extra,
    /// The others of its set.
    pub others: Vec<Candidate>,
    /// Whether it is named: it is the simplest of the set (fewer factors than every
    /// other), so the finding names it and lists the others; else the set is reported
    /// as ambiguous, none named.
    pub named: bool,
}

/// One round of the library search: what the resampled selection proposed and which
/// proposal (if any) passed every acceptance rule.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct LibraryRound {
    /// Library columns tried.
    pub tried: usize,
    /// The terms proposed (`term on axis`, with the share of resamples choosing it).
    pub proposed: Vec<ProposedTerm>,
    /// The term that passed and joined the model (null: none passed).
    pub found: Option<String>,
}

/// A term the resampled selection proposed.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ProposedTerm {
    /// The term in the catalogue's vocabulary.
    pub term: String,
    /// The output axis.
    pub axis: &'static str,
    /// Share of the bootstrap resamples of the time chunks that chose it.
    pub inclusion: f64,
}

/// One re-search after the effects accepted so far: the located region it looked at,
/// the candidates whose contribution sits there, and what passed the rules.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Research {
    /// Where the joint model's residual still stands out (the groups looked at, worst
    /// first; the one the effect found explains, when one was found).
    pub region: Vec<Hotspot>,
    /// The effects proposed there: each explains at least
    /// [`crate::diagnose::rules::Rules::material_share`] of the excess in a located group.
    pub tried: Vec<EffectId>,
    /// The effect that passed every acceptance rule and stayed in the joint model; None:
    /// nothing passed.
    pub found: Option<EffectId>,
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
    let mut research = Vec::new();
    // effects a re-search found that the checks then dropped: not proposed there again
    let mut dropped: Vec<EffectId> = Vec::new();
    // the effects a re-search found, with the located rows they were judged on: the
    // backward check judges them there again
    let mut regions: Vec<Region> = Vec::new();
    loop {
        s.forward();
        s.current = checked(data, s.current.clone(), &regions);
        if research.len() >= data.rules.research_rounds || s.stop() {
            break;
        }
        let Some((mut r, step)) = s.research(&dropped) else {
            break;
        };
        let Some((step, rows)) = step else {
            research.push(r);
            break;
        };
        let id = step.id;
        let Some(extra) = step.fit.spec.extras.last().cloned() else {
            research.push(r);
            break;
        };
        regions.push((extra.clone(), rows));
        s.accept(step);
        s.current = checked(data, s.current.clone(), &regions);
        if !s.current.spec.extras.contains(&extra) {
            log::debug!("  re-search: {id:?} dropped by the checks");
            dropped.push(id);
            r.found = None;
        }
        research.push(r);
    }
    // the catalogue's time constants estimated jointly before the library looks at the
    // rest: a lag profiled before the rate beside it leaves a rest of its own making
    s.current = profile::refine_jointly(data, &s.current);
    let (library, term_sets, unidentifiable) = library_search(&mut s, &regions);
    Outcome {
        joint: s.current,
        ambiguous: s.ambiguous,
        research,
        library,
        term_sets,
        unidentifiable,
    }
}

/// What the library search leaves: its rounds, the discovered terms found as sets, the
/// terms the design cannot identify.
type LibraryOutcome = (Vec<LibraryRound>, Vec<TermSet>, Vec<Unidentifiable>);

/// A proposal and the library terms the design cannot tell from it: the simplest of
/// them (fewest factors) is the one judged, the others go with it; `named` when it is
/// the only one that simple (Occam: a set of equally simple terms is not a choice).
fn simplest(p: &Proposal) -> (Proposal, Vec<Candidate>, bool) {
    let mut all = vec![p.candidate.clone()];
    all.extend(p.equivalents.iter().cloned());
    let least = all.iter().map(|c| c.term.factors()).min().unwrap_or(0);
    let simplest: Vec<usize> = (0..all.len())
        .filter(|&i| all[i].term.factors() == least)
        .collect();
    let pick = simplest.first().copied().unwrap_or(0);
    let chosen = all.remove(pick);
    (
        Proposal {
            candidate: chosen,
            equivalents: Vec::new(),
            ..p.clone()
        },
        all,
        simplest.len() == 1,
    )
}

/// After the catalogue's search: while the rest stays above the floor, the library of
/// discovered terms is searched ([`discover`]) and its proposals judged in turn by every
/// acceptance rule a catalogue effect meets, and by reproduction on both halves; the
/// first that passes joins the model (its decay's time constant profiled), the joint
/// model is checked backward (an effect the term explains better is dropped) and the
/// library is searched again, at most
/// [`crate::diagnose::rules::Rules::discover_max_terms`] times. Time-series terms need
/// the same data the catalogue's time-series effects need.
fn library_search(s: &mut Forward, regions: &[Region]) -> LibraryOutcome {
    let data = s.data;
    let rules = &data.rules;
    let mut rounds = Vec::new();
    let mut sets = Vec::new();
    let mut unidentifiable = Vec::new();
    let reach = crate::diagnose::library::Reach {
        temperature: s.scope.temperature,
        time: s.scope.measured,
        rate: s.scope.dynamics,
    };
    let mut rejected: Vec<Candidate> = Vec::new();
    while rounds.len() < rules.discover_max_terms
        && normalized_rms(data, &s.current) > rules.at_floor_rms
    {
        let order = match s.current.spec.basis {
            crate::fit::temperature::Basis::Poly { order } => order,
            crate::fit::temperature::Basis::Pwl { .. } => 1,
        };
        let found = discover(data, &s.current, order, reach);
        if unidentifiable.is_empty() {
            unidentifiable = found.unidentifiable.clone();
        }
        let mut round = LibraryRound {
            tried: found.tried,
            proposed: found
                .proposals
                .iter()
                .map(|p| ProposedTerm {
                    term: p.candidate.term.to_string(),
                    axis: firmware_core::model::AXES[p.candidate.axis],
                    inclusion: p.inclusion,
                })
                .collect(),
            found: None,
        };
        let mut step = None;
        for p in found.proposals {
            let (p, others, named) = simplest(&p);
            if rejected.contains(&p.candidate) {
                continue;
            }
            match s.judged_term(&p) {
                Some(fit) => {
                    step = Some((p, others, named, fit));
                    break;
                }
                None => rejected.push(p.candidate.clone()),
            }
        }
        let Some((p, others, named, fit)) = step else {
            rounds.push(round);
            break;
        };
        let Some(extra) = fit.spec.extras.last().cloned() else {
            rounds.push(round);
            break;
        };
        round.found = Some(format!("{}", extra.form()));
        s.current = reorder(data, &fit, s.scope.max_order);
        s.current = checked(data, s.current.clone(), regions);
        if s.current.spec.extras.contains(&extra) && !others.is_empty() {
            sets.push(TermSet {
                extra,
                others,
                named,
            });
        } else if !s.current.spec.extras.contains(&extra) {
            round.found = None;
            rejected.push(p.candidate.clone());
        }
        rounds.push(round);
    }
    sets.retain(|t| s.current.spec.extras.contains(&t.extra));
    (rounds, sets, unidentifiable)
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

/// A re-search's step and the located rows it was judged on.
type Relocated = (Step, Vec<usize>);

/// An effect a re-search found, with the located rows it was judged on.
type Region = (Extra, Vec<usize>);

/// One round's decision: the effect accepted (fitted in full) and its rivals.
struct Step {
    id: EffectId,
    fit: Fit,
    rivals: Vec<EffectId>,
}

impl Forward<'_, '_> {
    /// Rounds of propose, rank, judge, accept until none passes or none is left.
    fn forward(&mut self) {
        loop {
            let proposals = self.propose();
            let ranked = self.rank(proposals);
            let Some(step) = self.judge(ranked) else {
                break;
            };
            self.accept(step);
            if self.stop() {
                break;
            }
        }
    }

    /// Look again where the current model's residual is located: for each of the worst
    /// [`crate::diagnose::rules::Rules::research_groups`] located groups, the ranked
    /// proposals (effects not in `dropped`) that explain a material share of the excess
    /// there are judged in full by the acceptance rules, the share counted in that
    /// group. None when the residual is at the floor or nowhere located; else what was
    /// looked at, and the step of the first that passed.
    fn research(&self, dropped: &[EffectId]) -> Option<(Research, Option<Relocated>)> {
        let data = self.data;
        let rules = &data.rules;
        if normalized_rms(data, &self.current) <= rules.at_floor_rms {
            return None;
        }
        let zs = z(data, &self.current);
        let spots: Vec<Hotspot> = locate(data, &zs, &self.current.resid, rules.located_sigmas)
            .into_iter()
            .take(rules.research_groups)
            .collect();
        if spots.is_empty() {
            return None;
        }
        let ranked: Vec<Ranked> = self
            .rank(self.propose())
            .into_iter()
            .filter(|r| !dropped.contains(&r.id))
            .collect();
        let mut tried: Vec<EffectId> = Vec::new();
        for h in &spots {
            let rows = rows_of(data, h);
            for r in &ranked {
                if regional_share(data, &self.current, &r.fit, &rows) < rules.material_share {
                    continue;
                }
                if !tried.contains(&r.id) {
                    tried.push(r.id);
                }
                if let Some(fit) = self.judged_where(&r.fit, Some(&rows)) {
                    log::debug!(
                        "  re-search at {} {} {}: {:?}",
                        h.group,
                        h.value,
                        h.axis,
                        r.id
                    );
                    let research = Research {
                        region: vec![h.clone()],
                        tried,
                        found: Some(r.id),
                    };
                    let step = Step {
                        id: r.id,
                        fit,
                        rivals: Vec::new(),
                    };
                    return Some((research, Some((step, rows))));
                }
            }
        }
        let research = Research {
            region: spots,
            tried,
            found: None,
        };
        Some((research, None))
    }

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
            let forms = profile::lag(data, spec, current);
            let one_pole = forms.first().cloned();
            let pick = choose_form(data, current, forms);
            out.extend(pick.map(|p| match one_pole {
                Some(one) if self.open(EffectId::TempRate) => {
                    lag_against_rate(data, current, one, p)
                }
                _ => p,
            }));
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
        self.judged_where(f, None)
    }

    /// [`Forward::judged`], its share of the excess counted on `rows` (a located region)
    /// when given: an effect found there must then also show on both halves of the
    /// recording, else the leftovers of a larger effect's imperfect form pass for a small
    /// one.
    fn judged_where(&self, f: &Fit, rows: Option<&[usize]>) -> Option<Fit> {
        let data = self.data;
        let full = data.fit(&f.spec, Some(&self.current), Depth::Full)?;
        let e = full.spec.extras.len().checked_sub(1)?;
        let mut j = judge(data, &self.current, &full, e);
        if let Some(rows) = rows {
            j.share = regional_share(data, &self.current, &full, rows);
        }
        let ok = j.accepted(data)
            && beats_drift(data, &self.current, &full, e)
            && rows.is_none_or(|_| reproduced(data, &full, &self.current));
        log::debug!(
            "  {}{:?}: {j:?} accepted {ok}",
            if rows.is_some() { "re-search " } else { "" },
            full.spec.extras.last()
        );
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

    /// A proposal of the library search at its profiled time constant, fitted in full,
    /// when it passes every acceptance rule against the current model, reproduces on
    /// both halves and explains the data where it acts.
    fn judged_term(&self, p: &Proposal) -> Option<Fit> {
        let data = self.data;
        let spec = &self.current.spec;
        let Candidate { term, axis } = p.candidate.clone();
        let extra = |t: &crate::diagnose::library::LibTerm| Extra::Discovered {
            term: t.clone(),
            axis,
        };
        let term = match term.tau_s() {
            Some(tau) => {
                let make = |t: f64| {
                    data.fit(
                        &spec.with(extra(&term.with_tau(t))),
                        Some(&self.current),
                        Depth::Profile,
                    )
                };
                let grid = profile::Grid {
                    max_s: profile::settling_limit_s(data),
                    ..profile::Grid::around(data, tau, 2, 5)
                };
                let (t, _) = profile::time_constant(&make, grid)?;
                // a decay that does not settle within the recording is a drift: `t`
                // (or its product) says that with one parameter less
                if t >= grid.max_s / data.rules.grid_ratio {
                    return None;
                }
                term.with_tau(t)
            }
            None => term,
        };
        let full = data.fit(&spec.with(extra(&term)), Some(&self.current), Depth::Full)?;
        let e = full.spec.extras.len().checked_sub(1)?;
        let j = judge(data, &self.current, &full, e);
        let ok = j.accepted(data)
            && reproduced(data, &full, &self.current)
            && adequate_term(data, &full, &self.current, axis);
        log::debug!("  library {term} on {axis}: {j:?} accepted {ok}");
        ok.then_some(full)
    }

    /// Every effect has been used up.
    fn stop(&self) -> bool {
        self.used.len() >= EffectId::ALL.len()
    }
}

/// The share of the excess over the floor on `rows` (residual rows, floor-weighted) that
/// `larger` explains beyond `smaller`: [`Judgement::share`] counted in a located region.
fn regional_share(data: &Data, smaller: &Fit, larger: &Fit, rows: &[usize]) -> f64 {
    let chi2 = |f: &Fit| -> f64 {
        rows.iter()
            .map(|&r| data.w[r] * f.resid[r / 3][r % 3] * f.resid[r / 3][r % 3])
            .sum()
    };
    let before = chi2(smaller);
    let excess = (before - rows.len() as f64).max(f64::MIN_POSITIVE);
    (before - chi2(larger)) / excess
}

/// Whether effect `e` of `full` (a full fit; `current` is it without `e`), when it can
/// pass for a trend in time (a hysteresis, a warm-up, a temperature curvature), explains
/// the data better than a linear drift in time of the same coefficients would in its
/// place: its quasi-BIC is lower than the drift's by more than
/// [`crate::diagnose::rules::Rules::q_margin`], in its own dispersion. A slow disturbance
/// with no temperature reversal and no power-on behind it (bias or scale ageing, part of
/// a slow cycle) is fitted by a direction switch, a long decay or a bend about as well as
/// by the trend itself on a single pass through the temperatures; the effect must show
/// its own shape (a switch at the reversals, a decay from the event, a bend at a
/// temperature revisited at another time), not only a trend, to be named. The other
/// effects act through the position or the rate, not through time, and have no such
/// rival.
fn beats_drift(data: &Data, current: &Fit, full: &Fit, e: usize) -> bool {
    let scale = match full.spec.extras.get(e) {
        Some(Extra::Hysteresis { scale, .. }) => *scale,
        Some(Extra::Warmup { .. } | Extra::Curvature(_)) => false,
        Some(Extra::Bend { .. }) => true,
        Some(
            Extra::Lag { .. }
            | Extra::Rate { .. }
            | Extra::K2
            | Extra::Asymmetry
            | Extra::Fixture(..)
            | Extra::Discovered { .. },
        )
        | None => return true,
    };
    let Some(rival) = data.fit_drift(&current.spec, Some(current), scale) else {
        return true;
    };
    let phi = dispersion(data, full);
    let gain = qbic(data, &rival, phi) - qbic(data, full, phi);
    log::debug!(
        "  against a linear drift in time: gain {gain:.1} (chi2 {:.0} vs {:.0}, params {} vs {}, {:?})",
        rival.chi2,
        full.chi2,
        rival.params(),
        full.params(),
        current.spec.extras
    );
    gain > data.rules.q_margin
}

/// The lag form `richer` (a time constant per axis, or two poles) when it beats the
/// one-pole lag `one` with a temperature-rate term beside it (its estimator profiled) by
/// more than the margin in quasi-BIC, else `one`: on a chamber's ramps a rate term's
/// offset in dT/dt looks like the difference of per-axis lags where the offsets'
/// temperature slopes dominate, and the two part in flight (a lag acts through every
/// coefficient's slope, at every attitude; a rate term on the offsets only), so the rate
/// is the catalogue's own reading and the richer lag must earn its place against it. The
/// rate itself is then judged as any effect, in the next round.
fn lag_against_rate(data: &Data, current: &Fit, one: Fit, richer: Fit) -> Fit {
    if richer.spec == one.spec {
        return richer;
    }
    let with_rate = profile::rate(data, &one.spec, &one)
        .and_then(|f| data.fit(&f.spec, Some(current), Depth::Full));
    let Some(rival) = with_rate else {
        return richer;
    };
    let Some(rich) = data.fit(&richer.spec, Some(current), Depth::Full) else {
        return richer;
    };
    let phi = dispersion(data, &rich).max(dispersion(data, &rival));
    let gain = qbic(data, &rival, phi) - qbic(data, &rich, phi);
    log::debug!(
        "  {:?} against one pole and a rate: gain {gain:.1}",
        richer.spec.extras.last()
    );
    if gain > data.rules.q_margin {
        richer
    } else {
        one
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
/// one of them no longer passes the acceptance rules against the model without it (a
/// hysteresis, a warm-up or a curvature also against a linear drift in its place, see
/// [`beats_drift`]). An effect a re-search found (in `regions`, with its located rows)
/// has its share counted there, as when it was accepted.
pub fn backward(data: &Data, mut current: Fit, regions: &[(Extra, Vec<usize>)]) -> Fit {
    loop {
        let mut weakest: Option<(Judgement, Fit)> = None;
        for e in 0..current.spec.extras.len() {
            let Some(reduced) = without(data, &current, e) else {
                continue;
            };
            let mut j = judge(data, &reduced, &current, e);
            if let Some((_, rows)) = regions.iter().find(|(x, _)| *x == current.spec.extras[e]) {
                j.share = regional_share(data, &reduced, &current, rows);
            }
            let kept = j.accepted(data) && beats_drift(data, &reduced, &current, e);
            if !kept && weakest.as_ref().is_none_or(|(w, _)| j.gain < w.gain) {
                weakest = Some((j, reduced));
            }
        }
        match weakest {
            Some((_, reduced)) => current = reduced,
            None => return current,
        }
    }
}

/// The backward check and the adequacy check, again until neither drops an effect: an
/// effect dropped as inadequate changes what the others are judged against.
fn checked(data: &Data, mut current: Fit, regions: &[(Extra, Vec<usize>)]) -> Fit {
    loop {
        let n = current.spec.extras.len();
        current = keep_adequate(data, backward(data, current, regions));
        if current.spec.extras.len() == n {
            return current;
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
