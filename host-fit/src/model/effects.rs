//! The catalogue's effects as candidate extensions of the baseline model, each with the
//! structural unknowns of its form (time constants, thresholds, initial states, restart
//! events, where a bend sits), which the search profiles instead of assuming.
use crate::model::library::LibTerm;
use serde::{Deserialize, Serialize};

/// When a warm-up clock restarts (besides the start of the recording).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Restart {
    /// Only at power-on (the start of the recording).
    Start,
    /// Also after every gap in the recording (the unit was off).
    Gaps,
    /// Also after every handling run (re-mounting disturbs the settled state); in
    /// flight only the power-on part applies.
    Handling,
}

/// An effect added to the baseline model.
#[derive(Debug, Clone, PartialEq)]
pub enum Extra {
    /// `temp_curvature`, broad: the offsets' temperature basis replaced by a fine
    /// piecewise-linear one (breakpoints, C).
    Curvature(Vec<f64>),
    /// `temp_curvature`, local: offsets and scales bend at `knot_c` (a hinge,
    /// `max(0, T - knot)`).
    Bend {
        /// Where the bend sits, C.
        knot_c: f64,
    },
    /// `thermal_lag`: each axis evaluated at its element temperature, up to two cascaded
    /// poles per axis (`[tau1, tau2]`, s; tau2 = 0 is one pole).
    Lag {
        /// Time constants per axis.
        taus: [[f64; 2]; 3],
    },
    /// `temp_rate`: U0_i += r_i dT/dt, the rate estimated as `tau_s` and `centred` say.
    Rate {
        /// The rate estimator, s: negative, the firmware's zero-lag estimator of time
        /// constant `-tau_s` that a blob flies with; positive, a low-pass of `tau_s`
        /// (causal, as the search judges the effect) or, with `centred`, the slope over
        /// `tau_s` on each side that the final model describes the unit's physics with
        /// (`model::regressors::centred_rates`).
        tau_s: f64,
        /// The centred slope (the host's, non-causal) rather than a causal estimator.
        centred: bool,
    },
    /// `hysteresis`: a coefficient depends on the direction of the last temperature
    /// change: offsets (and, with `scale`, scale factors) shift by +-1/2 of a term.
    Hysteresis {
        /// A change larger than this sets the direction, C (a relay); negative `-d`: a
        /// play operator of half-width `d`, the state linear over `2 d` C of travel after
        /// a reversal (a gradual hysteresis; the firmware's encoding,
        /// `firmware_core::inflight::Direction`).
        threshold_c: f64,
        /// The direction before the first such change.
        initial: f64,
        /// Scale factors depend on the direction too.
        scale: bool,
    },
    /// `nonlinearity_k2`: U_i += K2_i a_i^2.
    K2,
    /// `scale_asymmetry`: U_i += c_i |a_i| (c_i = K_ii delta_i).
    Asymmetry,
    /// `fixture_error`: position p rotated by two small angles; with `Some(n)`, only
    /// from stop n on (1-based, n >= 2: the position re-clamped between two stops).
    Fixture(usize, Option<usize>),
    /// `warmup_drift`: U0_i += d_i exp(-t_since_restart / tau).
    Warmup {
        /// Time constant, s.
        tau_s: f64,
        /// Restart events.
        restart: Restart,
    },
    /// `discovered`: a term of the library (not the catalogue's) entering one output
    /// axis additively.
    Discovered {
        /// The term.
        term: LibTerm,
        /// The output axis.
        axis: usize,
    },
}

/// The catalogue's effects (physics-catalogue.md), by their ids; the JSON contract and
/// the text name them by [`EffectId::as_str`].
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    Serialize,
    Deserialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum EffectId {
    /// The coefficients bend between the temperatures more than the baseline follows.
    TempCurvature,
    /// The sensing element lags the temperature sensor.
    ThermalLag,
    /// The offsets depend on the rate of temperature change.
    TempRate,
    /// The coefficients depend on the direction of the last temperature change.
    Hysteresis,
    /// The output grows with the square of the specific force.
    NonlinearityK2,
    /// The scale factors differ for positive and negative specific force.
    ScaleAsymmetry,
    /// A position of the fixture is off its nominal direction.
    FixtureError,
    /// The offsets settle after power-on.
    WarmupDrift,
    /// Not a catalogue effect: a term of the library found in the data
    /// (physics-catalogue.md, "Beyond the catalogue").
    Discovered,
}

