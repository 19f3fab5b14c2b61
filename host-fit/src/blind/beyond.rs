//! The classes beyond the catalogue, written from physics (not from the diagnosis's term
//! search): forms the term library expresses (each must be named as its `discovered`
//! term on its axis), forms it does not express (each must stay unexplained, located on
//! its axis), and clean and catalogue-only units on the same designs (nothing may be
//! discovered there). Each runs on a design of [`crate::blind::designs`] that identifies
//! what it needs; its size is drawn per seed at 0.5-2x a nominal size whose visible part
//! is about 10x the floor (the window means' scatter, about 5e-6 V on the twin).
use crate::blind::designs::{Design, PositionSet, Power};
use crate::blind::draw::conceal;
use crate::blind::terms::Term;
use crate::diagnose::EffectId;
use crate::rng::Rng;
use crate::simulate::{
    Fixture, PerAxis, Periodic, Quadratic, Relaxation, Repeatability, SimConfig, Telegraph,
    TempWarmup, TurnOn,
};

/// A form outside the catalogue that a short product of measured factors expresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expressed {
    /// IEEE 1293 cross-coupling: `a_i a_j` on output i (Kip, Kio).
    CrossCoupling,
    /// A cubic response K3 `a_i^3`.
    Cubic,
    /// A cross-axis square: `a_j^2` on output i (Kpp, Koo).
    CrossSquare,
    /// The signal chain settles after each tilter move: `decay(position,TAU)`.
    MoveSettle,
    /// Turn-on to turn-on repeatability across one power cycle: `step(power_on)`.
    TurnOnStep,
    /// The scale factor drifts through the test: `a_i*t`.
    ScaleDrift,
    /// K2 with a temperature coefficient: `a_i^2*dT`.
    K2OfTemperature,
    /// The scale factor moves with the rate of temperature change: `a_i*dTdt`.
    ScaleOfRate,
    /// A turn-on transient sized by the distance from T0: `dT*decay(power_on,TAU)`.
    WarmupOfTemperature,
    /// The signal chain settles after each new stop: `decay(stop,TAU)`.
    StopSettle,
}

/// A form that no short sum of the library's terms expresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unexpressed {
    /// A random walk of the bias, with power cycles (a walk is no warm-up).
    BiasWalk,
    /// A periodic disturbance of 20-60 min.
    Periodic,
    /// The tilter's repeatability: each rest a fresh small rotation.
    TilterRepeatability,
    /// A bias jumping between two levels at random times, with a power cycle.
    Telegraph,
}

/// A unit with nothing to discover on a design of the new classes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plain {
    /// Clean, on a product design.
    CleanProducts,
    /// Clean, power cycled (mid-stop on odd seeds, at -20 and 40 C on even ones).
    CleanPowerCycles,
    /// Clean, turning through the ramps.
    CleanTurning,
    /// nonlinearity_k2 on a product design (not `a_i^2`).
    K2Products,
    /// scale_asymmetry on a product design (not `abs(a_i)`).
    AsymmetryProducts,
    /// fixture_error of an edge or corner position (not a product term).
    FixtureProducts,
    /// warmup_drift restarting at two power cycles (not `decay(power_on,TAU)`).
    WarmupRestarts,
    /// thermal_lag and temp_rate, turning through the ramps (not `a_i*dTdt`).
    LagRateTurning,
    /// hysteresis with a power cycle mid-stop (not `step(power_on)`).
    HysteresisPowerCycle,
}

