//! The blind suite's cases beyond the catalogue's own forms, written from physics (not
//! from the diagnosis): other forms of each effect, effects outside the catalogue, and
//! clean recordings with the nuisances real data has; and the classes that run on test
//! profiles of their own ([`crate::blind::kinds`]). Each class is its own enum, so every form is concealed by
//! an exhaustive match: a form without physics cannot compile.
use crate::blind::beyond::{Expressed, Plain, Unexpressed};
use crate::blind::designs::Design;
use crate::blind::draw::{axes3, main_axis};
use crate::blind::kinds::{Digital, Mixture, Refixed, Slow};
use crate::blind::profiles::Profile;
use crate::diagnose::quality::NoteKind;
use crate::diagnose::EffectId;
use crate::rng::Rng;
use crate::simulate::{Bend, Fixture, Gradient, PerAxis, SimConfig, Stop, Warmup};

/// What a case tests. Its own name (`blind --class`) is short; [`Class::name`] is the
/// report's.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
pub enum Class {
    /// Catalogue effects in the catalogue's own form (and clean recordings).
    #[strum(serialize = "catalogue")]
    Catalogue,
    /// A catalogue effect in another physically plausible form.
    #[strum(serialize = "other-forms")]
    OtherForm,
    /// An effect outside the catalogue.
    #[strum(serialize = "outside")]
    Outside,
    /// A clean recording with a real-world nuisance.
    #[strum(serialize = "nuisances")]
    Nuisance,
    /// A slow disturbance of the bias with no power-on behind it.
    #[strum(serialize = "slow")]
    SlowDisturbance,
    /// A digital output of a few counts per g.
    #[strum(serialize = "digital")]
    Digital,
    /// A fixture re-clamped between two stops.
    #[strum(serialize = "re-clamped")]
    FixtureChange,
    /// Three catalogue effects at 0.3-1x their nominal sizes.
    #[strum(serialize = "mixtures")]
    Mixture,
    /// Forms outside the catalogue that the term library expresses: named as their
    /// `discovered` term on their axis.
    #[strum(serialize = "discovery-targets")]
    Expressed,
    /// Forms the term library does not express: left unexplained, located.
    #[strum(serialize = "discovery-blind-spots")]
    Unexpressed,
    /// Clean and catalogue-only units on the designs of the two classes above: nothing
    /// discovered.
    #[strum(serialize = "discovery-controls")]
    NoDiscovery,
}

impl Class {
    /// The class's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Class::Catalogue => "catalogue effects, catalogue form",
            Class::OtherForm => "catalogue effects, other forms",
            Class::Outside => "effects outside the catalogue",
            Class::Nuisance => "clean recordings with nuisances",
            Class::SlowDisturbance => "slow disturbances without a power-on",
            Class::Digital => "digital outputs of a few counts per g",
            Class::FixtureChange => "fixtures re-clamped between two stops",
            Class::Mixture => "mixtures of three effects at 0.3-1x nominal",
            Class::Expressed => "discovery targets: forms the term library expresses",
            Class::Unexpressed => "discovery blind spots: forms it does not express",
            Class::NoDiscovery => "discovery controls: clean and catalogue-only units",
        }
    }
}

/// One form of the suite beyond the catalogue's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    /// A catalogue effect in another physically plausible form.
    Other(OtherForm),
    /// An effect outside the catalogue.
    Outside(Outside),
    /// A clean unit with a real-world nuisance.
    Nuisance(Nuisance),
    /// A slow disturbance without a power-on.
    Slow(Slow),
    /// A digital output of a few counts per g.
    Digital(Digital),
    /// A fixture re-clamped between two stops.
    Refixed(Refixed),
    /// Three catalogue effects at once.
    Mixture(Mixture),
    /// A form the term library expresses.
    Expressed(Expressed),
    /// A form the term library does not express.
    Unexpressed(Unexpressed),
    /// A unit with nothing to discover.
    Plain(Plain),
}

