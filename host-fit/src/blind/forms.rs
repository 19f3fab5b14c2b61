//! The blind suite's cases beyond the catalogue's own forms, written from physics (not
//! from the diagnosis): other forms of each effect, effects outside the catalogue, and
//! clean recordings with the nuisances real data has.
use crate::blind::cases::{axes3, Case, Class};
use crate::rng::Rng;
use crate::simulate::{
    Bend, BiasStep, Fixture, Gradient, PerAxis, Periodic, SimConfig, Stop, Warmup,
};

/// One form.
pub struct Form {
    /// Its class.
    pub class: Class,
    /// Its name.
    pub name: &'static str,
    /// The catalogue effects a correct diagnosis names.
    pub expect: &'static [&'static str],
    /// The data-quality note a correct diagnosis raises (nuisances).
    pub note: Option<&'static str>,
}

const fn form(
    class: Class,
    name: &'static str,
    expect: &'static [&'static str],
    note: Option<&'static str>,
) -> Form {
    Form {
        class,
        name,
        expect,
        note,
    }
}

/// Every form of the suite.
pub const FORMS: [Form; 22] = [
    form(
        Class::OtherForm,
        "thermal_lag: two poles",
        &["thermal_lag"],
        None,
    ),
    form(
        Class::OtherForm,
        "thermal_lag: a time constant per axis",
        &["thermal_lag"],
        None,
    ),
    form(
        Class::OtherForm,
        "temp_rate: a thermal gradient",
        &["temp_rate"],
        None,
    ),
    form(
        Class::OtherForm,
        "hysteresis: cooled before the first change",
        &["hysteresis"],
        None,
    ),
    form(
        Class::OtherForm,
        "hysteresis: switching over 2 C",
        &["hysteresis"],
        None,
    ),
    form(
        Class::OtherForm,
        "hysteresis: of the scale factors",
        &["hysteresis"],
        None,
    ),
    form(
        Class::OtherForm,
        "warmup_drift: two time constants",
        &["warmup_drift"],
        None,
    ),
    form(
        Class::OtherForm,
        "warmup_drift: restarts after a power-off",
        &["warmup_drift"],
        None,
    ),
    form(
        Class::OtherForm,
        "temp_curvature: a local bend",
        &["temp_curvature"],
        None,
    ),
    form(
        Class::OtherForm,
        "fixture_error: two positions off",
        &["fixture_error"],
        None,
    ),
    form(Class::Outside, "a sudden bias shift", &[], None),
    form(Class::Outside, "a random wander of the bias", &[], None),
    form(Class::Outside, "a cubic response (K3)", &[], None),
    form(Class::Outside, "a periodic disturbance", &[], None),
    form(Class::Outside, "scale factors ageing", &[], None),
    form(
        Class::Nuisance,
        "coloured voltage noise",
        &[],
        Some("coloured_noise"),
    ),
    form(Class::Nuisance, "spikes", &[], Some("spikes")),
    form(Class::Nuisance, "logger dropouts", &[], Some("gaps")),
    form(
        Class::Nuisance,
        "a sensor off the chamber",
        &[],
        Some("sensor_vs_chamber"),
    ),
    form(Class::Nuisance, "three heat-cool cycles", &[], None),
    form(
        Class::Nuisance,
        "dwell means only",
        &[],
        Some("one_sample_per_dwell"),
    ),
    form(Class::Nuisance, "a noisy voltmeter", &[], None),
];

fn main_axis(rng: &mut Rng, size: f64) -> [f64; 3] {
    let mut v = [0.0; 3];
    let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
    v[(rng.next_u64() % 3) as usize] = s * size * rng.range(0.7, 1.3);
    v
}

/// Conceal `case`'s form in `c`.
pub fn apply(case: &Case, c: &mut SimConfig, rng: &mut Rng) {
    match case.class {
        Class::OtherForm => other_form(case, c, rng),
        Class::Outside => outside(case, c, rng),
        _ => nuisance(case, c),
    }
}

