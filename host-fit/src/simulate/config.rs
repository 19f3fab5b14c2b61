//! The twin's configuration, as read from TOML (`examples/sim/all-effects.toml`
//! documents every option); every section optional, unknown keys refused.
use crate::data::output_unit::OutputUnit;
use crate::error::{ErrorKind, HostError, Result};
use crate::simulate::beyond_config::{
    Quadratic, Relaxation, Repeatability, Telegraph, TempWarmup, TurnOn,
};
use serde::{Deserialize, Serialize};

/// The whole simulation, as read from TOML (every section optional).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// Random seed (overridden by `--seed`).
    pub seed: u64,
    /// Reference temperature written as metadata, C.
    pub t0_c: f64,
    /// Thermal chamber and case.
    pub chamber: Chamber,
    /// The unit's temperature sensor.
    pub sensor: Sensor,
    /// Stops and tilter.
    pub schedule: Schedule,
    /// The unit's coefficients and voltmeter.
    pub unit: Unit,
    /// Physics beyond the paper's model.
    pub effects: Effects,
    /// How the logger writes rows (uneven clocks, dropped rows, jitter).
    pub logger: Logger,
    /// A flight-like recording of the same unit instead of the production test (none by
    /// default).
    pub flight: Option<Flight>,
    /// The unit the output columns are written in (volts by default; m/s2, counts ...).
    pub output: Output,
}

/// The output columns as written: the twin's volts (the default), or the same signal in
/// another unit of recording-format.md, scaled and quantised as a digital sensor or a
/// logger that converts writes it (`# output_unit=` is written when it is not V).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// The written unit: `V`, `mV`, `m/s2`, `g`, `mg` or `counts`.
    pub unit: OutputUnit,
    /// Written units per volt of the twin's outputs (0: the unit's nominal factor, from
    /// the paper unit's scale of about 0.55 V per g: V 1, mV 1000, g 1/0.55, mg 1000/0.55,
    /// m/s2 9.80665/0.55, counts 1000/0.55, i.e. about 1000 counts per g).
    pub per_v: f64,
    /// Step of the written values, in the written unit (0: none beyond the voltmeter's
    /// `resolution_v`). Counts are integers, a multiple of this (default 1); a step larger
    /// than the noise (`noise_v * per_v`) writes data quantised coarser than its noise.
    pub quantum: f64,
}

/// The paper unit's scale, V per g, for the output units' default factors.
pub const NOMINAL_V_PER_G: f64 = 0.55;

impl Output {
    /// Written units per volt ([`Output::per_v`], or the unit's default), and the step of
    /// the written values (0: none); an error for a factor or step that cannot be used.
    pub fn scale_and_step(&self) -> Result<(f64, f64)> {
        let default = match &self.unit {
            OutputUnit::Volt => 1.0,
            OutputUnit::Millivolt => 1000.0,
            OutputUnit::G => 1.0 / NOMINAL_V_PER_G,
            OutputUnit::MilliG | OutputUnit::Counts => 1000.0 / NOMINAL_V_PER_G,
            OutputUnit::MetresPerS2 => 9.80665 / NOMINAL_V_PER_G,
            OutputUnit::Other(u) => {
                return Err(HostError::new(
                    ErrorKind::Invalid,
                    format!("output.unit `{u}`: expected V, mV, m/s2, g, mg or counts"),
                ))
            }
        };
        let per_v = if self.per_v == 0.0 {
            default
        } else {
            self.per_v
        };
        if !(per_v.is_finite() && per_v > 0.0) {
            return Err(HostError::new(
                ErrorKind::Invalid,
                "output.per_v must be > 0 (0: the unit's default)",
            ));
        }
        let step = match (&self.unit, self.quantum) {
            (OutputUnit::Counts, 0.0) => 1.0,
            (OutputUnit::Counts, q) if q >= 1.0 && q.fract() == 0.0 => q,
            (OutputUnit::Counts, q) => {
                return Err(HostError::new(
                    ErrorKind::Invalid,
                    format!("output.quantum {q}: counts step by a whole number of counts (>= 1)"),
                ))
            }
            (_, q) if q.is_finite() && q >= 0.0 => q,
            (_, q) => {
                return Err(HostError::new(
                    ErrorKind::Invalid,
                    format!("output.quantum {q} must be >= 0"),
                ))
            }
        };
        Ok((per_v, step))
    }
}