/// A catalogue effect in another form.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OtherForm {
    /// thermal_lag through two cascaded poles.
    LagTwoPoles,
    /// thermal_lag with a time constant per axis.
    LagPerAxis,
    /// temp_rate as a thermal gradient across the unit.
    RateGradient,
    /// hysteresis, cooled before the first change.
    HysteresisCooledFirst,
    /// hysteresis switching gradually over 2 C.
    HysteresisWide,
    /// hysteresis of the scale factors.
    HysteresisOfScale,
    /// hysteresis as a play operator: linear over 6-12 C of travel, holding in the band.
    HysteresisPlay,
    /// hysteresis as a Preisach ensemble of relays up to 8-16 C wide.
    HysteresisPreisach,
    /// warmup_drift with two time constants.
    WarmupTwoTimeConstants,
    /// warmup_drift restarting after a power-off.
    WarmupRestarts,
    /// temp_curvature as one local bend.
    CurvatureLocalBend,
    /// fixture_error of two positions.
    FixtureTwoPositions,
}

/// An effect outside the catalogue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outside {
    /// A step of the bias mid-test.
    BiasStep,
    /// A random walk of the bias.
    BiasWander,
    /// A cubic response.
    CubicResponse,
    /// A periodic disturbance.
    Periodic,
    /// Scale factors drifting with time.
    ScaleAgeing,
}

/// A real-world nuisance on a clean unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Nuisance {
    /// Time-correlated voltage noise.
    ColouredNoise,
    /// Spikes in the samples.
    Spikes,
    /// The logger drops out twice.
    Dropouts,
    /// The temperature sensor is off the chamber.
    SensorOffChamber,
    /// Three heating-cooling cycles instead of the profile.
    HeatCoolCycles,
    /// One mean per dwell instead of samples.
    DwellMeans,
    /// A voltmeter five times noisier.
    NoisyVoltmeter,
}

impl Form {
    /// Every form of the suite, in the order of its report.
    pub const ALL: [Form; 24] = [
        Form::Other(OtherForm::LagTwoPoles),
        Form::Other(OtherForm::LagPerAxis),
        Form::Other(OtherForm::RateGradient),
        Form::Other(OtherForm::HysteresisCooledFirst),
        Form::Other(OtherForm::HysteresisWide),
        Form::Other(OtherForm::HysteresisOfScale),
        Form::Other(OtherForm::HysteresisPlay),
        Form::Other(OtherForm::HysteresisPreisach),
        Form::Other(OtherForm::WarmupTwoTimeConstants),
        Form::Other(OtherForm::WarmupRestarts),
        Form::Other(OtherForm::CurvatureLocalBend),
        Form::Other(OtherForm::FixtureTwoPositions),
        Form::Outside(Outside::BiasStep),
        Form::Outside(Outside::BiasWander),
        Form::Outside(Outside::CubicResponse),
        Form::Outside(Outside::Periodic),
        Form::Outside(Outside::ScaleAgeing),
        Form::Nuisance(Nuisance::ColouredNoise),
        Form::Nuisance(Nuisance::Spikes),
        Form::Nuisance(Nuisance::Dropouts),
        Form::Nuisance(Nuisance::SensorOffChamber),
        Form::Nuisance(Nuisance::HeatCoolCycles),
        Form::Nuisance(Nuisance::DwellMeans),
        Form::Nuisance(Nuisance::NoisyVoltmeter),
    ];

    /// The forms of the classes that run on test profiles of their own, in the order of
    /// their report: slow disturbances, digital outputs, re-clamped fixtures, mixtures.
    pub fn on_own_profiles() -> Vec<Form> {
        let mut v: Vec<Form> = Slow::ALL.map(Form::Slow).to_vec();
        v.extend(Digital::ALL.map(Form::Digital));
        v.extend(Refixed::ALL.map(Form::Refixed));
        v.extend(Mixture::ALL.map(Form::Mixture));
        v
    }