/// A catalogue effect in another form.
fn other_form(case: &Case, c: &mut SimConfig, rng: &mut Rng) {
    let e = &mut c.effects;
    let s = case.scale;
    match case.form {
        "thermal_lag: two poles" => {
            e.thermal_lag = Some(PerAxis {
                value: [rng.range(200.0, 500.0); 3],
            });
            e.thermal_lag2 = Some(PerAxis {
                value: [rng.range(200.0, 500.0); 3],
            });
        }
        "thermal_lag: a time constant per axis" => {
            let mut v = [300.0, 600.0, 900.0];
            let k = (rng.next_u64() % 3) as usize;
            v.rotate_left(k);
            e.thermal_lag = Some(PerAxis { value: v });
        }
        "temp_rate: a thermal gradient" => {
            let tau = rng.range(60.0, 300.0);
            e.temp_gradient = Some(Gradient {
                value: axes3(rng, s, 0.02 / tau),
                tau_s: tau,
            });
        }
        "hysteresis: cooled before the first change" => {
            e.hysteresis = Some(PerAxis {
                value: axes3(rng, s, 1e-4),
            });
            e.hysteresis_initial = Some(-1.0);
        }
        "hysteresis: switching over 2 C" => {
            e.hysteresis = Some(PerAxis {
                value: axes3(rng, s, 1e-4),
            });
            e.hysteresis_width_c = Some(2.0);
        }
        "hysteresis: of the scale factors" => {
            e.scale_hysteresis = Some(PerAxis {
                value: axes3(rng, s, 3e-4),
            });
        }
        "warmup_drift: two time constants" => {
            e.warmup_drift = Some(Warmup {
                d_v: axes3(rng, s, 2e-4),
                tau_s: rng.range(600.0, 1200.0),
            });
            e.warmup_drift2 = Some(Warmup {
                d_v: axes3(rng, s, 1.5e-4),
                tau_s: rng.range(3000.0, 6000.0),
            });
        }
        "warmup_drift: restarts after a power-off" => {
            e.warmup_drift = Some(Warmup {
                d_v: axes3(rng, s, 2e-4),
                tau_s: rng.range(600.0, 2400.0),
            });
            c.schedule.power_offs = vec![[9000.0, 900.0]];
        }
        "temp_curvature: a local bend" => {
            e.temp_bend = Some(Bend {
                knot_c: rng.range(0.0, 30.0),
                u0_v_per_c: main_axis(rng, 5e-5 * s),
                k_rel_per_c: [0.0; 3],
            });
        }
        "fixture_error: two positions off" => {
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
        _ => {}
    }
}

/// An effect outside the catalogue.
fn outside(case: &Case, c: &mut SimConfig, rng: &mut Rng) {
    let e = &mut c.effects;
    let s = case.scale;
    match case.form {
        "a sudden bias shift" => {
            e.bias_step = Some(BiasStep {
                at_s: rng.range(6000.0, 12000.0),
                value: main_axis(rng, 2e-4 * s),
            })
        }
        "a random wander of the bias" => {
            e.bias_walk = Some(PerAxis {
                value: main_axis(rng, 3e-6 * s),
            })
        }
        "a cubic response (K3)" => {
            e.nonlinearity_k3 = Some(PerAxis {
                value: main_axis(rng, 3e-4 * s),
            })
        }
        "a periodic disturbance" => {
            e.periodic = Some(Periodic {
                period_s: rng.range(1800.0, 3600.0),
                value: main_axis(rng, 1e-4 * s),
            })
        }
        "scale factors ageing" => {
            e.scale_aging = Some(PerAxis {
                value: main_axis(rng, 1e-4 * s),
            })
        }
        _ => {}
    }
}

/// A clean unit with a real-world nuisance.
fn nuisance(case: &Case, c: &mut SimConfig) {
    match case.form {
        "coloured voltage noise" => c.unit.noise_corr_s = 20.0,
        "spikes" => {
            c.unit.spike_rate = 2e-4;
            c.unit.spike_v = 2e-3;
        }
        "logger dropouts" => c.schedule.dropouts = vec![[5000.0, 600.0], [13000.0, 900.0]],
        "a sensor off the chamber" => {
            c.sensor.offset_c = 1.5;
            c.sensor.gain_error = 0.03;
        }
        "three heat-cool cycles" => {
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
        "dwell means only" => c.schedule.dwell_means = true,
        "a noisy voltmeter" => c.unit.noise_v = 1e-4,
        _ => {}
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
        .or(e.scale_aging.map(|p| p.value));
    match v {
        Some(v) => (0..3).filter(|&i| v[i] != 0.0).collect(),
        None => vec![0, 1, 2],
    }
}

/// The data-quality note a nuisance case should raise.
pub fn note(case: &Case) -> Option<&'static str> {
    FORMS
        .iter()
        .find(|f| f.name == case.form)
        .and_then(|f| f.note)
}