impl EffectId {
    /// Every catalogue effect, in the order candidates are tried (a discovered term is
    /// searched for after them).
    pub const ALL: [EffectId; 8] = [
        EffectId::TempCurvature,
        EffectId::ThermalLag,
        EffectId::TempRate,
        EffectId::Hysteresis,
        EffectId::NonlinearityK2,
        EffectId::ScaleAsymmetry,
        EffectId::FixtureError,
        EffectId::WarmupDrift,
    ];

    /// The catalogue id.
    pub fn as_str(self) -> &'static str {
        self.into()
    }

    /// A short name, distinct for every id (column heads).
    pub fn short(self) -> &'static str {
        match self {
            EffectId::TempCurvature => "curv",
            EffectId::ThermalLag => "lag",
            EffectId::TempRate => "rate",
            EffectId::Hysteresis => "hyst",
            EffectId::NonlinearityK2 => "k2",
            EffectId::ScaleAsymmetry => "asym",
            EffectId::FixtureError => "fixt",
            EffectId::WarmupDrift => "warm",
            EffectId::Discovered => "disc",
        }
    }

    /// The effect of catalogue id `s`.
    pub fn parse(s: &str) -> Option<EffectId> {
        s.parse().ok()
    }

    /// How many times the effect may be added (a second warm-up time constant, a second
    /// bend, more than one position off).
    pub fn max_count(self) -> usize {
        match self {
            EffectId::TempCurvature | EffectId::WarmupDrift => 2,
            // each on its axis; the library search limits them (Rules::discover_max_terms)
            EffectId::Discovered => usize::MAX,
            EffectId::FixtureError => 3,
            EffectId::ThermalLag
            | EffectId::TempRate
            | EffectId::Hysteresis
            | EffectId::NonlinearityK2
            | EffectId::ScaleAsymmetry => 1,
        }
    }
}

impl Extra {
    /// The catalogue id.
    pub fn id(&self) -> EffectId {
        match self {
            Extra::Curvature(_) | Extra::Bend { .. } => EffectId::TempCurvature,
            Extra::Lag { .. } => EffectId::ThermalLag,
            Extra::Rate { .. } => EffectId::TempRate,
            Extra::Hysteresis { .. } => EffectId::Hysteresis,
            Extra::K2 => EffectId::NonlinearityK2,
            Extra::Asymmetry => EffectId::ScaleAsymmetry,
            Extra::Warmup { .. } => EffectId::WarmupDrift,
            Extra::Fixture(..) => EffectId::FixtureError,
            Extra::Discovered { .. } => EffectId::Discovered,
        }
    }

    /// How many structural unknowns were profiled to choose this form (they count as
    /// parameters in the information criterion).
    pub fn structural(&self) -> usize {
        match self {
            Extra::Curvature(_) | Extra::K2 | Extra::Asymmetry => 0,
            Extra::Bend { .. } | Extra::Rate { .. } | Extra::Fixture(_, None) => 1,
            // the position and the stop it changed at
            Extra::Fixture(_, Some(_)) => 2,
            Extra::Lag { taus } => {
                let distinct = |k: usize| {
                    let mut v: Vec<f64> = taus.iter().map(|t| t[k]).collect();
                    v.sort_by(f64::total_cmp);
                    v.dedup();
                    v.iter().filter(|t| **t > 0.0).count()
                };
                distinct(0) + distinct(1)
            }
            Extra::Hysteresis { .. } => 2,
            Extra::Warmup { restart, .. } => 1 + usize::from(*restart != Restart::Start),
            // the term chosen from the library, and its decay's time constant
            Extra::Discovered { term, .. } => 1 + usize::from(term.tau_s().is_some()),
        }
    }