    /// Its class.
    pub fn class(self) -> Class {
        match self {
            Form::Other(_) => Class::OtherForm,
            Form::Outside(_) => Class::Outside,
            Form::Nuisance(_) => Class::Nuisance,
            Form::Slow(_) => Class::SlowDisturbance,
            Form::Digital(_) => Class::Digital,
            Form::Refixed(_) => Class::FixtureChange,
            Form::Mixture(_) => Class::Mixture,
            Form::Expressed(_) => Class::Expressed,
            Form::Unexpressed(_) => Class::Unexpressed,
            Form::Plain(_) => Class::NoDiscovery,
        }
    }

    /// The test profile it runs on, for the classes that do not use the suite's own.
    pub fn profile(self, seed: u64) -> Option<Profile> {
        match self {
            Form::Other(_) | Form::Outside(_) | Form::Nuisance(_) => None,
            Form::Expressed(_) | Form::Unexpressed(_) | Form::Plain(_) => None,
            Form::Slow(_) | Form::Digital(_) | Form::Refixed(_) | Form::Mixture(_) => {
                Some(Profile::of_seed(seed))
            }
        }
    }

    /// The design it runs on, for the classes beyond the catalogue (None for the forms on
    /// the suite's own profiles).
    pub fn design(self, seed: u64) -> Option<Design> {
        match self {
            Form::Expressed(f) => Some(f.design(seed)),
            Form::Unexpressed(f) => Some(f.design(seed)),
            Form::Plain(f) => Some(f.design(seed)),
            Form::Other(_)
            | Form::Outside(_)
            | Form::Nuisance(_)
            | Form::Slow(_)
            | Form::Digital(_)
            | Form::Refixed(_)
            | Form::Mixture(_) => None,
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Form::Other(f) => f.name(),
            Form::Outside(f) => f.name(),
            Form::Nuisance(f) => f.name(),
            Form::Slow(f) => f.name(),
            Form::Digital(f) => f.name(),
            Form::Refixed(f) => f.name(),
            Form::Mixture(f) => f.name(),
            Form::Expressed(f) => f.name(),
            Form::Unexpressed(f) => f.name(),
            Form::Plain(f) => f.name(),
        }
    }

    /// The catalogue effects a correct diagnosis names.
    pub fn expect(self) -> &'static [EffectId] {
        match self {
            Form::Other(f) => f.expect(),
            Form::Digital(f) => f.expect(),
            Form::Refixed(_) => &[EffectId::FixtureError],
            Form::Mixture(f) => f.expect(),
            Form::Plain(f) => f.expect(),
            Form::Outside(_) | Form::Nuisance(_) | Form::Slow(_) => &[],
            Form::Expressed(_) | Form::Unexpressed(_) => &[],
        }
    }

    /// The data-quality note a correct diagnosis raises (nuisances).
    pub fn note(self) -> Option<NoteKind> {
        match self {
            Form::Nuisance(f) => f.note(),
            Form::Other(_)
            | Form::Outside(_)
            | Form::Slow(_)
            | Form::Digital(_)
            | Form::Refixed(_)
            | Form::Mixture(_)
            | Form::Expressed(_)
            | Form::Unexpressed(_)
            | Form::Plain(_) => None,
        }
    }

    /// Conceal this form in `c` at magnitude `scale` (1 = the nominal size), its random
    /// sizes, signs and axes drawn from `rng`.
    pub fn apply(self, scale: f64, c: &mut SimConfig, rng: &mut Rng) {
        match self {
            Form::Other(f) => f.apply(scale, c, rng),
            Form::Outside(f) => f.apply(scale, c, rng),
            Form::Nuisance(f) => f.apply(c),
            Form::Slow(f) => f.apply(scale, c, rng),
            Form::Digital(f) => f.apply(c, rng),
            Form::Refixed(f) => f.apply(c, rng),
            Form::Mixture(f) => f.apply(c, rng),
            Form::Expressed(f) => f.apply(c, rng),
            Form::Unexpressed(f) => f.apply(c, rng),
            Form::Plain(f) => f.apply(c, rng),
        }
    }
}

