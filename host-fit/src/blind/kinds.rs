//! The blind classes that run on test profiles of their own, written from physics (not from the diagnosis): slow
//! disturbances with no power-on behind them, digital outputs of a few counts per g,
//! a fixture re-clamped between two stops, and mixtures of three catalogue effects at
//! 0.3-1x their nominal sizes; all on the profiles of [`crate::blind::profiles`].
use crate::blind::draw::{conceal, main_axis};
use crate::blind::profiles::{stop_spans, Profile};
use crate::data::output_unit::OutputUnit;
use crate::diagnose::EffectId;
use crate::rng::Rng;
use crate::simulate::config::NOMINAL_V_PER_G;
use crate::simulate::{BiasStep, FixtureChange, Output, PerAxis, Periodic, Settle, SimConfig};

/// A slow disturbance of the bias with no power-on behind it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slow {
    /// The bias drifts linearly over the whole test.
    LinearDrift,
    /// A sinusoid of 8-30 h period, of which the test sees a slice.
    SlowSine,
    /// A smooth step of the bias over 1-3 h in mid-test.
    SmoothStep,
    /// A random walk of the bias.
    RandomWalk,
    /// An exponential approach to a new bias that starts mid-test, not at a power-on.
    LateSettle,
}

/// A digital output of a few counts per g, its noise below one count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Digital {
    /// 20 counts per g, clean.
    Clean20,
    /// 100 counts per g, clean.
    Clean100,
    /// 500 counts per g, clean.
    Clean500,
    /// 500 counts per g with a fixture error of 2.5-4 counts (5-8 mrad).
    Fixture500,
}

/// A tilter position re-clamped between two stops (0.3-1x the nominal angle).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refixed {
    /// TP2, re-clamped before stop 2.
    Tp2FromStop2,
    /// PP4, re-clamped before stop 3.
    Pp4FromStop3,
    /// TP5, re-clamped before stop 4.
    Tp5FromStop4,
}

/// Three catalogue effects at once, each at 0.3-1x its nominal size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mixture {
    /// temp_rate, hysteresis and fixture_error.
    RateHysteresisFixture,
    /// warmup_drift, nonlinearity_k2 and temp_curvature.
    WarmupK2Curvature,
    /// thermal_lag, scale_asymmetry and hysteresis.
    LagAsymmetryHysteresis,
    /// fixture_error, warmup_drift and temp_rate.
    FixtureWarmupRate,
}

/// A size of 0.3-1x the nominal, drawn from `rng`.
fn small(rng: &mut Rng) -> f64 {
    rng.range(0.3, 1.0)
}

/// The recording's length under the schedule of `c`, s.
fn length_s(c: &SimConfig) -> f64 {
    stop_spans(c).last().map_or(0.0, |s| s[1])
}

impl Slow {
    /// Every form, in the order of the report.
    pub const ALL: [Slow; 5] = [
        Slow::LinearDrift,
        Slow::SlowSine,
        Slow::SmoothStep,
        Slow::RandomWalk,
        Slow::LateSettle,
    ];

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Slow::LinearDrift => "slow: a linear bias drift",
            Slow::SlowSine => "slow: a sinusoid of 8-30 h",
            Slow::SmoothStep => "slow: a smooth step over 1-3 h",
            Slow::RandomWalk => "slow: a bias random walk",
            Slow::LateSettle => "slow: a settling that starts mid-test",
        }
    }

    /// Conceal it on the seed's profile: one axis, random sign, sizes comparable to a
    /// nominal warm-up (2e-4 V) over the test.
    pub fn apply(self, s: f64, c: &mut SimConfig, rng: &mut Rng) {
        Profile::of_seed(c.seed).apply(c);
        let len = length_s(c);
        let e = &mut c.effects;
        match self {
            Slow::LinearDrift => {
                // about 2e-4 V over a 4 h test, V per hour
                e.bias_aging = Some(PerAxis {
                    value: main_axis(rng, 5e-5 * s),
                });
            }
            Slow::SlowSine => {
                e.periodic = Some(Periodic {
                    period_s: rng.range(8.0, 30.0) * 3600.0,
                    value: main_axis(rng, 2e-4 * s),
                    phase_rad: rng.range(0.0, std::f64::consts::TAU),
                });
            }
            Slow::SmoothStep => {
                e.bias_step = Some(BiasStep {
                    at_s: len * rng.range(0.4, 0.6),
                    value: main_axis(rng, 2e-4 * s),
                    rise_s: rng.range(3600.0, 10800.0),
                });
            }
            Slow::RandomWalk => {
                e.bias_walk = Some(PerAxis {
                    value: main_axis(rng, 2e-6 * s),
                });
            }
            Slow::LateSettle => {
                e.bias_settle = Some(Settle {
                    at_s: len * rng.range(0.3, 0.6),
                    value: main_axis(rng, 2e-4 * s),
                    tau_s: rng.range(1200.0, 3600.0),
                });
            }
        }
    }
}