/// The logger's clock: which ticks of the twin become rows, and when they are taken.
/// The physics runs on every tick (`schedule.rate_hz`) whatever is written.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Logger {
    /// Rows per second while the unit rests through ramps and soaks (0: every tick, as in
    /// the dwells); a common setting logs 1 Hz in the dwells and 0.1 Hz at rest.
    pub rest_rate_hz: f64,
    /// Each row is taken up to this many seconds after its tick (uniform), and stamped
    /// with its own time: an uneven clock (less than one tick).
    pub jitter_s: f64,
    /// Probability that a row is lost (a dropout), independently per row.
    pub drop_rate: f64,
    /// Write `schedule.power_offs` as the `power_off_s` metadata (a logger that knows when
    /// the unit was off); otherwise only the gap in the rows shows them.
    pub power_off_metadata: bool,
    /// Write the rows at rest (ramps and soaks) with position `-`, as a logger that
    /// names only the tilter's dwells: the firmware still sees the whole temperature
    /// history, and only the dwells in equilibrium are judged (a verification block).
    pub rest_unnamed: bool,
}

/// A flight-like recording: power-on at a cold start, fast warming and cooling both ways,
/// a second power cycle, static attitudes all over the sphere held for tens of seconds,
/// sampled at an MCU rate. The unit, sensor and effects are the configuration's.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Flight {
    /// Samples per second (the MCU's rate; 10, 100, 1000 Hz ...).
    pub rate_hz: f64,
    /// Temperature of everything at power-on (the unit soaked there), C.
    pub start_c: f64,
    /// The environment's temperature profile after power-on, leg by leg.
    pub legs: Vec<Leg>,
    /// Time constant of the air around the unit following the environment, s.
    pub tau_air_s: f64,
    /// Time constant of the case following the air, s.
    pub tau_case_s: f64,
    /// Distinct static attitudes, spread over the sphere (a Fibonacci lattice), visited in
    /// turn.
    pub attitudes: usize,
    /// Each attitude held, s.
    pub hold_s: f64,
    /// Motion between attitudes, s (rows with position `-`).
    pub move_s: f64,
    /// Spans `[start_s, duration_s]` the unit is powered off (nothing logged; every
    /// in-flight machine starts again at power-on; written as `power_off_s`).
    pub power_offs: Vec<[f64; 2]>,
    /// The hysteresis state at the start (-1: cooled to the cold start).
    pub initial_direction: f64,
}

/// One leg of a flight's temperature profile.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Leg {
    /// Environment temperature at the end of the ramp, C.
    pub to_c: f64,
    /// Ramp rate, C/min.
    pub c_per_min: f64,
    /// Held at `to_c` after the ramp, s.
    #[serde(default)]
    pub hold_s: f64,
}

/// The time constant of a unit's case following the chamber air, s: the twin's chamber
/// (a case of a few hundred grams in forced air); `plan` assumes it, as it cannot measure
/// the case before the test.
pub const CASE_TAU_S: f64 = 600.0;

/// The unit type's output noise, V (1 sigma per sample): the twin's voltmeter, and the
/// noise `plan` assumes when none is given or diagnosed.
pub const UNIT_NOISE_V: f64 = 2e-5;

/// Chamber air and unit case: first-order lags.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Chamber {
    /// Initial temperature of everything, C.
    pub start_c: f64,
    /// Time constant of the air following the set point, s.
    pub tau_air_s: f64,
    /// Time constant of the case following the air, s.
    pub tau_case_s: f64,
}

/// The temperature sensor on the case.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Sensor {
    /// White noise, C (1 sigma).
    pub noise_c: f64,
    /// Quantisation step, C (0 = none).
    pub quantum_c: f64,
    /// The sensor reads the case plus this, C.
    pub offset_c: f64,
    /// ... plus this times (case - 20 C): a gain error.
    pub gain_error: f64,
}