    /// The form found, in words (for the report).
    pub fn form(&self) -> String {
        match self {
            Extra::Curvature(b) => format!("offsets bend through {} breakpoints", b.len()),
            Extra::Bend { knot_c } => format!("a bend at {knot_c:.1} C"),
            Extra::Lag { taus } => {
                let poles = if taus.iter().any(|t| t[1] > 0.0) {
                    "two poles"
                } else {
                    "one pole"
                };
                let same = taus.iter().all(|t| *t == taus[0]);
                format!(
                    "{poles}, {}",
                    if same {
                        "one time constant for all axes"
                    } else {
                        "a time constant per axis"
                    }
                )
            }
            Extra::Rate { tau_s, centred } => {
                format!("rate by the {}", fitted_rate_estimator(*tau_s, *centred))
            }
            Extra::Hysteresis {
                threshold_c,
                initial,
                scale,
            } => format!(
                "{} {}; {} before the first change",
                if *scale {
                    "offsets and scale factors"
                } else {
                    "offsets"
                },
                if *threshold_c < 0.0 {
                    format!(
                        "switch linearly over {} C (a play operator)",
                        -2.0 * threshold_c
                    )
                } else {
                    format!("switch after {threshold_c} C")
                },
                if *initial > 0.0 { "heated" } else { "cooled" }
            ),
            Extra::K2 | Extra::Asymmetry => "per axis".into(),
            Extra::Fixture(_, None) => "two small rotations of one position".into(),
            Extra::Fixture(_, Some(n)) => {
                format!("two small rotations of one position from stop {n} on")
            }
            Extra::Discovered { term, axis } => format!(
                "{term} on the {} output{}",
                firmware_core::model::AXES[*axis],
                if term.of_unit() {
                    ""
                } else {
                    " (of the rig or the test: corrects the calibration only)"
                }
            ),
            Extra::Warmup { tau_s, restart } => format!(
                "settles with {tau_s:.0} s after {}",
                match restart {
                    Restart::Start => "power-on",
                    Restart::Gaps => "power-on and each gap",
                    Restart::Handling => "power-on, each gap and each handling",
                }
            ),
        }
    }
}

/// The rate estimator a blob's `rate_tau_s` names, in words: `zero-lag estimator of 4 s`
/// for a negative time constant (`firmware_core::temperature::Physics::rate_zero_lag`),
/// else `4 s low-pass` (the firmware's reading of the sign).
pub fn rate_estimator(tau_s: f64) -> String {
    if tau_s < 0.0 {
        format!("zero-lag estimator of {:.0} s", -tau_s)
    } else {
        format!("{tau_s:.0} s low-pass")
    }
}

/// The rate estimator an [`Extra::Rate`] names, in words: the firmware's reading of its
/// time constant ([`rate_estimator`]), or with `centred` the host's `centred slope over
/// +-40 s` ([`crate::model::regressors::centred_rates`]).
pub fn fitted_rate_estimator(tau_s: f64, centred: bool) -> String {
    if centred {
        format!("centred slope over +-{tau_s:.0} s")
    } else {
        rate_estimator(tau_s)
    }
}

#[cfg(test)]
mod rate_estimator_tests {
    use super::*;

    /// The sign of a blob's rate time constant names the estimator, in words.
    #[test]
    fn the_rate_estimator_is_named_by_its_sign() {
        assert_eq!(rate_estimator(-4.0), "zero-lag estimator of 4 s");
        assert_eq!(rate_estimator(40.0), "40 s low-pass");
        // the final model's centred slope is not a low-pass
        assert_eq!(
            fitted_rate_estimator(40.0, true),
            "centred slope over +-40 s"
        );
        assert_eq!(fitted_rate_estimator(40.0, false), "40 s low-pass");
        assert_eq!(
            fitted_rate_estimator(-4.0, false),
            "zero-lag estimator of 4 s"
        );
    }
}
