//! Typed parameter ids of the diagnosis's designs: which coefficient's temperature term,
//! which effect term on which axis, which fixture angle. Their text form is the JSON
//! contract's.
use crate::model::units::{Factor, Unit};
use firmware_core::model::AXES;
use std::fmt;

/// A per-axis term of a catalogue effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Term {
    /// `temp_rate`: offset per C/s.
    Rate,
    /// `hysteresis`: offset split by direction.
    Hysteresis,
    /// `hysteresis` on the scale factor: output per g, split by direction.
    HysteresisScale,
    /// `nonlinearity_k2`: output per g^2.
    K2,
    /// `scale_asymmetry`: output per |g| (`c_i = K_ii delta_i`).
    Asymmetry,
    /// `warmup_drift`: offset at the restart.
    Warmup,
    /// `temp_curvature` (bend): offset per C beyond the knot.
    BendOffset,
    /// `temp_curvature` (bend): scale factor per C beyond the knot.
    BendScale,
    /// Not a catalogue effect: the offset drifting linearly in time (per recording span),
    /// the rival a `hysteresis`, a `warmup_drift` or a `temp_curvature` must beat (see
    /// [`crate::diagnose::search`]); never named, never flashed.
    Drift,
    /// Not a catalogue effect: the scale factor drifting linearly in time, beside
    /// [`Term::Drift`] for a hysteresis of the scale factors.
    DriftScale,
    /// A discovered term's coefficient (output units per the term's units).
    Discovered,
}

impl Term {
    /// Every term.
    pub const ALL: [Term; 11] = [
        Term::Rate,
        Term::Hysteresis,
        Term::HysteresisScale,
        Term::K2,
        Term::Asymmetry,
        Term::Warmup,
        Term::BendOffset,
        Term::BendScale,
        Term::Drift,
        Term::DriftScale,
        Term::Discovered,
    ];

    /// The unit of its coefficient: the output unit per the units of what it multiplies.
    pub fn unit(self) -> Unit {
        match self {
            Term::Rate => Unit::output_per(&[Factor::CPerS]),
            Term::Hysteresis | Term::Warmup | Term::Drift => Unit::output(),
            Term::HysteresisScale | Term::Asymmetry | Term::DriftScale => {
                Unit::output_per(&[Factor::G])
            }
            Term::K2 => Unit::Output(vec![(Factor::G, 2)]),
            Term::BendOffset => Unit::output_per(&[Factor::C]),
            Term::BendScale => Unit::output_per(&[Factor::G, Factor::C]),
            // per the term's own factors: the finding's parameters carry it
            // (`Parameters::term_unit`)
            Term::Discovered => Unit::output(),
        }
    }

    /// The term of symbol `s` ([`Term::symbol`]).
    pub fn from_symbol(s: &str) -> Option<Term> {
        Term::ALL.into_iter().find(|t| t.symbol() == s)
    }

    /// The symbol in parameter names (`r_x`, `h_y`, ...).
    pub fn symbol(self) -> &'static str {
        match self {
            Term::Rate => "r",
            Term::Hysteresis => "h",
            Term::HysteresisScale => "hk",
            Term::K2 => "k2",
            Term::Asymmetry => "c",
            Term::Warmup => "d",
            Term::BendOffset => "bend_u0",
            Term::BendScale => "bend_k",
            Term::Drift => "drift",
            Term::DriftScale => "drift_k",
            Term::Discovered => "coefficient",
        }
    }
}

/// One column of a diagnosis design.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Param {
    /// `K[i][j]`, temperature-basis function `k`.
    K {
        /// Row (output axis).
        i: usize,
        /// Column (input axis).
        j: usize,
        /// Basis function.
        k: usize,
    },
    /// `U0[i]`, temperature-basis function `k`.
    U0 {
        /// Axis.
        i: usize,
        /// Basis function.
        k: usize,
    },
    /// A per-axis effect term; `extra` is the index of its effect in the spec.
    Effect {
        /// Which term.
        term: Term,
        /// Axis.
        axis: usize,
        /// The effect's index among the spec's extras.
        extra: usize,
    },
    /// `fixture_error`: rotation angle 1 or 2, rad; `extra` as above.
    FixtureAngle {
        /// 1 or 2.
        n: u8,
        /// The effect's index among the spec's extras.
        extra: usize,
    },
}

impl Param {
    /// The axis of a per-axis effect term.
    pub fn effect_axis(self) -> Option<usize> {
        match self {
            Param::Effect { axis, .. } => Some(axis),
            Param::K { .. } | Param::U0 { .. } | Param::FixtureAngle { .. } => None,
        }
    }

    /// The index of the effect this parameter belongs to (None: the baseline).
    pub fn extra(self) -> Option<usize> {
        match self {
            Param::Effect { extra, .. } | Param::FixtureAngle { extra, .. } => Some(extra),
            Param::K { .. } | Param::U0 { .. } => None,
        }
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ax = |i: usize| AXES.get(i).copied().unwrap_or("?");
        match *self {
            Param::K { i, j, k } => write!(f, "k{}{}#{k}", ax(i), ax(j)),
            Param::U0 { i, k } => write!(f, "u0{}#{k}", ax(i)),
            Param::Effect { term, axis, .. } => write!(f, "{}_{}", term.symbol(), ax(axis)),
            Param::FixtureAngle { n, .. } => write!(f, "angle{n}_rad"),
        }
    }
}
