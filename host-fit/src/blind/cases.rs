//! The blind suite's cases: what each tests, its name, and the test profile.
use crate::blind::forms::{Class, Form};
use crate::diagnose::EffectId;
use crate::simulate::{SimConfig, Stop};

/// Every catalogue effect the simulator conceals.
pub const EFFECTS: [EffectId; 8] = EffectId::ALL;

/// One blind case.
#[derive(Debug, Clone)]
pub struct Case {
    /// The form concealed; None: the catalogue's own forms of [`Case::effects`].
    pub form: Option<Form>,
    /// The effects expected to be named; empty = none.
    pub effects: Vec<EffectId>,
    /// Magnitude in units of the effect's nominal size (1 = clearly visible).
    pub scale: f64,
    /// Seed of the simulation and of the random axes/signs.
    pub seed: u64,
    /// Only TP positions (then k2 and asymmetry cannot be told apart).
    pub tp_only: bool,
}

impl Case {
    /// A catalogue case: `effects` in the catalogue's form.
    pub fn catalogue(effects: Vec<EffectId>, scale: f64, seed: u64) -> Case {
        Case {
            form: None,
            effects,
            scale,
            seed,
            tp_only: false,
        }
    }

    /// A case of `form` at its nominal size.
    pub fn of_form(form: Form, seed: u64) -> Case {
        Case {
            form: Some(form),
            effects: form.expect().to_vec(),
            scale: 1.0,
            seed,
            tp_only: false,
        }
    }

    /// What it tests.
    pub fn class(&self) -> Class {
        self.form.map_or(Class::Catalogue, Form::class)
    }

    /// The case's name in reports.
    pub fn name(&self) -> String {
        let base = match self.form {
            Some(f) => f.name().to_string(),
            None if self.effects.is_empty() => "clean".to_string(),
            None => self
                .effects
                .iter()
                .map(|e| e.as_str())
                .collect::<Vec<_>>()
                .join("+"),
        };
        let profile = self
            .form
            .and_then(|f| f.profile(self.seed))
            .map(|p| p.name().to_string())
            .or_else(|| self.form?.design(self.seed).map(|d| d.name()))
            .map_or(String::new(), |p| format!(" [{p}]"));
        base + if self.tp_only { " (TP only)" } else { "" } + &profile
    }
}

/// The cases of these classes: every form on seeds 1-4 (`long`), or one of each class
/// on seed 1 (a product term, a jumping bias beside a power cycle, a fixture error of a
/// new position).
pub fn discovery_cases(long: bool) -> Vec<Case> {
    use crate::blind::beyond::{Expressed, Plain, Unexpressed};
    let forms: Vec<Form> = if long {
        Expressed::ALL
            .map(Form::Expressed)
            .into_iter()
            .chain(Unexpressed::ALL.map(Form::Unexpressed))
            .chain(Plain::ALL.map(Form::Plain))
            .collect()
    } else {
        vec![
            Form::Expressed(Expressed::CrossCoupling),
            Form::Unexpressed(Unexpressed::Telegraph),
            Form::Plain(Plain::FixtureProducts),
        ]
    };
    let seeds: Vec<u64> = if long { (1..=4).collect() } else { vec![1] };
    let mut v = Vec::new();
    for &seed in &seeds {
        v.extend(forms.iter().map(|f| Case::of_form(*f, seed)));
    }
    v
}

/// The short test profile: 20 -> -20 -> 10 -> 40 -> 10 C (the last stop reached by
/// cooling), TP1..TP6 and PP1..PP6 at each, 1 C/min ramps, 20 min soaks.
pub fn profile(tp_only: bool) -> SimConfig {
    let mut c = SimConfig::default();
    c.unit.serial = "BLIND".into();
    let pos: Vec<String> = if tp_only {
        (1..=6).map(|i| format!("TP{i}")).collect()
    } else {
        c.schedule.positions.clone()
    };
    c.schedule.stops = stops(&[20.0, -20.0, 10.0, 40.0, 10.0], &pos);
    c.schedule.positions = pos;
    c
}

/// The profile's stops at `temps`: every position in `positions`, 1 C/min ramps, 20 min
/// soaks.
pub fn stops(temps: &[f64], positions: &[String]) -> Vec<Stop> {
    temps
        .iter()
        .map(|t| Stop {
            temp_c: *t,
            soak_s: 1200.0,
            ramp_c_per_min: 1.0,
            positions: Some(positions.to_vec()),
        })
        .collect()
}
