//! The blind suite's cases: what each tests, its name, and the test profile.
use crate::diagnose::EFFECT_IDS;
use crate::rng::Rng;
use crate::simulate::{SimConfig, Stop};

/// Every catalogue effect the simulator conceals.
pub const EFFECTS: [&str; 8] = EFFECT_IDS;

/// What a case tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    /// Catalogue effects in the catalogue's own form (and clean recordings).
    Catalogue,
    /// A catalogue effect in another physically plausible form.
    OtherForm,
    /// An effect outside the catalogue.
    Outside,
    /// A clean recording with a real-world nuisance.
    Nuisance,
}

impl Class {
    /// The class's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Class::Catalogue => "catalogue effects, catalogue form",
            Class::OtherForm => "catalogue effects, other forms",
            Class::Outside => "effects outside the catalogue",
            Class::Nuisance => "clean recordings with nuisances",
        }
    }
}

/// One blind case.
#[derive(Debug, Clone)]
pub struct Case {
    /// What it tests.
    pub class: Class,
    /// The form concealed (classes other than the catalogue's), a [`forms`] name.
    pub form: &'static str,
    /// The effects expected to be named (catalogue ids); empty = none.
    pub effects: Vec<&'static str>,
    /// Magnitude in units of the effect's nominal size (1 = clearly visible).
    pub scale: f64,
    /// Seed of the simulation and of the random axes/signs.
    pub seed: u64,
    /// Only TP positions (then k2 and asymmetry cannot be told apart).
    pub tp_only: bool,
}

impl Case {
    /// A catalogue case: `effects` in the catalogue's form.
    pub fn catalogue(effects: Vec<&'static str>, scale: f64, seed: u64) -> Case {
        Case {
            class: Class::Catalogue,
            form: "",
            effects,
            scale,
            seed,
            tp_only: false,
        }
    }

    /// The case's name in reports.
    pub fn name(&self) -> String {
        let base = if !self.form.is_empty() {
            self.form.to_string()
        } else if self.effects.is_empty() {
            "clean".to_string()
        } else {
            self.effects.join("+")
        };
        base + if self.tp_only { " (TP only)" } else { "" }
    }
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

/// Per-axis sizes: one or two axes, random signs, 0.7..1.3 of `size` times `scale`.
pub fn axes3(rng: &mut Rng, scale: f64, size: f64) -> [f64; 3] {
    // one or two axes, random signs, 0.7..1.3 of the size
    let main = (rng.next_u64() % 3) as usize;
    let mut v = [0.0; 3];
    for (i, x) in v.iter_mut().enumerate() {
        if i == main || rng.uniform() < 0.3 {
            let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            *x = s * size * scale * rng.range(0.7, 1.3);
        }
    }
    v
}