impl OtherForm {
    fn name(self) -> &'static str {
        match self {
            OtherForm::LagTwoPoles => "thermal_lag: two poles",
            OtherForm::LagPerAxis => "thermal_lag: a time constant per axis",
            OtherForm::RateGradient => "temp_rate: a thermal gradient",
            OtherForm::HysteresisCooledFirst => "hysteresis: cooled before the first change",
            OtherForm::HysteresisWide => "hysteresis: switching over 2 C",
            OtherForm::HysteresisOfScale => "hysteresis: of the scale factors",
            OtherForm::HysteresisPlay => "hysteresis: a play operator over 6-12 C",
            OtherForm::HysteresisPreisach => "hysteresis: a Preisach model to 8-16 C",
            OtherForm::WarmupTwoTimeConstants => "warmup_drift: two time constants",
            OtherForm::WarmupRestarts => "warmup_drift: restarts after a power-off",
            OtherForm::CurvatureLocalBend => "temp_curvature: a local bend",
            OtherForm::FixtureTwoPositions => "fixture_error: two positions off",
        }
    }

    fn expect(self) -> &'static [EffectId] {
        match self {
            OtherForm::LagTwoPoles | OtherForm::LagPerAxis => &[EffectId::ThermalLag],
            OtherForm::RateGradient => &[EffectId::TempRate],
            OtherForm::HysteresisCooledFirst
            | OtherForm::HysteresisWide
            | OtherForm::HysteresisOfScale
            | OtherForm::HysteresisPlay
            | OtherForm::HysteresisPreisach => &[EffectId::Hysteresis],
            OtherForm::WarmupTwoTimeConstants | OtherForm::WarmupRestarts => {
                &[EffectId::WarmupDrift]
            }
            OtherForm::CurvatureLocalBend => &[EffectId::TempCurvature],
            OtherForm::FixtureTwoPositions => &[EffectId::FixtureError],
        }
    }

    fn apply(self, s: f64, c: &mut SimConfig, rng: &mut Rng) {
        let e = &mut c.effects;
        match self {
            OtherForm::LagTwoPoles => {
                e.thermal_lag = Some(PerAxis {
                    value: [rng.range(200.0, 500.0); 3],
                });
                e.thermal_lag2 = Some(PerAxis {
                    value: [rng.range(200.0, 500.0); 3],
                });
            }
            OtherForm::LagPerAxis => {
                let mut v = [300.0, 600.0, 900.0];
                let k = (rng.next_u64() % 3) as usize;
                v.rotate_left(k);
                e.thermal_lag = Some(PerAxis { value: v });
            }
            OtherForm::RateGradient => {
                let tau = rng.range(60.0, 300.0);
                e.temp_gradient = Some(Gradient {
                    value: axes3(rng, s, 0.02 / tau),
                    tau_s: tau,
                });
            }
            OtherForm::HysteresisCooledFirst => {
                e.hysteresis = Some(PerAxis {
                    value: axes3(rng, s, 1e-4),
                });
                e.hysteresis_initial = Some(-1.0);
            }
            OtherForm::HysteresisWide => {
                e.hysteresis = Some(PerAxis {
                    value: axes3(rng, s, 1e-4),
                });
                e.hysteresis_width_c = Some(2.0);
            }
            OtherForm::HysteresisPlay => {
                e.hysteresis = Some(PerAxis {
                    value: axes3(rng, s, 1e-4),
                });
                e.hysteresis_play_c = Some(rng.range(6.0, 12.0));
            }
            OtherForm::HysteresisPreisach => {
                e.hysteresis = Some(PerAxis {
                    value: axes3(rng, s, 1e-4),
                });
                e.hysteresis_preisach_c = Some(rng.range(8.0, 16.0));
            }
            OtherForm::HysteresisOfScale => {
                e.scale_hysteresis = Some(PerAxis {
                    value: axes3(rng, s, 3e-4),
                });
            }
            OtherForm::WarmupTwoTimeConstants => {
                e.warmup_drift = Some(Warmup {
                    d_v: axes3(rng, s, 2e-4),
                    tau_s: rng.range(600.0, 1200.0),
                });
                e.warmup_drift2 = Some(Warmup {
                    d_v: axes3(rng, s, 1.5e-4),
                    tau_s: rng.range(3000.0, 6000.0),
                });
            }
            OtherForm::WarmupRestarts => {
                e.warmup_drift = Some(Warmup {
                    d_v: axes3(rng, s, 2e-4),
                    tau_s: rng.range(600.0, 2400.0),
                });
                c.schedule.power_offs = vec![[9000.0, 900.0]];
            }
            OtherForm::CurvatureLocalBend => {
                e.temp_bend = Some(Bend {
                    knot_c: rng.range(0.0, 30.0),
                    u0_v_per_c: main_axis(rng, 5e-5 * s),
                    k_rel_per_c: [0.0; 3],
                });
            }
            OtherForm::FixtureTwoPositions => {
                let angle = |rng: &mut Rng| [rng.range(2e-4, 4e-4) * s, rng.range(-2e-4, 2e-4) * s];
                e.fixture_error = Some(Fixture {
                    position: "TP2".into(),
                    angles_rad: angle(rng),
                });
                e.fixture_error2 = Some(Fixture {
                    position: "PP5".into(),
                    angles_rad: angle(rng),
                });
            }
        }
    }
}