/// The random numbers of one form's case: the suite's stream of the seed (`rng`) mixed
/// with the form's place, so that forms do not share their draws (sizes, axes, signs).
fn stream(rng: &mut Rng, class: u64, index: usize) -> Rng {
    Rng::new(
        rng.next_u64() ^ (class << 32) ^ (index as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
    )
}

/// A size of 0.5-2x `nominal`, random sign.
fn size(rng: &mut Rng, nominal: f64) -> f64 {
    let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
    s * nominal * rng.range(0.5, 2.0)
}

/// A random axis.
fn axis(rng: &mut Rng) -> usize {
    (rng.next_u64() % 3) as usize
}

/// `v` on axis `i`, zero on the others.
fn on(i: usize, v: f64) -> [f64; 3] {
    let mut a = [0.0; 3];
    a[i] = v;
    a
}

/// The column of `a_i a_j` (i != j) in [`Quadratic`]'s rows.
fn pair_column(i: usize, j: usize) -> usize {
    match (i.min(j), i.max(j)) {
        (0, 1) => 3,
        (0, 2) => 4,
        _ => 5,
    }
}

/// The product design of a seed, no power cycle.
fn products(seed: u64) -> Design {
    Design {
        positions: PositionSet::of_seed(seed),
        ..Design::STANDARD
    }
}

/// The standard positions with `power`.
fn powered(power: Power) -> Design {
    Design {
        power,
        ..Design::STANDARD
    }
}

/// The standard positions, turning through the ramps.
const TURNING: Design = Design {
    turning: true,
    ..Design::STANDARD
};

impl Expressed {
    /// Every form, in the order of the report.
    pub const ALL: [Expressed; 10] = [
        Expressed::CrossCoupling,
        Expressed::Cubic,
        Expressed::CrossSquare,
        Expressed::MoveSettle,
        Expressed::TurnOnStep,
        Expressed::ScaleDrift,
        Expressed::K2OfTemperature,
        Expressed::ScaleOfRate,
        Expressed::WarmupOfTemperature,
        Expressed::StopSettle,
    ];

    /// Its place in [`Expressed::ALL`] (an exhaustive match: a new form must be listed).
    pub fn index(self) -> usize {
        match self {
            Expressed::CrossCoupling => 0,
            Expressed::Cubic => 1,
            Expressed::CrossSquare => 2,
            Expressed::MoveSettle => 3,
            Expressed::TurnOnStep => 4,
            Expressed::ScaleDrift => 5,
            Expressed::K2OfTemperature => 6,
            Expressed::ScaleOfRate => 7,
            Expressed::WarmupOfTemperature => 8,
            Expressed::StopSettle => 9,
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Expressed::CrossCoupling => "term: cross-coupling a_i*a_j (IEEE 1293)",
            Expressed::Cubic => "term: a cubic response a_i^3",
            Expressed::CrossSquare => "term: a cross-axis square a_j^2",
            Expressed::MoveSettle => "term: settling after each move",
            Expressed::TurnOnStep => "term: a bias step at a power cycle",
            Expressed::ScaleDrift => "term: a scale drifting in time a_i*t",
            Expressed::K2OfTemperature => "term: K2 with temperature a_i^2*dT",
            Expressed::ScaleOfRate => "term: a scale with the rate a_i*dTdt",
            Expressed::WarmupOfTemperature => "term: a warm-up sized by dT",
            Expressed::StopSettle => "term: settling after each stop",
        }
    }

    /// The design it runs on.
    pub fn design(self, seed: u64) -> Design {
        match self {
            Expressed::CrossCoupling | Expressed::Cubic | Expressed::CrossSquare => products(seed),
            Expressed::TurnOnStep => powered(Power::MidStop),
            Expressed::WarmupOfTemperature => powered(Power::AtStops),
            Expressed::ScaleOfRate => TURNING,
            Expressed::MoveSettle
            | Expressed::ScaleDrift
            | Expressed::K2OfTemperature
            | Expressed::StopSettle => Design::STANDARD,
        }
    }

    /// Conceal it on its design, on one random axis, at 0.5-2x its nominal size. The
    /// nominal sizes are set so that even half of one leaves the baseline's residual
    /// clearly above the floor (5e-6 V) on its design: cross-coupling 2e-4 V/g^2 (1e-4 V
    /// at an edge), K3 3e-4 V/g^3, a cross square 1.2e-4 V/g^2, a settling after a move of
    /// 3e-4 V with 30-60 s, a turn-on step of 8e-5 V, a scale drift of 5e-5 per hour, K2
    /// of 6e-6 V/g^2 per C, a scale of 2e-4 per C/min, a warm-up of 6e-6 V per C from T0
    /// with 10-25 min, a settling after a stop of 1.5e-4 V with 15-30 min.
    pub fn apply(self, c: &mut SimConfig, rng: &mut Rng) {
        self.design(c.seed).apply(c);
        let rng = &mut stream(rng, 1, self.index());
        let i = axis(rng);
        let e = &mut c.effects;
        match self {
            Expressed::CrossCoupling | Expressed::CrossSquare => {
                let j = (i + 1 + (rng.next_u64() % 2) as usize) % 3;
                let mut q = [[0.0; 6]; 3];
                if self == Expressed::CrossCoupling {
                    q[i][pair_column(i, j)] = size(rng, 2e-4);
                } else {
                    q[i][j] = size(rng, 1.2e-4);
                }
                e.quadratic = Some(Quadratic { value: q });
            }
            Expressed::Cubic => {
                e.nonlinearity_k3 = Some(PerAxis {
                    value: on(i, size(rng, 3e-4)),
                })
            }
            Expressed::MoveSettle => {
                e.move_settle = Some(Relaxation {
                    d_v: on(i, size(rng, 3e-4)),
                    tau_s: rng.range(30.0, 60.0),
                })
            }
            Expressed::TurnOnStep => {
                e.turn_on_bias = Some(TurnOn {
                    value: vec![on(i, size(rng, 8e-5))],
                })
            }
            Expressed::ScaleDrift => {
                e.scale_aging = Some(PerAxis {
                    value: on(i, size(rng, 5e-5)),
                })
            }
            Expressed::K2OfTemperature => {
                e.k2_temp = Some(PerAxis {
                    value: on(i, size(rng, 6e-6)),
                })
            }
            Expressed::ScaleOfRate => {
                e.scale_rate = Some(PerAxis {
                    value: on(i, size(rng, 2e-4)),
                })
            }
            Expressed::WarmupOfTemperature => {
                e.warmup_temp = Some(TempWarmup {
                    v_per_c: on(i, size(rng, 6e-6)),
                    tau_s: rng.range(600.0, 1500.0),
                })
            }
            Expressed::StopSettle => {
                e.stop_settle = Some(Relaxation {
                    d_v: on(i, size(rng, 1.5e-4)),
                    tau_s: rng.range(900.0, 1800.0),
                })
            }
        }
    }
}

impl Unexpressed {
    /// Every form, in the order of the report.
    pub const ALL: [Unexpressed; 4] = [
        Unexpressed::BiasWalk,
        Unexpressed::Periodic,
        Unexpressed::TilterRepeatability,
        Unexpressed::Telegraph,
    ];

    /// Its place in [`Unexpressed::ALL`] (an exhaustive match: a new form must be listed).
    pub fn index(self) -> usize {
        match self {
            Unexpressed::BiasWalk => 0,
            Unexpressed::Periodic => 1,
            Unexpressed::TilterRepeatability => 2,
            Unexpressed::Telegraph => 3,
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Unexpressed::BiasWalk => "no term: a bias random walk, power cycled",
            Unexpressed::Periodic => "no term: a periodic disturbance of 20-60 min",
            Unexpressed::TilterRepeatability => "no term: the tilter's repeatability",
            Unexpressed::Telegraph => "no term: a two-level bias (telegraph)",
        }
    }

    /// The design it runs on: each where the library has a near miss to offer (power-ons
    /// for a walk or a jumping bias, products for random rotations).
    pub fn design(self, seed: u64) -> Design {
        match self {
            Unexpressed::BiasWalk => powered(Power::AtStops),
            Unexpressed::Periodic => Design::STANDARD,
            Unexpressed::TilterRepeatability => products(seed),
            Unexpressed::Telegraph => powered(Power::MidStop),
        }
    }

    /// Conceal it on its design at 0.5-2x its nominal size, set as the targets' are: a
    /// walk of 8e-7 V/sqrt(s) (about 1.2e-4 V over the test), a sinusoid of 5e-5 V,
    /// rotations of 6e-5 rad (1 sigma, 3.3e-5 V across the axis), a telegraph of 6e-5 V
    /// held 20-60 min.
    pub fn apply(self, c: &mut SimConfig, rng: &mut Rng) {
        self.design(c.seed).apply(c);
        let rng = &mut stream(rng, 2, self.index());
        let i = axis(rng);
        let e = &mut c.effects;
        match self {
            Unexpressed::BiasWalk => {
                e.bias_walk = Some(PerAxis {
                    value: on(i, size(rng, 8e-7).abs()),
                })
            }
            Unexpressed::Periodic => {
                e.periodic = Some(Periodic {
                    period_s: rng.range(1200.0, 3600.0),
                    value: on(i, size(rng, 5e-5)),
                    phase_rad: rng.range(0.0, std::f64::consts::TAU),
                })
            }
            Unexpressed::TilterRepeatability => {
                e.tilter_repeatability = Some(Repeatability {
                    sigma_rad: size(rng, 6e-5).abs(),
                })
            }
            Unexpressed::Telegraph => {
                e.telegraph = Some(Telegraph {
                    value: on(i, size(rng, 6e-5)),
                    mean_s: rng.range(1200.0, 3600.0),
                })
            }
        }
    }
}

impl Plain {
    /// Every form, in the order of the report.
    pub const ALL: [Plain; 9] = [
        Plain::CleanProducts,
        Plain::CleanPowerCycles,
        Plain::CleanTurning,
        Plain::K2Products,
        Plain::AsymmetryProducts,
        Plain::FixtureProducts,
        Plain::WarmupRestarts,
        Plain::LagRateTurning,
        Plain::HysteresisPowerCycle,
    ];

    /// Its place in [`Plain::ALL`] (an exhaustive match: a new form must be listed).
    pub fn index(self) -> usize {
        match self {
            Plain::CleanProducts => 0,
            Plain::CleanPowerCycles => 1,
            Plain::CleanTurning => 2,
            Plain::K2Products => 3,
            Plain::AsymmetryProducts => 4,
            Plain::FixtureProducts => 5,
            Plain::WarmupRestarts => 6,
            Plain::LagRateTurning => 7,
            Plain::HysteresisPowerCycle => 8,
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Plain::CleanProducts => "nothing to discover: clean, products",
            Plain::CleanPowerCycles => "nothing to discover: clean, power cycled",
            Plain::CleanTurning => "nothing to discover: clean, turning",
            Plain::K2Products => "nothing to discover: nonlinearity_k2",
            Plain::AsymmetryProducts => "nothing to discover: scale_asymmetry",
            Plain::FixtureProducts => "nothing to discover: fixture_error",
            Plain::WarmupRestarts => "nothing to discover: warmup_drift",
            Plain::LagRateTurning => "nothing to discover: thermal_lag+temp_rate",
            Plain::HysteresisPowerCycle => "nothing to discover: hysteresis",
        }
    }

    /// The catalogue effects a correct diagnosis names.
    pub fn expect(self) -> &'static [EffectId] {
        match self {
            Plain::CleanProducts | Plain::CleanPowerCycles | Plain::CleanTurning => &[],
            Plain::K2Products => &[EffectId::NonlinearityK2],
            Plain::AsymmetryProducts => &[EffectId::ScaleAsymmetry],
            Plain::FixtureProducts => &[EffectId::FixtureError],
            Plain::WarmupRestarts => &[EffectId::WarmupDrift],
            Plain::LagRateTurning => &[EffectId::ThermalLag, EffectId::TempRate],
            Plain::HysteresisPowerCycle => &[EffectId::Hysteresis],
        }
    }

    /// The design it runs on: each where a discovered term would be the catalogue
    /// effect's look-alike.
    pub fn design(self, seed: u64) -> Design {
        match self {
            Plain::CleanProducts
            | Plain::K2Products
            | Plain::AsymmetryProducts
            | Plain::FixtureProducts => products(seed),
            Plain::CleanPowerCycles if seed % 2 == 1 => powered(Power::MidStop),
            Plain::CleanPowerCycles | Plain::WarmupRestarts => powered(Power::AtStops),
            Plain::CleanTurning | Plain::LagRateTurning => TURNING,
            Plain::HysteresisPowerCycle => powered(Power::MidStop),
        }
    }

    /// Conceal its catalogue effects in their catalogue forms at 0.5-2x their nominal
    /// sizes (a fixture error at one of the design's own new positions).
    pub fn apply(self, c: &mut SimConfig, rng: &mut Rng) {
        let design = self.design(c.seed);
        design.apply(c);
        let rng = &mut stream(rng, 3, self.index());
        if self == Plain::FixtureProducts {
            let extra = design.positions.extra();
            let (name, _) = &extra[(rng.next_u64() as usize) % extra.len()];
            let s = rng.range(0.5, 2.0);
            c.effects.fixture_error = Some(Fixture {
                position: name.clone(),
                angles_rad: [
                    rng.range(-2e-4, 2e-4) * s + 2e-4 * s,
                    rng.range(-2e-4, 2e-4) * s,
                ],
            });
            return;
        }
        for e in self.expect() {
            let s = rng.range(0.5, 2.0);
            conceal(*e, s, c, rng);
        }
    }
}