/// One stop of the profile.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Stop {
    /// Set point, C.
    pub temp_c: f64,
    /// Soak after reaching the set point, s.
    #[serde(default = "default_soak")]
    pub soak_s: f64,
    /// Ramp rate to this stop, C/min.
    #[serde(default = "default_ramp")]
    pub ramp_c_per_min: f64,
    /// Positions visited (default: the schedule's).
    #[serde(default)]
    pub positions: Option<Vec<String>>,
}

fn default_soak() -> f64 {
    1500.0
}
fn default_ramp() -> f64 {
    1.0
}

/// The tilter schedule.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Schedule {
    /// Samples per second.
    pub rate_hz: f64,
    /// Dwell per position, s.
    pub dwell_s: f64,
    /// Motion between positions, s (rows with position `-`).
    pub move_s: f64,
    /// Where the unit rests during ramps and soaks (recorded).
    pub rest_position: String,
    /// Positions visited at every stop unless the stop says otherwise.
    pub positions: Vec<String>,
    /// The profile.
    pub stops: Vec<Stop>,
    /// Extra positions (name, unit vector) beyond TP/PP.
    pub extra_positions: Vec<(String, [f64; 3])>,
    /// Spans `[start_s, duration_s]` the logger drops (the unit runs on).
    pub dropouts: Vec<[f64; 2]>,
    /// Spans `[start_s, duration_s]` the unit is powered off (nothing logged; the
    /// warm-up starts again at power-on).
    pub power_offs: Vec<[f64; 2]>,
    /// Write one row per dwell (its mean), as a voltmeter that averages each position.
    pub dwell_means: bool,
    /// A continuous sweep instead of the stops: the chamber follows these legs from
    /// `chamber.start_c` while the tilter keeps turning through `positions` (`move_s`,
    /// `dwell_s` each) the whole time, no soaks (none by default).
    pub sweep: Option<Sweep>,
    /// A chamber and tilter program instead of the stops (`simulate --plan PLAN.csv`;
    /// see [`crate::simulate::program`]); empty by default.
    pub program: Vec<crate::simulate::program::Step>,
}

/// A continuous sweep: the set point ramps (and holds) leg by leg while the tilter turns.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// The set point's legs (to, rate, hold at the end).
    pub legs: Vec<Leg>,
}

/// How the coefficients depend on temperature.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Unit {
    /// Serial written as metadata.
    pub serial: String,
    /// `paper` (the built-in paper unit) or `table` (`temps_c` + `coeffs`).
    pub model: UnitModel,
    /// Table temperatures, C.
    pub temps_c: Vec<f64>,
    /// Table rows, 12 coefficients each (kxx kyy kzz kxy kxz kyx kyz kzx kzy u0x u0y u0z).
    pub coeffs: Vec<[f64; 12]>,
    /// Between table rows: `poly` (the polynomial through all rows) or `pwl`.
    pub interp: Interp,
    /// Voltmeter white noise, V (1 sigma).
    pub noise_v: f64,
    /// Voltmeter resolution, V (0 = none).
    pub resolution_v: f64,
    /// Correlation time of the voltmeter noise, s (0 = white; else first-order
    /// autoregressive with the same per-sample sigma).
    pub noise_corr_s: f64,
    /// Probability per sample and axis of a spike.
    pub spike_rate: f64,
    /// Spike amplitude, V (random sign).
    pub spike_v: f64,
}

/// Where the twin's true coefficients come from (`unit.model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UnitModel {
    /// The paper's unit, built in.
    Paper,
    /// The table `unit.temps_c` x `unit.coeffs`.
    Table,
}

/// How the twin's table is read between its rows (`unit.interp`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Interp {
    /// The polynomial through all rows.
    Poly,
    /// Piecewise-linear between rows.
    Pwl,
}

