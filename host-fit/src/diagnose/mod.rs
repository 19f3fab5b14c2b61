//! Diagnosis: when the model and a recording disagree, locate the mismatch, name the
//! physics left out (physics-catalogue.md) where the data support it, model it, show the
//! fit improve on held-out data, and say plainly what stays unexplained.
//!
//! [`diagnose`] reads top-down, on the [`crate::model`] engine: the error floor is
//! measured inside the dwells at every time scale, the windows are built once and
//! weighted by it ([`crate::model::weights`]); the baseline and the catalogue's effects
//! (their structural unknowns profiled) are fitted in one weighted least squares over all
//! three axes ([`crate::model::solve`]); the [`search`] adds an effect only when it
//! passes every acceptance rule ([`crate::model::rules`], judged by
//! [`crate::model::metrics`]) in the dispersion of the larger model, survives the backward
//! check of the joint model, and explains the data where it acts. Findings ([`findings`])
//! take their parameters from the final joint fit, typed with their units
//! ([`parameters`]); [`location`] says where a residual sits, [`quality`] what the data
//! themselves show, [`contract`] the JSON contract; the model the blob carries is
//! [`crate::model::flashed`]'s. With a logger at debug level (`HOSTFIT_DEBUG=1` for the
//! command), every candidate's judgement is logged.
pub mod contract;
pub mod coupled;
pub mod discover;
pub mod findings;
pub mod location;
pub mod parameters;
pub mod quality;
pub mod search;

pub use crate::model::effects::EffectId;
pub use crate::model::rules::Rules;

use crate::data::recording::Recording;
use crate::error::Result;
use crate::model::baseline;
use crate::model::basis::temperature_clusters;
use crate::model::data::Data;
use crate::model::flashed::Flashed;
use crate::model::floor::Floor;
use crate::model::metrics;
use crate::model::solve::Fit;
use crate::model::weights::{weighed, Purpose, Weighed};
use findings::{Ambiguity, Finding};
use firmware_core::temperature::Calibration;
use location::{locate, Hotspot};
use quality::QualityNote;

/// The whole diagnosis of one recording.
#[derive(Debug, Clone)]
pub struct Diagnosis<'a> {
    /// The data it was made on (the windows, their weights, the rules).
    pub data: Data<'a>,
    /// The measured error floor.
    pub floor: Floor,
    /// Whether the floor was measured (else the baseline's own scatter stands in).
    pub floor_measured: bool,
    /// Baseline.
    pub baseline: Fit,
    /// Final model.
    pub final_fit: Fit,
    /// Accepted findings.
    pub findings: Vec<Finding>,
    /// Ambiguities.
    pub ambiguous: Vec<Ambiguity>,
    /// Effects found together whose split the design pins only through its ramps.
    pub coupled: Vec<coupled::Coupling>,
    /// Where the baseline residual exceeds the floor.
    pub hotspots: Vec<Hotspot>,
    /// Where the final residual still exceeds the floor (empty when at the floor).
    pub unexplained: Vec<Hotspot>,
    /// The re-searches where the rest was located after the effects accepted: the
    /// region looked at and what was found there (empty: nothing was left to locate).
    pub research: Vec<search::Research>,
    /// The library search for discovered terms after the catalogue's, round by round.
    pub library: Vec<search::LibraryRound>,
    /// Why the catalogue's search and the library's phase ended.
    pub search_ended: search::Ended,
    /// What cannot be identified from this recording.
    pub not_identifiable: Vec<String>,
    /// Notes on the data.
    pub quality: Vec<QualityNote>,
    /// Expected residual RMS from the floor alone (output units, per window).
    pub noise_rms: f64,
    /// The model the blob carries: the final one in the firmware's forms (one lag pole
    /// for all axes, offsets-only hysteresis, one warm-up), refitted where it differs.
    pub flashed: Flashed,
}

impl Diagnosis<'_> {
    /// The recording diagnosed.
    pub fn recording(&self) -> &Recording {
        self.data.rec
    }

    /// The flashed model as a firmware calibration (see [`Flashed::calibration`]).
    pub fn calibration(&self, t0: f64) -> Result<Calibration<f64>> {
        self.flashed.calibration(t0, None).map(|(cal, _)| cal)
    }

    /// The discovered terms of the unit's state the blob carries in its term table (see
    /// [`Flashed::terms`]).
    pub fn terms(&self) -> Result<Vec<crate::terms::AxisTerm>> {
        self.flashed.terms()
    }

    /// The 1-sigma of the flashed model's 12 coefficients at temperature `t` (see
    /// [`metrics::coefficient_sigma`]).
    pub fn coefficient_sigma(&self, t: f64) -> [f64; 12] {
        metrics::coefficient_sigma(&self.data, &self.flashed.fit, t)
    }
}

/// Run the diagnosis with the default [`Rules`].
pub fn diagnose(rec: &Recording) -> Result<Diagnosis<'_>> {
    diagnose_with(rec, Rules::default())
}