impl Outside {
    fn name(self) -> &'static str {
        match self {
            Outside::BiasStep => "a sudden bias shift",
            Outside::BiasWander => "a random wander of the bias",
            Outside::CubicResponse => "a cubic response (K3)",
            Outside::Periodic => "a periodic disturbance",
            Outside::ScaleAgeing => "scale factors ageing",
        }
    }

    fn apply(self, s: f64, c: &mut SimConfig, rng: &mut Rng) {
        let e = &mut c.effects;
        match self {
            Outside::BiasStep => {
                e.bias_step = Some(crate::simulate::BiasStep {
                    at_s: rng.range(6000.0, 12000.0),
                    value: main_axis(rng, 2e-4 * s),
                    rise_s: 0.0,
                })
            }
            Outside::BiasWander => {
                e.bias_walk = Some(PerAxis {
                    value: main_axis(rng, 3e-6 * s),
                })
            }
            Outside::CubicResponse => {
                e.nonlinearity_k3 = Some(PerAxis {
                    value: main_axis(rng, 3e-4 * s),
                })
            }
            Outside::Periodic => {
                e.periodic = Some(crate::simulate::Periodic {
                    period_s: rng.range(1800.0, 3600.0),
                    value: main_axis(rng, 1e-4 * s),
                    phase_rad: 0.0,
                })
            }
            Outside::ScaleAgeing => {
                e.scale_aging = Some(PerAxis {
                    value: main_axis(rng, 1e-4 * s),
                })
            }
        }
    }
}