/// Every effect of physics-catalogue.md; all off by default. Per-axis arrays are x, y, z.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Effects {
    /// `temp_curvature`: an extra shape `sin(2 pi (T - T0) / period)` on offsets (V)
    /// and scale factors (relative).
    pub temp_curvature: Option<Curvature>,
    /// `thermal_lag`: sensing elements follow the case with these time constants, s.
    pub thermal_lag: Option<PerAxis>,
    /// `temp_rate`: U0 += r dT/dt, V per (C/s).
    pub temp_rate: Option<PerAxis>,
    /// `hysteresis`: U0 += +-h/2 by the direction of the last temperature change, V.
    pub hysteresis: Option<PerAxis>,
    /// `nonlinearity_k2`: U += K2 a^2, V/g^2.
    pub nonlinearity_k2: Option<PerAxis>,
    /// `scale_asymmetry`: K_ii (1 +- d) for positive/negative input (relative).
    pub scale_asymmetry: Option<PerAxis>,
    /// `fixture_error`: one position rotated by two small angles.
    pub fixture_error: Option<Fixture>,
    /// `warmup_drift`: U0 += d exp(-t / tau).
    pub warmup_drift: Option<Warmup>,
    /// Other forms (a blind test's "physics not in the tool's own form"):
    /// `thermal_lag` through a second pole: the element lags an intermediate stage by
    /// these time constants, s.
    pub thermal_lag2: Option<PerAxis>,
    /// `temp_rate` as a thermal gradient: U0 += g (T_case - T_inner), T_inner a lag of
    /// the case with `tau_s`.
    pub temp_gradient: Option<Gradient>,
    /// `hysteresis`: the state before the first change (+1 heated, -1 cooled; default +1).
    pub hysteresis_initial: Option<f64>,
    /// `hysteresis` that switches smoothly: the state relaxes toward the new direction
    /// over this many C of travel after a reversal.
    pub hysteresis_width_c: Option<f64>,
    /// `hysteresis` as a play operator (backlash): the state moves linearly from one
    /// direction's value to the other's over this many C of travel after a reversal, and
    /// holds wherever the temperature turns within that band (a gradual hysteresis that
    /// also remembers partial reversals).
    pub hysteresis_play_c: Option<f64>,
    /// `hysteresis` as a Preisach ensemble of relays (their centres spread evenly over
    /// every temperature) up to this many C wide: the mean of 24 play operators of widths
    /// spread evenly up to it, each normalised to [-1, 1] (the Prandtl-Ishlinskii form of
    /// a Preisach model whose relay density falls as one over the width): after a
    /// reversal the state moves fast at first, as the narrow plays turn, then ever more
    /// slowly until the widest has turned after this many C. Of the three forms of a
    /// gradual hysteresis, `hysteresis_play_c` wins over this, and this over
    /// `hysteresis_width_c`; each must be > 0 C (refused otherwise, as every width).
    pub hysteresis_preisach_c: Option<f64>,
    /// `hysteresis` of the scale factors: K_ii (1 +- s/2), relative.
    pub scale_hysteresis: Option<PerAxis>,
    /// A second warm-up with its own time constant.
    pub warmup_drift2: Option<Warmup>,
    /// `temp_curvature` as a local bend: offsets and scales change slope at `knot_c`.
    pub temp_bend: Option<Bend>,
    /// A second position off its nominal orientation.
    pub fixture_error2: Option<Fixture>,
    /// Outside the catalogue: the bias steps at `at_s` (a sudden shift).
    pub bias_step: Option<BiasStep>,
    /// Outside the catalogue: the bias wanders as a random walk, V per sqrt(s).
    pub bias_walk: Option<PerAxis>,
    /// Outside the catalogue: a cubic response U += K3 a^3, V/g^3.
    pub nonlinearity_k3: Option<PerAxis>,
    /// Outside the catalogue: a periodic disturbance of the bias.
    pub periodic: Option<Periodic>,
    /// Outside the catalogue: scale factors age, relative per hour.
    pub scale_aging: Option<PerAxis>,
    /// `fixture_error` that changes during the test: a position re-clamped (or slipped)
    /// at a time, e.g. between two stops.
    pub fixture_change: Option<FixtureChange>,
    /// Outside the catalogue: the bias ages, V per hour since the start (no power-on
    /// behind it: a slow drift of the whole test).
    pub bias_aging: Option<PerAxis>,
    /// Outside the catalogue: the bias settles exponentially toward a new value from
    /// `at_s` on (a disturbance that starts mid-test, no power-on behind it).
    pub bias_settle: Option<Settle>,
    /// Beyond the catalogue ([`crate::simulate::beyond`]): the IEEE Std 1293 second-order
    /// terms of each output (cross-coupling Kip, Kio, Kpo and cross-axis squares Kpp, Koo).
    pub quadratic: Option<Quadratic>,
    /// Beyond the catalogue: K2 with a temperature coefficient, `U += c (T - T0) a^2`,
    /// V/g^2 per C.
    pub k2_temp: Option<PerAxis>,
    /// Beyond the catalogue: the scale factor moves with the rate of temperature change,
    /// `K_ii (1 + s dT/dt)`, relative per (C/min).
    pub scale_rate: Option<PerAxis>,
    /// Beyond the catalogue: a turn-on transient whose size grows with T - T0.
    pub warmup_temp: Option<TempWarmup>,
    /// Beyond the catalogue: turn-on to turn-on repeatability, the bias after each
    /// power-off.
    pub turn_on_bias: Option<TurnOn>,
    /// Beyond the catalogue (the rig): the signal chain relaxes after each tilter move.
    pub move_settle: Option<Relaxation>,
    /// Beyond the catalogue (the rig): the signal chain relaxes after the chamber reaches
    /// each new stop.
    pub stop_settle: Option<Relaxation>,
    /// Beyond the catalogue (the rig): the tilter stops a fresh small rotation off each
    /// position.
    pub tilter_repeatability: Option<Repeatability>,
    /// Beyond the catalogue: the bias jumps between two levels (random telegraph noise).
    pub telegraph: Option<Telegraph>,
}