impl Digital {
    /// Every form, in the order of the report.
    pub const ALL: [Digital; 4] = [
        Digital::Clean20,
        Digital::Clean100,
        Digital::Clean500,
        Digital::Fixture500,
    ];

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Digital::Clean20 => "digital: 20 counts/g, clean",
            Digital::Clean100 => "digital: 100 counts/g, clean",
            Digital::Clean500 => "digital: 500 counts/g, clean",
            Digital::Fixture500 => "digital: 500 counts/g, fixture_error",
        }
    }

    /// The catalogue effects a correct diagnosis names.
    pub fn expect(self) -> &'static [EffectId] {
        match self {
            Digital::Clean20 | Digital::Clean100 | Digital::Clean500 => &[],
            Digital::Fixture500 => &[EffectId::FixtureError],
        }
    }

    /// Counts per g.
    pub fn counts_per_g(self) -> f64 {
        match self {
            Digital::Clean20 => 20.0,
            Digital::Clean100 => 100.0,
            Digital::Clean500 | Digital::Fixture500 => 500.0,
        }
    }

    /// Conceal it on the seed's profile: the output in whole counts (the twin's 2e-5 V
    /// noise is 0.02 count at 500 counts/g); the fixture error tilts a position by
    /// 5-8 mrad, 2.5-4 counts across it, above the half-count quantisation.
    pub fn apply(self, c: &mut SimConfig, rng: &mut Rng) {
        Profile::of_seed(c.seed).apply(c);
        c.output = Output {
            unit: OutputUnit::Counts,
            per_v: self.counts_per_g() / NOMINAL_V_PER_G,
            quantum: 1.0,
        };
        match self {
            Digital::Clean20 | Digital::Clean100 | Digital::Clean500 => {}
            Digital::Fixture500 => {
                let p = ["TP2", "TP3", "TP5", "PP1", "PP4"][(rng.next_u64() % 5) as usize];
                let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                c.effects.fixture_error = Some(crate::simulate::Fixture {
                    position: p.into(),
                    angles_rad: [sign * rng.range(5e-3, 8e-3), rng.range(-2e-3, 2e-3)],
                });
            }
        }
    }
}

impl Refixed {
    /// Every form, in the order of the report.
    pub const ALL: [Refixed; 3] = [
        Refixed::Tp2FromStop2,
        Refixed::Pp4FromStop3,
        Refixed::Tp5FromStop4,
    ];

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Refixed::Tp2FromStop2 => "re-clamped: TP2 from stop 2 on",
            Refixed::Pp4FromStop3 => "re-clamped: PP4 from stop 3 on",
            Refixed::Tp5FromStop4 => "re-clamped: TP5 from stop 4 on",
        }
    }

    /// The position re-clamped and the stop (1-based) from which on it is off.
    pub fn where_when(self) -> (&'static str, usize) {
        match self {
            Refixed::Tp2FromStop2 => ("TP2", 2),
            Refixed::Pp4FromStop3 => ("PP4", 3),
            Refixed::Tp5FromStop4 => ("TP5", 4),
        }
    }

    /// Conceal it on the seed's profile: at its nominal orientation until the end of
    /// the stop before, then tilted by 0.3-1x the nominal 3e-4 rad (at the start of the
    /// ramp, as when the chamber is opened between two stops).
    pub fn apply(self, c: &mut SimConfig, rng: &mut Rng) {
        Profile::of_seed(c.seed).apply(c);
        let (position, stop) = self.where_when();
        let spans = stop_spans(c);
        let at_s = spans.get(stop - 1).map_or(0.0, |s| s[0]) + 60.0;
        let s = small(rng);
        let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
        c.effects.fixture_change = Some(FixtureChange {
            position: position.into(),
            before_rad: [0.0; 2],
            angles_rad: [
                sign * 3e-4 * s * rng.range(0.8, 1.2),
                rng.range(-1e-4, 1e-4) * s,
            ],
            at_s,
        });
    }
}

impl Mixture {
    /// Every form, in the order of the report.
    pub const ALL: [Mixture; 4] = [
        Mixture::RateHysteresisFixture,
        Mixture::WarmupK2Curvature,
        Mixture::LagAsymmetryHysteresis,
        Mixture::FixtureWarmupRate,
    ];

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Mixture::RateHysteresisFixture => "mixture: temp_rate+hysteresis+fixture_error",
            Mixture::WarmupK2Curvature => "mixture: warmup_drift+nonlinearity_k2+temp_curvature",
            Mixture::LagAsymmetryHysteresis => "mixture: thermal_lag+scale_asymmetry+hysteresis",
            Mixture::FixtureWarmupRate => "mixture: fixture_error+warmup_drift+temp_rate",
        }
    }

    /// The three effects concealed.
    pub fn expect(self) -> &'static [EffectId] {
        match self {
            Mixture::RateHysteresisFixture => &[
                EffectId::TempRate,
                EffectId::Hysteresis,
                EffectId::FixtureError,
            ],
            Mixture::WarmupK2Curvature => &[
                EffectId::WarmupDrift,
                EffectId::NonlinearityK2,
                EffectId::TempCurvature,
            ],
            Mixture::LagAsymmetryHysteresis => &[
                EffectId::ThermalLag,
                EffectId::ScaleAsymmetry,
                EffectId::Hysteresis,
            ],
            Mixture::FixtureWarmupRate => &[
                EffectId::FixtureError,
                EffectId::WarmupDrift,
                EffectId::TempRate,
            ],
        }
    }

    /// Conceal the three in their catalogue forms on the seed's profile, each at its own
    /// 0.3-1x of the nominal size (a lag's time constant is drawn as in the catalogue
    /// class).
    pub fn apply(self, c: &mut SimConfig, rng: &mut Rng) {
        Profile::of_seed(c.seed).apply(c);
        for e in self.expect() {
            let s = small(rng);
            conceal(*e, s, c, rng);
        }
    }
}