/// A term the truth of a configuration holds, on one output axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Expect {
    /// The term.
    pub term: Term,
    /// The output axis (0, 1, 2).
    pub axis: usize,
}

/// The terms of the library that the concealed physics of `c` is, axis by axis: what a
/// right discovery names. Catalogue effects are not among them (a K2 is
/// `nonlinearity_k2`, not `a_i^2`); nor is physics no term expresses.
pub fn expected_terms(c: &SimConfig) -> Vec<Expect> {
    let e = &c.effects;
    let mut v = Vec::new();
    let x = ["x", "y", "z"];
    let mut put = |axis: usize, text: String| {
        if let Ok(term) = Term::parse(&text) {
            v.push(Expect { term, axis });
        }
    };
    let per_axis = |p: Option<PerAxis>| p.map_or([0.0; 3], |p| p.value);
    for i in 0..3 {
        if let Some(q) = e.quadratic {
            for (k, coef) in q.value[i].iter().enumerate() {
                let text = match k {
                    0..=2 if k == i => continue, // its own K2: the catalogue's
                    0..=2 => format!("a_{}^2", x[k]),
                    3 => "a_x*a_y".into(),
                    4 => "a_x*a_z".into(),
                    _ => "a_y*a_z".into(),
                };
                if *coef != 0.0 {
                    put(i, text);
                }
            }
        }
        let terms = [
            (per_axis(e.nonlinearity_k3)[i], format!("a_{}^3", x[i])),
            (per_axis(e.scale_aging)[i], format!("a_{}*t", x[i])),
            (per_axis(e.bias_aging)[i], "t".to_string()),
            (per_axis(e.k2_temp)[i], format!("a_{}^2*dT", x[i])),
            (per_axis(e.scale_rate)[i], format!("a_{}*dTdt", x[i])),
        ];
        for (coef, text) in terms {
            if coef != 0.0 {
                put(i, text);
            }
        }
        if let Some(w) = e.warmup_temp.filter(|w| w.v_per_c[i] != 0.0) {
            put(i, format!("dT*decay(power_on,{}s)", w.tau_s));
        }
        if let Some(r) = e.move_settle.filter(|r| r.d_v[i] != 0.0) {
            put(i, format!("decay(position,{}s)", r.tau_s));
        }
        if let Some(r) = e.stop_settle.filter(|r| r.d_v[i] != 0.0) {
            put(i, format!("decay(stop,{}s)", r.tau_s));
        }
        if let Some(b) = &e.turn_on_bias {
            if b.value.iter().any(|v| v[i] != 0.0) {
                put(i, "step(power_on)".into());
            }
        }
    }
    v
}