/// Run the diagnosis with `rules` (see the module doc for the steps).
pub fn diagnose_with(rec: &Recording, rules: Rules) -> Result<Diagnosis<'_>> {
    let Weighed {
        data,
        floor,
        measured,
    } = weighed(rec, rules, Purpose::Diagnosis)?;
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    let n_temps = temperature_clusters(&temps).len();
    let (baseline, mut not_identifiable) = baseline::required(&data)?;
    let scope = scope(&data, measured, n_temps, &mut not_identifiable);
    let z = metrics::z(&data, &baseline);
    let hotspots = locate(&data, &z, &baseline.resid, rules.located_sigmas);
    let mut found = search::run(&data, &baseline, &scope);
    let refined = crate::model::profile::refine_jointly(&data, &found.joint);
    // the sets of discovered terms follow their terms to the refined time constants
    for t in &mut found.term_sets {
        if let Some(i) = found.joint.spec.extras.iter().position(|e| *e == t.extra) {
            t.extra = refined.spec.extras[i].clone();
        }
    }
    found.joint = refined;
    let ambiguous_groups: Vec<Vec<EffectId>> = found
        .ambiguous
        .into_iter()
        .filter(|g| found.joint.spec.extras.iter().any(|e| g.contains(&e.id())))
        .collect();
    let research = found.research;
    let library = found.library;
    let search_ended = found.ended;
    // one line per kind of position that would identify them
    let mut kinds: Vec<(&str, Vec<&str>)> = Vec::new();
    for u in &found.unidentifiable {
        match kinds.iter_mut().find(|(p, _)| *p == u.positions) {
            Some((_, terms)) => terms.push(&u.term),
            None => kinds.push((&u.positions, vec![&u.term])),
        }
    }
    for (positions, terms) in kinds {
        not_identifiable.push(format!(
            "discovered terms {} (and their products): zero, or one of the model's own columns, at these positions; {positions} would identify them",
            terms.join(", ")
        ));
    }
    let term_sets = found.term_sets;
    let (final_fit, findings) = findings_of(&data, found.joint, &ambiguous_groups, &term_sets);
    let mut ambiguous: Vec<Ambiguity> = ambiguous_groups
        .iter()
        .map(|g| Ambiguity {
            candidates: g.clone(),
            terms: Vec::new(),
            needed: findings::needed(g),
        })
        .collect();
    ambiguous.extend(
        term_sets
            .iter()
            .filter(|t| !t.named && final_fit.spec.extras.contains(&t.extra))
            .filter_map(|t| findings::term_set(&t.extra, &t.others)),
    );
    let coupled = coupled::coupled(&data, &final_fit, &findings);
    let unexplained = if metrics::normalized_rms(&data, &final_fit) > rules.at_floor_rms {
        let z = metrics::z(&data, &final_fit);
        locate(&data, &z, &final_fit.resid, rules.located_sigmas)
    } else {
        Vec::new()
    };
    let quality = quality::notes(&quality::Inputs {
        rec,
        floor: &floor,
        obs: &data.obs,
        events: &data.events,
        n_temps,
        rules: &rules,
    });
    let noise_rms = metrics::floor_rms(&data);
    Ok(Diagnosis {
        noise_rms,
        flashed: Flashed::of(&data, &final_fit, noise_rms),
        floor,
        floor_measured: measured,
        baseline,
        final_fit,
        findings,
        ambiguous,
        coupled,
        hotspots,
        unexplained,
        research,
        library,
        search_ended,
        not_identifiable,
        quality,
        data,
    })
}

/// What this recording can judge.
fn scope(data: &Data, measured: bool, n_temps: usize, notes: &mut Vec<String>) -> search::Scope {
    let r = &data.rules;
    let moving = data.rate.iter().any(|v| v.abs() > r.moving_rate_c_per_s);
    let m = r.direction_majority;
    let reversals = data.dir.iter().any(|d| *d > m) && data.dir.iter().any(|d| *d < -m);
    let s = search::Scope {
        temperature: n_temps > 1,
        dynamics: measured && moving && n_temps > 1,
        reversals,
        orders: crate::model::orders::Orders::of(data),
        measured,
    };
    if !s.dynamics {
        notes.push("thermal_lag, temp_rate, warmup_drift, hysteresis: need a time series through temperature changes with a measurable floor".into());
    } else if !s.reversals {
        notes
            .push("hysteresis: needs a temperature visited after heating and after cooling".into());
    }
    if !s.temperature {
        notes.push(
            "temp_curvature and every temperature model: need more than one temperature".into(),
        );
    }
    s
}

/// Findings of the final model (an effect that matters on no axis is dropped and the
/// model refitted).
fn findings_of(
    data: &Data,
    mut f: Fit,
    ambiguous: &[Vec<EffectId>],
    term_sets: &[search::TermSet],
) -> (Fit, Vec<Finding>) {
    'again: loop {
        let mut out = Vec::new();
        let added = findings::profiled_variance(data, &f);
        for e in 0..f.spec.extras.len() {
            let Some(reduced) = search::without(data, &f, e) else {
                continue;
            };
            let id = f.spec.extras[e].id();
            match findings::finding(data, &f, &reduced, e, &added) {
                None => {
                    f = reduced;
                    continue 'again;
                }
                Some(x) => {
                    let set = term_sets.iter().find(|t| t.extra == f.spec.extras[e]);
                    match set {
                        Some(t) if !t.named => {}
                        Some(t) => out.push(Finding {
                            equivalent: t.others.iter().map(ToString::to_string).collect(),
                            ..x
                        }),
                        None if !ambiguous.iter().any(|g| g.contains(&id)) => out.push(x),
                        None => {}
                    }
                }
            }
        }
        return (f, out);
    }
}