/// An exponential approach of the bias that starts mid-test: `value (1 - exp(-(t -
/// at_s) / tau_s))` from `at_s` on, nothing before.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Settle {
    /// When it starts, s.
    pub at_s: f64,
    /// The shift it approaches, per axis, V.
    pub value: [f64; 3],
    /// Its time constant, s.
    pub tau_s: f64,
}

/// A tilter position whose orientation changes at one moment of the test.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FixtureChange {
    /// The position.
    pub position: String,
    /// Its two rotation angles before the change, rad (default: at its nominal
    /// orientation).
    #[serde(default)]
    pub before_rad: [f64; 2],
    /// Its two rotation angles from `at_s` on, rad.
    pub angles_rad: [f64; 2],
    /// When it was re-clamped, s.
    pub at_s: f64,
}

/// A thermal gradient across the sensor.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Gradient {
    /// Offset per C of gradient, per axis, V/C.
    pub value: [f64; 3],
    /// Time constant of the inner temperature, s.
    pub tau_s: f64,
}

/// A local bend of the temperature dependence.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Bend {
    /// Where, C.
    pub knot_c: f64,
    /// Offset slope change per axis, V/C.
    pub u0_v_per_c: [f64; 3],
    /// Scale slope change per axis, relative per C.
    #[serde(default)]
    pub k_rel_per_c: [f64; 3],
}

/// A sudden bias shift.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BiasStep {
    /// When, s (the middle of the shift when it takes `rise_s`).
    pub at_s: f64,
    /// Shift per axis, V.
    pub value: [f64; 3],
    /// The shift takes this long, s (a raised cosine; 0: sudden).
    #[serde(default)]
    pub rise_s: f64,
}

/// A periodic bias disturbance.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Periodic {
    /// Period, s.
    pub period_s: f64,
    /// Amplitude per axis, V.
    pub value: [f64; 3],
    /// Phase at the start of the recording, rad: `value sin(2 pi t / period + phase)`.
    #[serde(default)]
    pub phase_rad: f64,
}

/// Three per-axis values.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct PerAxis {
    /// x, y, z.
    pub value: [f64; 3],
}

/// Extra temperature shape.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Curvature {
    /// Offset amplitude per axis, V.
    pub u0_v: [f64; 3],
    /// Scale-factor amplitude per axis, relative.
    #[serde(default)]
    pub k_rel: [f64; 3],
    /// Period of the shape, C.
    #[serde(default = "default_period")]
    pub period_c: f64,
}
fn default_period() -> f64 {
    60.0
}