impl Nuisance {
    fn name(self) -> &'static str {
        match self {
            Nuisance::ColouredNoise => "coloured voltage noise",
            Nuisance::Spikes => "spikes",
            Nuisance::Dropouts => "logger dropouts",
            Nuisance::SensorOffChamber => "a sensor off the chamber",
            Nuisance::HeatCoolCycles => "three heat-cool cycles",
            Nuisance::DwellMeans => "dwell means only",
            Nuisance::NoisyVoltmeter => "a noisy voltmeter",
        }
    }

    fn note(self) -> Option<NoteKind> {
        match self {
            Nuisance::ColouredNoise => Some(NoteKind::ColouredNoise),
            Nuisance::Spikes => Some(NoteKind::Spikes),
            Nuisance::Dropouts => Some(NoteKind::Gaps),
            Nuisance::SensorOffChamber => Some(NoteKind::SensorVsChamber),
            Nuisance::DwellMeans => Some(NoteKind::OneSamplePerDwell),
            Nuisance::HeatCoolCycles | Nuisance::NoisyVoltmeter => None,
        }
    }

    fn apply(self, c: &mut SimConfig) {
        match self {
            Nuisance::ColouredNoise => c.unit.noise_corr_s = 20.0,
            Nuisance::Spikes => {
                c.unit.spike_rate = 2e-4;
                c.unit.spike_v = 2e-3;
            }
            Nuisance::Dropouts => c.schedule.dropouts = vec![[5000.0, 600.0], [13000.0, 900.0]],
            Nuisance::SensorOffChamber => {
                c.sensor.offset_c = 1.5;
                c.sensor.gain_error = 0.03;
            }
            Nuisance::HeatCoolCycles => {
                let pos = c.schedule.positions.clone();
                c.schedule.stops = [20.0, -20.0, 40.0, -20.0, 40.0, 10.0]
                    .iter()
                    .map(|t| Stop {
                        temp_c: *t,
                        soak_s: 900.0,
                        ramp_c_per_min: 1.5,
                        positions: Some(pos.clone()),
                    })
                    .collect();
            }
            Nuisance::DwellMeans => c.schedule.dwell_means = true,
            Nuisance::NoisyVoltmeter => c.unit.noise_v = 1e-4,
        }
    }
}

/// The axes an outside effect of configuration `c` is on (all three for other cases).
pub fn axes(c: &SimConfig) -> Vec<usize> {
    let e = &c.effects;
    let v = e
        .bias_step
        .map(|b| b.value)
        .or(e.bias_walk.map(|p| p.value))
        .or(e.nonlinearity_k3.map(|p| p.value))
        .or(e.periodic.map(|p| p.value))
        .or(e.scale_aging.map(|p| p.value))
        .or(e.bias_aging.map(|p| p.value))
        .or(e.bias_settle.map(|p| p.value))
        .or(e.telegraph.map(|p| p.value));
    match v {
        Some(v) => (0..3).filter(|&i| v[i] != 0.0).collect(),
        None => vec![0, 1, 2],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blind::cases::Case;
    use crate::blind::config::configure;
    use crate::simulate::simulate;

    /// Every form conceals something: its recording differs from the clean unit's of the
    /// same seed (same noise), so no form silently injects nothing.
    #[test]
    fn every_form_changes_the_twins_recording() {
        let seed = 1;
        let clean = simulate(&configure(&Case::catalogue(vec![], 1.0, seed)), |_| {})
            .unwrap()
            .csv;
        for form in Form::ALL {
            let cfg = configure(&Case::of_form(form, seed));
            let csv = simulate(&cfg, |_| {}).unwrap().csv;
            assert_ne!(
                csv,
                clean,
                "{}: the same recording as a clean unit",
                form.name()
            );
        }
        // these forms run on profiles of their own: against the same profile without
        // effects (a digital clean form conceals nothing but its output unit)
        for form in Form::on_own_profiles() {
            let cfg = configure(&Case::of_form(form, seed));
            let mut bare = cfg.clone();
            bare.effects = crate::simulate::Effects::default();
            let clean_here = matches!(
                form,
                Form::Digital(Digital::Clean20 | Digital::Clean100 | Digital::Clean500)
            );
            if clean_here {
                assert_eq!(cfg, bare, "{}", form.name());
                continue;
            }
            let csv = simulate(&cfg, |_| {}).unwrap().csv;
            let bare_csv = simulate(&bare, |_| {}).unwrap().csv;
            assert_ne!(csv, bare_csv, "{}: nothing concealed", form.name());
        }
    }

    #[test]
    fn form_names_are_distinct() {
        let all: Vec<Form> = Form::ALL
            .into_iter()
            .chain(Form::on_own_profiles())
            .collect();
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert_ne!(a.name(), b.name());
            }
        }
    }
}