/// A tilter face off its nominal orientation.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Fixture {
    /// The position.
    pub position: String,
    /// Two rotation angles about axes perpendicular to the nominal vector, rad.
    pub angles_rad: [f64; 2],
}

/// Exponential settling after power-on.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Warmup {
    /// Amplitude per axis, V.
    pub d_v: [f64; 3],
    /// Time constant, s.
    pub tau_s: f64,
}

impl Default for Chamber {
    fn default() -> Self {
        Chamber {
            start_c: 20.0,
            tau_air_s: 120.0,
            tau_case_s: CASE_TAU_S,
        }
    }
}
impl Default for Sensor {
    fn default() -> Self {
        Sensor {
            noise_c: 0.02,
            quantum_c: 0.0625,
            offset_c: 0.0,
            gain_error: 0.0,
        }
    }
}
impl Default for Schedule {
    fn default() -> Self {
        let tp: Vec<String> = (1..=6).map(|i| format!("TP{i}")).collect();
        let pp: Vec<String> = (1..=6).map(|i| format!("PP{i}")).collect();
        Schedule {
            rate_hz: 1.0,
            dwell_s: 60.0,
            move_s: 10.0,
            rest_position: "TP1".into(),
            positions: tp.into_iter().chain(pp).collect(),
            stops: [-40.0, -10.0, 20.0, 45.0, 70.0]
                .iter()
                .map(|t| Stop {
                    temp_c: *t,
                    soak_s: default_soak(),
                    ramp_c_per_min: default_ramp(),
                    positions: None,
                })
                .collect(),
            extra_positions: Vec::new(),
            dropouts: Vec::new(),
            power_offs: Vec::new(),
            dwell_means: false,
            sweep: None,
            program: Vec::new(),
        }
    }
}
impl Default for Unit {
    fn default() -> Self {
        Unit {
            serial: "PAPER-UNIT".into(),
            model: UnitModel::Paper,
            temps_c: Vec::new(),
            coeffs: Vec::new(),
            interp: Interp::Poly,
            noise_v: UNIT_NOISE_V,
            resolution_v: 1e-7,
            noise_corr_s: 0.0,
            spike_rate: 0.0,
            spike_v: 0.0,
        }
    }
}
impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            seed: 1,
            t0_c: 20.0,
            chamber: Chamber::default(),
            sensor: Sensor::default(),
            schedule: Schedule::default(),
            unit: Unit::default(),
            effects: Effects::default(),
            logger: Logger::default(),
            flight: None,
            output: Output::default(),
        }
    }
}
impl Default for Output {
    fn default() -> Self {
        Output {
            unit: OutputUnit::Volt,
            per_v: 0.0,
            quantum: 0.0,
        }
    }
}
impl Default for Logger {
    fn default() -> Self {
        Logger {
            rest_rate_hz: 0.0,
            jitter_s: 0.0,
            drop_rate: 0.0,
            power_off_metadata: false,
            rest_unnamed: false,
        }
    }
}
impl Default for Flight {
    /// About 73 minutes at 20 Hz: 5 min cold at -30 C, a power cycle (2 min off), 3 min
    /// cold, warm to +45 C at 6 C/min, 20 min there, cool to +5 C at 5 C/min, 10 min,
    /// warm to +25 C at 8 C/min, 10 min; 24 attitudes held 40 s each.
    fn default() -> Self {
        let leg = |to_c: f64, c_per_min: f64, hold_s: f64| Leg {
            to_c,
            c_per_min,
            hold_s,
        };
        Flight {
            rate_hz: 20.0,
            start_c: -30.0,
            legs: vec![
                leg(-30.0, 1.0, 600.0),
                leg(45.0, 6.0, 1200.0),
                leg(5.0, 5.0, 600.0),
                leg(25.0, 8.0, 600.0),
            ],
            tau_air_s: 30.0,
            tau_case_s: 120.0,
            attitudes: 24,
            hold_s: 40.0,
            move_s: 5.0,
            power_offs: vec![[300.0, 120.0]],
            initial_direction: -1.0,
        }
    }
}
