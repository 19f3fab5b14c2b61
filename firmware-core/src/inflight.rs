//! The in-flight state machines of the physics terms (physics-catalogue.md), written once:
//! the firmware steps them over its samples, and host-fit's diagnosis steps the very same
//! code over a recording's rows to build its regressors, so what is flashed is what was
//! fitted, on any clock (one exception: across a recording's unlogged gap the host
//! carries the lag along the sensor's bend, which it sees in the rows on both sides;
//! host-fit's `model::regressors::Cubic`).
//!
//! # Time
//! Every time constant is in seconds and every step is told how long it was (the MCU's
//! sample period, an explicit time step, a recording's row spacing). The machines step
//! on a [`Clock`]: at the first sample after power-on, then as soon as at least
//! [`MIN_STEP_S`] has passed since their last step, over the time actually elapsed. So a
//! 10 Hz MCU and a 1 Hz or 0.1 Hz logger step them at every sample, a 100 Hz MCU at every
//! 10th and a 1 kHz one at every 100th, all on about the same 0.1 s steps: in f32, a
//! 1 ms step of a 600 s low-pass (`1 - exp(-dt/tau) = 1.7e-6`) would be below the
//! resolution of its state, and the MCU's rate would change the compensation. Between
//! steps the outputs are held (the model temperature and the offsets; at 5 C/min the
//! temperature moves 0.008 C in 0.1 s).
//!
//! # Discretisation
//! Between two steps the sensor temperature is taken as the straight line between its two
//! readings, and each first-order low-pass is advanced by its exact solution for that input
//! ([`LowPass::step`]), unbiased at any step length. (`y += alpha (x - y)` with
//! `alpha = 1 - exp(-h/tau)` holds the new reading over the whole step: the output comes
//! out early by `h/2`, and a time constant fitted with it long by half the row spacing.)
//! The per-step constants come from [`Step::new`]: one `exp(-u) - 1` each, in f32 by
//! [`crate::exp::expm1_neg_f32`] (no libm `exp`, no soft-double), in f64 by libm.
//!
//! # A state that does not cancel
//! A low-pass keeps its output minus its input (the deviation, small in a dwell), not its
//! output: its f32 rounding is relative to the deviation, not to a temperature of 25 C
//! whose ulp (1.9e-6 C) a slow filter's increment would fall below. In f32, per step the
//! deviation is rounded by at most 1.5 ulp of itself; the filter contracts by `1 - a` per
//! step, so the accumulated error stays below `1.5 ulp(e) / a` (with 0.1 s steps and a
//! 900 s lag: 1.6e-3 of the deviation). Held by the test
//! `f32_machines_follow_f64_at_every_rate`.
//!
//! # Power-on
//! [`Machines`] starts at the first sample after the MCU's power-on (a new compensator):
//! the lag's element at the sensor's temperature (a unit at rest), the rate 0, the
//! hysteresis in the direction that brought the unit to that temperature from its
//! reference T0 (-1 below `T0 - threshold`: cooled to a cold start; +1 above
//! `T0 + threshold`; the blob's initial direction within the threshold of T0), the warm-up
//! weight `exp(-t_on / tau_w)` with `t_on` the time since power-on (the first sample's time
//! step). A power cycle of the sensor while the MCU keeps its state
//! ([`Machines::power_on`]; the host at the end of each power-off a recording states)
//! restarts the warm-up clock only: the element's temperature, its hysteresis state and
//! the temperature's rate are the unit's physics, not its power's, and the next step
//! bridges the gap with the real time elapsed, the sensor's temperature taken as straight
//! across it. After a start and after a power-on the rate is taken as 0 until its
//! estimator has averaged [`RATE_SETTLE_TAUS`] time constants ([`rate_settled`]): its
//! low-passes then hold one reading, whose noise they would otherwise read as a rate. The host does the same at the first row of a recording and at each stated
//! power-on, but for the lag, which its fits carry along the sensor's bend across a gap,
//! and for the diagnosis's own rate low-pass, held after the start only (a unit switched
//! on in a ramp feels the rate at once). (What a power-off during a fast temperature
//! change does to an MCU that loses its state cannot be known: its lag starts again at
//! the sensor's temperature.)
use crate::real::Real;
use crate::temperature::Physics;

/// The shortest step the machines take, s: 0.1 s, less the f32 rounding of ten 10-ms
/// sample periods (so a 100 Hz MCU steps them at every 10th sample, not every 11th).
pub const MIN_STEP_S: f32 = 0.099_9;

/// The per-step constants of a first-order low-pass with time constant `tau` over a step
/// of `h` (`u = h / tau`): `a = 1 - exp(-u)`, `b = a / u`.
///
/// Error bound: in f64 a few ulp; in f32, `a` within `2e-7` of itself
/// ([`crate::exp::EXPM1_NEG_F32_BOUND`]) and `b` within `3e-7` (one more rounding).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Step<R> {
    /// `1 - exp(-h/tau)`: how much of the deviation decays over the step.
    pub a: R,
    /// `a tau / h`: how much of a linear input change the output misses over the step.
    pub b: R,
}

impl<R: Real> Step<R> {
    /// The constants for a step of `h` s and a time constant of `tau` s; `tau <= 0` is no
    /// lag (`a = 1`, `b = 0`), `h <= 0` no time (`a = 0`, `b = 1`).
    // The negated comparisons are the point: a NaN takes the degenerate branch. Not
    // inlined: one copy of the exponential for the three machines (flash).
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    #[inline(never)]
    pub fn new(h: R, tau: R) -> Self {
        if !(tau > R::ZERO) {
            return Step {
                a: R::ONE,
                b: R::ZERO,
            };
        }
        let u = h / tau;
        if !(u > R::ZERO) {
            return Step {
                a: R::ZERO,
                b: R::ONE,
            };
        }
        let a = -u.expm1_neg();
        Step { a, b: a / u }
    }
}

/// What the machines do at a sample (from [`Clock::tick`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Tick<R> {
    /// The first sample after power-on: start, this many seconds after power-on.
    Start(R),
    /// Step over this many seconds (at least [`MIN_STEP_S`]).
    Step(R),
    /// Hold: less than [`MIN_STEP_S`] since the last step.
    Hold,
}

/// When the machines step: the first sample after power-on starts them, then a step as
/// soon as [`MIN_STEP_S`] has accumulated.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Clock<R> {
    started: bool,
    /// The next sample steps, however short the time since the last step.
    force: bool,
    /// Seconds since the last step (or since power-on, before the start).
    pending: R,
}

/// After a start or a power-on the rate estimator's low-passes hold one reading, off the
/// temperature's mean by that reading's noise (a quantised sensor: up to a quantum), and
/// as they settle onto the mean that offset would be read as a rate: its integral is the
/// offset, however it is spread. So the rate is taken as 0 until the estimator has
/// averaged this many of its time constants (the low-pass's share of the offset left
/// `e^-5` = 0.7 %, the zero-lag one's 3 %), and at most [`RATE_SETTLE_MAX_S`].
pub const RATE_SETTLE_TAUS: f32 = 5.0;

/// The longest the rate is held at 0 after a start or a power-on, s: five time
/// constants of the flight's estimator (4 s, host-fit's `FLIGHT_RATE_TAU_S`). A slower
/// estimator (the 30-60 s a chamber's data prefer) would be held for minutes, losing a
/// rate that is really there, while its start's offset is spread over its own time
/// constant and is as much smaller per second.
pub const RATE_SETTLE_MAX_S: f32 = 20.0;

/// Whether the rate estimator of time constant `tau_s` (negative: zero-lag, of `|tau_s|`)
/// has settled `age_s` seconds (stepped) after a start or a power-on
/// ([`RATE_SETTLE_TAUS`] time constants, at most [`RATE_SETTLE_MAX_S`]; a time constant
/// of 0, the plain difference, at once). The boundary is half a [`MIN_STEP_S`] early:
/// the age is a sum of steps, which in f32 and in f64, or from 10 ms and from 100 ms
/// samples, rounds either side of a whole number of 0.1-s steps, and half a step away
/// from it they agree (steps of other lengths, a logger's rows, may still fall within
/// the rounding of the boundary: then the f32 and f64 paths may settle one step apart).
#[inline]
pub fn rate_settled<R: Real>(age_s: R, tau_s: R) -> bool {
    let need = R::from_f32(RATE_SETTLE_TAUS) * tau_s.abs();
    let most = R::from_f32(RATE_SETTLE_MAX_S);
    age_s + R::from_f32(0.5 * MIN_STEP_S) >= if need < most { need } else { most }
}

impl<R: Real> Clock<R> {
    /// A sample `dt` seconds after the previous one (or after power-on).
    #[inline]
    pub fn tick(&mut self, dt: R) -> Tick<R> {
        let t = self.pending + dt;
        if !self.started {
            self.started = true;
            self.pending = R::ZERO;
            return Tick::Start(t);
        }
        if t >= R::from_f32(MIN_STEP_S) || self.force {
            self.pending = R::ZERO;
            self.force = false;
            Tick::Step(t)
        } else {
            self.pending = t;
            Tick::Hold
        }
    }

    /// A sample whose temperature is not used (not finite, or a glitch): its time still
    /// passes, and the next step spans it.
    #[inline]
    pub fn wait(&mut self, dt: R) {
        self.pending = self.pending + dt;
    }

    /// Power-on again: the next sample starts the machines.
    pub fn restart(&mut self) {
        *self = Clock::default();
    }

    /// The next sample steps the machines, however short the time since the last step.
    pub fn force_step(&mut self) {
        self.force = true;
    }

    /// Whether the machines have started since power-on.
    pub fn started(&self) -> bool {
        self.started
    }
}

/// A first-order low-pass, kept as its output minus its input (the deviation `e`).
///
/// Over a step in which the input moves linearly by `dx`, the exact solution of
/// `tau y' = x - y` is `e1 = e0 - a e0 - b dx` ([`Step`]). Error bound (f32): one step
/// rounds `e1` by at most 1.5 ulp of `max(|e0|, |e1|, b |dx|)`; the filter contracts by
/// `1 - a` per step, so errors do not grow over steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LowPass<R> {
    e: R,
}

impl<R: Real> LowPass<R> {
    /// Settled at its input.
    #[inline]
    pub fn start(&mut self) {
        self.e = R::ZERO;
    }

    /// Step over an input change `dx` (linear over the step); returns the new deviation.
    #[inline]
    pub fn step(&mut self, k: Step<R>, dx: R) -> R {
        self.e = self.e - k.a * self.e - k.b * dx;
        self.e
    }

    /// Output minus input, at the last step.
    pub fn deviation(&self) -> R {
        self.e
    }
}

/// `thermal_lag`: the sensing element's temperature as up to two cascaded first-order
/// lags of the sensor's (a second time constant of 0 is a single pole). The second stage
/// takes the first stage's output as linear over the step (exact for one pole; for two,
/// an error of second order in the step over the time constants).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Lag<R> {
    first: LowPass<R>,
    second: LowPass<R>,
}

impl<R: Real> Lag<R> {
    /// Settled at the sensor's temperature.
    pub fn start(&mut self) {
        self.first.start();
        self.second.start();
    }

    /// Step to sensor temperature `x1`, a change of `dx` over the step; returns the
    /// element's temperature.
    #[inline]
    pub fn step(&mut self, k1: Step<R>, k2: Step<R>, x1: R, dx: R) -> R {
        let before = self.first.e;
        let e1 = self.first.step(k1, dx);
        let e2 = self.second.step(k2, dx + e1 - before);
        x1 + e1 + e2
    }
}

/// `temp_rate`: the rate of the temperature, C/s, as the change over the step divided by
/// the step's duration of its low-pass `L1` (time constant tau_r), or, zero-lag, of
/// `2 L1 - L2` (`L2` the low-pass of `L1`, the same tau_r). Either is exactly `s` for a
/// ramp of slope `s` once settled, whatever the step. The low-pass's rate trails the
/// temperature's by tau_r (an error of `tau_r` times the second derivative); the
/// zero-lag one does not (its error is of the order of `tau_r^2` times the third) at the
/// price of up to twice the low-pass's noise at high frequencies: what a fast flight
/// needs of an estimator smoothed over seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rate<R> {
    lp: LowPass<R>,
    /// The low-pass of `lp`'s output (the zero-lag estimator's `L2`).
    lp2: LowPass<R>,
}

impl<R: Real> Rate<R> {
    /// Settled (rate 0).
    pub fn start(&mut self) {
        self.lp.start();
        self.lp2.start();
    }

    /// Step over a temperature change `dx` in `h` seconds; returns the rate, C/s; 0 over
    /// no time (a forced step). The low-pass's: `(dx + e1 - e0) / h`, written as
    /// `(dx (1 - b) - a e0) / h` (`dL1 / h`) so that no two nearly equal numbers are
    /// subtracted. Zero-lag: the change of `2 L1 - L2` is `2 dL1 - dL2`, with
    /// `dL2 = dL1 + e2' - e2 = dL1 (1 - b) - a e2` (`L1` taken as linear over the step, as
    /// the two-pole lag takes its first stage): `(dL1 (1 + b) + a e2) / h`. Both states
    /// are stepped either way, so the time per sample does not depend on the choice.
    // The negated comparison is the point: a NaN step takes the degenerate branch.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    #[inline]
    pub fn step(&mut self, k: Step<R>, dx: R, h: R, zero_lag: bool) -> R {
        let e0 = self.lp.e;
        self.lp.step(k, dx);
        let dl1 = dx * (R::ONE - k.b) - k.a * e0;
        let e2 = self.lp2.e;
        self.lp2.step(k, dl1);
        if !(h > R::ZERO) {
            return R::ZERO;
        }
        if zero_lag {
            (dl1 * (R::ONE + k.b) + k.a * e2) / h
        } else {
            dl1 / h
        }
    }
}

/// `hysteresis`: the direction of the last temperature change larger than a threshold
/// (+1 heated to here, -1 cooled, the initial state until the first such change): a
/// relay. With a negative threshold `-d`, a play operator (backlash) of half-width `d`
/// instead: the state moves linearly from -1 to +1 over `2 d` C of travel after a
/// reversal and holds where the temperature turns within that band (a gradual
/// hysteresis; the same two numbers of state).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Direction<R> {
    dir: R,
    /// The relay's reference (the turn), or the play operator's output.
    reference: R,
}

impl<R: Real> Direction<R> {
    /// In state `initial` (+1, -1, or 0 for unknown), at temperature `t`; `threshold` as
    /// in [`Direction::step`] (a play operator's output starts `initial` half-widths
    /// below `t`, so its state is `initial`).
    pub fn start(&mut self, initial: R, t: R, threshold: R) {
        self.dir = initial;
        self.reference = if threshold < R::ZERO {
            t + initial * threshold
        } else {
            t
        };
    }

    /// Step with temperature `t`; returns the direction. A change of more than
    /// `threshold` from the reference sets the direction; moving on in the same
    /// direction moves the reference with it (so a reversal is measured from the turn).
    /// A negative threshold `-d` is a play operator: its output is held within `d` of
    /// `t`, and the state is `(t - output) / d`, within [-1, 1] but for rounding: the
    /// clamp's `t - d` or `t + d` and the difference each round once, so in f32 the state
    /// is within about `2 ulp(|t| + d) / d` of the exact one (1.3e-5 at 60 C over 3 C;
    /// it may leave [-1, 1] by that much, where the relay's is exact). A NaN temperature
    /// leaves the output where it was and makes this step's state NaN (the compensator
    /// refuses such a temperature before it gets here).
    #[inline]
    pub fn step(&mut self, threshold: R, t: R) -> R {
        if threshold < R::ZERO {
            let d = -threshold;
            // NaN-safe clamp: a NaN temperature leaves the output where it was
            if t - self.reference > d {
                self.reference = t - d;
            } else if self.reference - t > d {
                self.reference = t + d;
            }
            self.dir = (t - self.reference) / d;
            return self.dir;
        }
        if t - self.reference > threshold {
            self.dir = R::ONE;
            self.reference = t;
        } else if self.reference - t > threshold {
            self.dir = -R::ONE;
            self.reference = t;
        } else if (t - self.reference) * self.dir > R::ZERO {
            self.reference = t;
        }
        self.dir
    }

    /// The current direction.
    pub fn value(&self) -> R {
        self.dir
    }

    /// The state at power-on at temperature `x`, the reference temperature being `t0`: a
    /// relay in [`power_on_direction`]'s direction; a play operator as if it had stood at
    /// `t0` in the blob's initial state and moved straight to `x`, so its state is
    /// continuous in `x` (the initial state at `t0`, +-1 only from `2 d` away), where a
    /// relay's rule (the way from `t0` beyond the threshold) would jump by a whole state
    /// at `d` from `t0`. Not inlined: it runs once per start, and inlined into the
    /// machines' step it cost 26 bytes of flash and 7 instructions per step (measured by
    /// `cargo xtask embedded`).
    #[inline(never)]
    pub fn power_on(&mut self, p: &Physics<R>, x: R, t0: R) {
        let th = p.hysteresis_threshold_c;
        if th < R::ZERO {
            self.start(p.hysteresis_initial, t0, th);
            let _ = self.step(th, x);
        } else {
            self.start(power_on_direction(p, x, t0), x, th);
        }
    }
}

/// `warmup_drift`: the weight of the settling offset, `exp(-t_on / tau_w)` with `t_on`
/// the time since power-on, decayed step by step (`w -= a w`: relative error per step
/// 1.5 ulp, so about 1e-3 of itself after 10^4 steps, when it has long decayed).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Warmup<R> {
    w: R,
}

impl<R: Real> Default for Warmup<R> {
    fn default() -> Self {
        Warmup { w: R::ONE }
    }
}

impl<R: Real> Warmup<R> {
    /// Power-on, `k` being the step from power-on to the first sample; returns the weight.
    pub fn start(&mut self, k: Step<R>) -> R {
        self.w = R::ONE - k.a;
        self.w
    }

    /// Decay over a step; returns the weight.
    #[inline]
    pub fn step(&mut self, k: Step<R>) -> R {
        self.w = self.w - k.a * self.w;
        self.w
    }

    /// The weight.
    pub fn value(&self) -> R {
        self.w
    }
}

/// Seconds elapsed, summed step by step with a compensation term (Kahan): the sum stays
/// within `2 eps` of itself (eps the type's) of the exact sum of the steps however many
/// there are, where a plain f32 sum of 0.1 s steps would drift by up to
/// `n ulp(t)/2` (0.6 s after 1000 s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Elapsed<R> {
    sum: R,
    lost: R,
}

impl<R: Real> Elapsed<R> {
    /// Start at `s` seconds.
    pub fn set(&mut self, s: R) {
        self.sum = s;
        self.lost = R::ZERO;
    }

    /// Add a step of `h` seconds.
    #[inline]
    pub fn add(&mut self, h: R) {
        let y = h - self.lost;
        let t = self.sum + y;
        self.lost = (t - self.sum) - y;
        self.sum = t;
    }

    /// The seconds elapsed.
    pub fn value(&self) -> R {
        self.sum
    }
}

/// The hysteresis direction at power-on at temperature `x`: the direction that brought
/// the unit there from its reference `t0` when it is more than the threshold away from
/// it (a cold start was cooled to), else the blob's initial direction. For a relay; a
/// play operator's state at power-on is [`Direction::power_on`]'s.
pub fn power_on_direction<R: Real>(p: &Physics<R>, x: R, t0: R) -> R {
    let th = p.hysteresis_threshold_c;
    if x - t0 > th {
        R::ONE
    } else if t0 - x > th {
        -R::ONE
    } else {
        p.hysteresis_initial
    }
}

/// The machines of the firmware's physics terms together (one lag pole for all axes, the
/// rate, the hysteresis of the offsets, one warm-up): what the compensator holds, and what
/// the host runs to check it. Its outputs, from the last step: the model temperature and
/// the offsets to remove from the outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Machines<R> {
    clock: Clock<R>,
    /// The sensor temperature at the last step.
    x: R,
    lag: LowPass<R>,
    rate: Rate<R>,
    dir: Direction<R>,
    warm: Warmup<R>,
    offset: [R; 3],
    /// The time since the latest power-on, as of the last step (a discovered term's
    /// `decay(power_on,TAU)`; only with the `terms` feature: flash and state).
    #[cfg(feature = "terms")]
    since_on: Elapsed<R>,
    /// Not negative: a power-on of the sensor is pending ([`Machines::power_on`]) this
    /// many seconds before the next sample. Negative: none is, and this is `-1` minus
    /// the seconds stepped since the start or the last power-on, how long the rate
    /// estimator has averaged ([`rate_settled`]). One number for both, no flag beside it:
    /// the compensator's state stays within its 256 bytes on a 64-bit host too.
    power: R,
}

impl<R: Real> Default for Machines<R> {
    /// Powered on, not started.
    fn default() -> Self {
        Machines {
            clock: Clock::default(),
            x: R::ZERO,
            lag: LowPass::default(),
            rate: Rate::default(),
            dir: Direction::default(),
            warm: Warmup::default(),
            offset: [R::ZERO; 3],
            #[cfg(feature = "terms")]
            since_on: Elapsed::default(),
            power: -R::ONE,
        }
    }
}

impl<R: Real> Machines<R> {
    /// The clock: [`Clock::tick`] at a sample, then [`Machines::apply`] unless it holds.
    pub fn clock(&mut self) -> &mut Clock<R> {
        &mut self.clock
    }

    /// Start or step at sensor temperature `x`, the reference temperature being `t0`
    /// (`Tick::Hold` changes nothing); returns the temperature's rate at this step, C/s
    /// (0 at the start and for `Hold`): what a discovered term's `dTdt` reads.
    #[inline]
    pub fn apply(&mut self, tick: Tick<R>, p: &Physics<R>, x: R, t0: R) -> R {
        let (rate, dir, w) = match tick {
            Tick::Hold => return R::ZERO,
            Tick::Start(since_on) => {
                self.x = x;
                self.lag.start();
                self.rate.start();
                self.dir.power_on(p, x, t0);
                self.power = -R::ONE;
                #[cfg(feature = "terms")]
                self.since_on.set(since_on);
                let w = self.warm.start(Step::new(since_on, p.warmup_tau_s));
                (R::ZERO, self.dir.value(), w)
            }
            Tick::Step(h) => {
                let dx = x - self.x;
                self.x = x;
                self.lag.step(Step::new(h, p.lag_tau_s), dx);
                let rate =
                    self.rate
                        .step(Step::new(h, p.rate_tau_s.abs()), dx, h, p.rate_zero_lag());
                let on_s = self.power;
                let powered_on = on_s >= R::ZERO;
                // across a power-on the estimator starts averaging again
                self.power = if powered_on { -R::ONE } else { on_s - h };
                let rate = if rate_settled(self.rate_age_s(), p.rate_tau_s) {
                    rate
                } else {
                    R::ZERO
                };
                let dir = self.dir.step(p.hysteresis_threshold_c, x);
                let w = if powered_on {
                    let on = on_s;
                    #[cfg(feature = "terms")]
                    self.since_on.set(on);
                    self.warm.start(Step::new(on, p.warmup_tau_s))
                } else {
                    #[cfg(feature = "terms")]
                    self.since_on.add(h);
                    self.warm.step(Step::new(h, p.warmup_tau_s))
                };
                (rate, dir, w)
            }
        };
        let half = R::from_f32(0.5) * dir;
        let ([r0, r1, r2], [h0, h1, h2], [d0, d1, d2]) = (p.rate, p.hysteresis, p.warmup);
        self.offset = [
            r0 * rate + h0 * half + d0 * w,
            r1 * rate + h1 * half + d1 * w,
            r2 * rate + h2 * half + d2 * w,
        ];
        rate
    }

    /// One sample at sensor temperature `x`, `dt` seconds after the previous one (or
    /// after power-on), reference temperature `t0`; returns whether the machines started
    /// or stepped.
    #[inline]
    pub fn sample(&mut self, p: &Physics<R>, x: R, dt: R, t0: R) -> bool {
        let tick = self.clock.tick(dt);
        let _ = self.apply(tick, p, x, t0);
        tick != Tick::Hold
    }

    /// The sensor was powered on again `since_s` seconds before the next sample (its
    /// power cycled while these machines kept their state): the warm-up clock starts
    /// again from there; the next sample steps the other machines across the gap (see the
    /// module's documentation). Before the first sample, nothing to do: the start is a
    /// power-on.
    pub fn power_on(&mut self, since_s: R) {
        if self.clock.started() {
            // a negative or NaN time is no time: the warm-up at full weight, as before
            self.power = if since_s > R::ZERO { since_s } else { R::ZERO };
            self.clock.force_step();
        }
    }

    /// Seconds stepped since the start or the last power-on, as of the last step (0 while
    /// a power-on is pending): how long the rate estimator has averaged.
    #[inline]
    pub fn rate_age_s(&self) -> R {
        if self.power < R::ZERO {
            -R::ONE - self.power
        } else {
            R::ZERO
        }
    }

    /// The temperature the coefficient model is evaluated at: the lagged element's, at
    /// the last step.
    #[inline]
    pub fn model_temperature(&self) -> R {
        self.x + self.lag.deviation()
    }

    /// The offsets of rate, hysteresis and warm-up (output units), at the last step.
    #[inline]
    pub fn offset(&self) -> [R; 3] {
        self.offset
    }

    /// The sensor temperature at the last step, C.
    #[inline]
    pub fn sensor_temperature(&self) -> R {
        self.x
    }

    /// The time since the latest power-on at the last step, s (with the `terms` feature).
    #[cfg(feature = "terms")]
    #[inline]
    pub fn since_power_on(&self) -> R {
        self.since_on.value()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(h: f64, tau: f64) -> Step<f64> {
        Step::new(h, tau)
    }

    #[test]
    fn low_pass_is_exact_for_a_ramp_at_any_spacing() {
        // tau y' = x - y with x = s t from y(0) = 0: y = s (t - tau (1 - exp(-t/tau)))
        let (tau, s) = (30.0, 0.05);
        for h in [0.1, 1.0, 7.0, 10.0, 45.0] {
            let mut lp = LowPass::<f64>::default();
            lp.start();
            let mut t = 0.0;
            for _ in 0..40 {
                lp.step(step(h, tau), s * h);
                t += h;
                let exact = s * (t - tau * (1.0 - (-t / tau).exp()));
                assert!((s * t + lp.deviation() - exact).abs() < 1e-12, "h {h}");
            }
        }
    }

    #[test]
    fn holding_the_new_reading_would_be_early_by_half_a_step() {
        // the bias this module's discretisation removes: the old form on a ramp settles
        // s (tau - h/2) behind (to second order in h/tau), the exact one s tau
        let (tau, s, h): (f64, f64, f64) = (30.0, 0.05, 10.0);
        let alpha = 1.0f64 - (-h / tau).exp();
        let (mut y, mut lp) = (0.0, LowPass::<f64>::default());
        for k in 1..400 {
            let x = s * h * k as f64;
            y += alpha * (x - y);
            lp.step(step(h, tau), s * h);
            if k == 399 {
                assert!(
                    ((x - y) - s * (tau - h / 2.0)).abs() < 0.03 * s * h,
                    "{}",
                    x - y
                );
                assert!((lp.deviation() + s * tau).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn rate_of_a_ramp_is_its_slope_at_any_spacing() {
        for zero_lag in [false, true] {
            for (h, tau) in [(0.1, 5.0), (1.0, 30.0), (10.0, 5.0), (3.3, 0.0)] {
                let mut r = Rate::<f64>::default();
                r.start();
                let mut last = 0.0;
                for _ in 0..2000 {
                    last = r.step(step(h, tau), 0.02 * h, h, zero_lag);
                }
                assert!(
                    (last - 0.02).abs() < 1e-12,
                    "zero-lag {zero_lag}, h {h} tau {tau}: {last}"
                );
            }
        }
    }

    /// On a temperature accelerating at `c` C/s^2 (`T = c t^2 / 2`) the low-pass's rate
    /// trails the true rate `c t` by `c tau`; the zero-lag one meets it (the step's own
    /// error aside: within `c h` here), at 10 Hz and at 1 kHz.
    #[test]
    fn the_zero_lag_rate_does_not_trail_an_accelerating_temperature() {
        let (tau, c) = (2.0, 1e-3);
        for h in [0.1, 0.001] {
            let (mut lp, mut zl) = (Rate::<f64>::default(), Rate::<f64>::default());
            lp.start();
            zl.start();
            let n = (60.0 / h) as usize;
            let (mut last_lp, mut last_zl) = (0.0, 0.0);
            for k in 1..=n {
                let t = k as f64 * h;
                let dx = c * (t * t - (t - h) * (t - h)) / 2.0;
                last_lp = lp.step(step(h, tau), dx, h, false);
                last_zl = zl.step(step(h, tau), dx, h, true);
            }
            // the rate at the step's middle, where a difference over the step is exact
            let truth = c * (n as f64 * h - h / 2.0);
            assert!(
                (last_lp - (truth - c * tau)).abs() < 1e-3 * c * tau,
                "h {h}: low-pass {last_lp} against {truth}"
            );
            assert!(
                (last_zl - truth).abs() < c * h + 1e-9,
                "h {h}: zero-lag {last_zl} against {truth}"
            );
        }
    }

    #[test]
    fn direction_follows_changes_beyond_the_threshold() {
        let mut d = Direction::<f64>::default();
        d.start(-1.0, 20.0, 0.5);
        let seq = [20.0, 20.3, 20.6, 21.0, 25.0, 24.8, 24.4, 23.0, 23.2];
        let got: Vec<f64> = seq.iter().map(|t| d.step(0.5, *t)).collect();
        assert_eq!(got, [-1.0, -1.0, 1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0]);
    }

    /// A play operator of half-width 2 C (threshold -2): linear over 4 C after a
    /// reversal, held where the temperature turns inside the band, saturated beyond;
    /// the f32 machine within 2 ulp of 1 (its error bound) of the exact values.
    #[test]
    fn a_play_operator_moves_linearly_over_its_width() {
        let seq = [
            20.0, 21.0, 22.0, 23.0, 26.0, 25.0, 24.0, 24.5, 22.0, 20.0, 19.0,
        ];
        let want = [-1.0, -0.5, 0.0, 0.5, 1.0, 0.5, 0.0, 0.25, -1.0, -1.0, -1.0];
        let mut d = Direction::<f64>::default();
        d.start(-1.0, 20.0, -2.0);
        let got: Vec<f64> = seq.iter().map(|t| d.step(-2.0, *t)).collect();
        assert_eq!(got, want);
        // f32 against f64 on temperatures no binary fraction holds: within the stated
        // 2 ulp(|t| + d) / d
        let seq = [
            25.1, 23.7, 27.9, 84.7, 61.93, 58.3, 60.1, -37.3, -33.9, -35.2,
        ];
        for d in [3.0, 0.7] {
            let mut f = Direction::<f32>::default();
            let mut e = Direction::<f64>::default();
            f.start(1.0, 25.1, -d as f32);
            e.start(1.0, 25.1f32 as f64, -d);
            for t in seq {
                let (g, w) = (f.step(-d as f32, t as f32), e.step(-d, t as f32 as f64));
                let ulp = f64::from(f32::EPSILON) * (t.abs() + d);
                assert!(
                    (g as f64 - w).abs() <= 2.0 * ulp / d,
                    "{t} over {d}: {g} for {w}"
                );
            }
        }
        // a NaN temperature holds the output: the state is NaN for that step only
        assert!(d.step(-2.0, f64::NAN).is_nan());
        assert_eq!(d.step(-2.0, 19.0), -1.0);
    }

    #[test]
    fn warmup_is_the_exponential_of_the_time_since_power_on() {
        let mut w = Warmup::<f64>::default();
        assert_eq!(w.start(step(0.0, 100.0)), 1.0);
        let mut t = 0.0;
        for h in [0.1, 0.5, 13.0, 2.0, 100.0] {
            t += h;
            let got = w.step(step(h, 100.0));
            assert!((got - (-t / 100.0f64).exp()).abs() < 1e-15);
        }
        assert!((w.start(step(50.0, 100.0)) - (-0.5f64).exp()).abs() < 1e-15);
        assert_eq!(
            w.start(step(1.0, 0.0)),
            0.0,
            "no time constant: no warm-up term"
        );
    }

    #[test]
    fn two_poles_lag_more_than_one() {
        let (mut one, mut two) = (Lag::<f64>::default(), Lag::<f64>::default());
        one.start();
        two.start();
        let none = step(1.0, 0.0);
        let (a, b) = (
            one.step(step(1.0, 10.0), none, 10.0, 10.0),
            two.step(step(1.0, 10.0), step(1.0, 10.0), 10.0, 10.0),
        );
        assert!(a > b && b > 0.0, "{a} {b}");
    }

    #[test]
    fn the_clock_steps_on_at_least_the_minimum_step() {
        let mut c = Clock::<f32>::default();
        assert_eq!(c.tick(0.5), Tick::Start(0.5));
        let mut held = 0;
        let mut steps = 0;
        for _ in 0..1000 {
            match c.tick(0.01) {
                Tick::Hold => held += 1,
                Tick::Step(h) => {
                    steps += 1;
                    assert!((h - 0.1).abs() < 1e-6, "{h}");
                }
                Tick::Start(_) => unreachable!(),
            }
        }
        assert_eq!((steps, held), (100, 900), "every 10th sample at 100 Hz");
        c.wait(0.3);
        assert!(matches!(c.tick(0.01), Tick::Step(h) if (h - 0.31).abs() < 1e-6));
        c.restart();
        assert!(matches!(c.tick(2.0), Tick::Start(t) if t == 2.0));
        c.force_step();
        assert!(matches!(c.tick(0.001), Tick::Step(t) if t == 0.001));
        assert_eq!(c.tick(0.001), Tick::Hold);
    }

    /// A power cycle of the sensor restarts the warm-up clock at the power-on, and the
    /// rate's settling: the lag, the rate's estimator and the hysteresis run on, the next
    /// step spanning the gap; the rate reads 0 until the estimator has averaged
    /// [`RATE_SETTLE_TAUS`] time constants again, then as if there had been no power-on.
    #[test]
    fn a_power_on_restarts_the_warm_up_only() {
        let p = Physics::<f64> {
            lag_tau_s: 100.0,
            rate: [1.0, 0.0, 0.0],
            rate_tau_s: 10.0,
            hysteresis: [0.0, 1.0, 0.0],
            hysteresis_threshold_c: 0.5,
            warmup: [0.0, 0.0, 1.0],
            warmup_tau_s: 1000.0,
            ..Physics::neutral()
        };
        let (mut a, mut b) = (Machines::<f64>::default(), Machines::<f64>::default());
        for m in [&mut a, &mut b] {
            m.sample(&p, 20.0, 0.0, 20.0);
            for k in 1..600 {
                m.sample(&p, 20.0 + 0.01 * k as f64, 1.0, 20.0);
            }
        }
        // a was off for the last 300 s before its next sample; b never was
        a.power_on(300.0);
        a.sample(&p, 26.0, 301.0, 20.0);
        b.sample(&p, 26.0, 301.0, 20.0);
        assert_eq!(a.model_temperature(), b.model_temperature());
        assert_eq!(a.offset()[1], b.offset()[1]);
        assert_eq!(a.offset()[0], 0.0);
        assert!(b.offset()[0] > 0.0);
        assert!((a.offset()[2] - (-0.3f64).exp()).abs() < 1e-12);
        assert!((b.offset()[2] - (-0.9f64).exp()).abs() < 1e-9);
        // the estimator (10 s) settles after five of its time constants, at most
        // RATE_SETTLE_MAX_S: 19 s on it has not, 20 s on it has
        for k in 1..=40 {
            for m in [&mut a, &mut b] {
                m.sample(&p, 26.0 + 0.01 * k as f64, 1.0, 20.0);
            }
            assert_eq!(a.offset()[0] == b.offset()[0], k >= 20, "{k} s after");
        }
        assert!(a.offset()[0] > 0.0);
    }

    /// The rate's age counts the seconds stepped since the start or a power-on on any
    /// step length (a power-on pending: 0); the rate settles after
    /// [`RATE_SETTLE_TAUS`] time constants, a plain difference at once.
    #[test]
    fn the_rate_settles_on_the_clock_after_a_start_or_a_power_on() {
        let p = Physics::<f32> {
            rate: [1.0, 0.0, 0.0],
            rate_tau_s: -4.0,
            ..Physics::neutral()
        };
        for h in [0.001f32, 0.01, 0.1, 1.0] {
            let mut m = Machines::<f32>::default();
            m.sample(&p, 20.0, 0.0, 20.0);
            assert_eq!(m.rate_age_s(), 0.0);
            for _ in 0..(12.0 / h).round() as usize {
                m.sample(&p, 20.0, h, 20.0);
            }
            // held between steps of at least MIN_STEP_S: within one step of 12 s
            let age = m.rate_age_s();
            assert!(
                age <= 12.001 && age > 12.0 - h.max(MIN_STEP_S) - 1e-3,
                "{h}: {age}"
            );
            m.power_on(5.0);
            assert_eq!(m.rate_age_s(), 0.0, "{h}: pending");
            m.sample(&p, 20.0, h, 20.0);
            assert_eq!(m.rate_age_s(), 0.0, "{h}: across the power-on");
        }
        assert!(!rate_settled(19.9f32, 4.0) && rate_settled(19.99f32, 4.0));
        assert!(
            rate_settled(20.0f32, -4.0),
            "the zero-lag estimator's time constant"
        );
        assert!(rate_settled(0.0f32, 0.0));
        assert!(!rate_settled(f32::NAN, 0.0), "a NaN age is never settled");
        assert!(
            !rate_settled(19.9f32, 60.0) && rate_settled(19.99f32, 60.0),
            "at most 20 s"
        );
    }

    /// The time since power-on in f32: a day of 0.1 s steps summed with the compensation
    /// term stays within 2 eps of the exact sum of the (f32) steps, where a plain f32
    /// sum is off by seconds; and the machines keep it, a power-on restarting it.
    #[cfg(feature = "terms")]
    #[test]
    fn elapsed_time_keeps_its_digits() {
        let (mut e, mut plain, mut exact) = (Elapsed::<f32>::default(), 0.0f32, 0.0f64);
        let h = 0.1f32;
        for _ in 0..864_000 {
            e.add(h);
            plain += h;
            exact += f64::from(h);
        }
        let rel = (f64::from(e.value()) - exact).abs() / exact;
        assert!(rel <= 2.0 * f64::from(f32::EPSILON) / 2.0, "{rel:e}");
        assert!((f64::from(plain) - exact).abs() > 1.0, "a plain sum drifts");
        let p = Physics::<f32>::neutral();
        let mut m = Machines::<f32>::default();
        m.sample(&p, 20.0, 5.0, 20.0);
        assert_eq!(m.since_power_on(), 5.0);
        for _ in 0..1000 {
            m.sample(&p, 20.0, 0.01, 20.0);
        }
        assert!(
            (m.since_power_on() - 15.0).abs() < 1e-4,
            "{}",
            m.since_power_on()
        );
        m.power_on(2.0);
        m.sample(&p, 20.0, 0.01, 20.0);
        assert_eq!(m.since_power_on(), 2.0);
        // a negative or NaN time since power-on is none
        m.power_on(f32::NAN);
        m.sample(&p, 20.0, 0.01, 20.0);
        assert_eq!(m.since_power_on(), 0.0);
    }

    #[test]
    fn the_power_on_direction_is_the_way_from_t0() {
        let p = Physics::<f64> {
            hysteresis_threshold_c: 0.5,
            hysteresis_initial: 1.0,
            ..Physics::neutral()
        };
        assert_eq!(power_on_direction(&p, -30.0, 20.0), -1.0);
        assert_eq!(power_on_direction(&p, 45.0, 20.0), 1.0);
        assert_eq!(power_on_direction(&p, 19.8, 20.0), 1.0);
        let q = Physics {
            hysteresis_initial: -1.0,
            ..p
        };
        assert_eq!(power_on_direction(&q, 20.3, 20.0), -1.0);
    }

    /// A play operator (half-width 4 C, cooled before the first change) powered on as if
    /// it had moved straight from T0: its state is continuous in the temperature (the
    /// initial state at T0, +1 only from 8 C above), where the relay's rule would jump
    /// from -1 to +1 at 4 C; a relay powers on as [`power_on_direction`] says.
    #[test]
    fn a_play_operator_powers_on_as_if_moved_from_t0() {
        let play = Physics::<f64> {
            hysteresis_threshold_c: -4.0,
            hysteresis_initial: -1.0,
            ..Physics::neutral()
        };
        let on = |p: &Physics<f64>, x: f64| {
            let mut d = Direction::default();
            d.power_on(p, x, 20.0);
            d.value()
        };
        let want = [
            (20.0, -1.0),
            (17.0, -1.0),
            (10.0, -1.0),
            (23.96, -0.01),
            (24.04, 0.01),
            (26.0, 0.5),
            (28.0, 1.0),
            (35.0, 1.0),
        ];
        for (x, w) in want {
            let got = on(&play, x);
            assert!((got - w).abs() < 1e-12, "{x}: {got} for {w}");
        }
        let relay = Physics {
            hysteresis_threshold_c: 4.0,
            ..play
        };
        for x in [17.0, 20.0, 23.96, 24.04, 35.0] {
            assert_eq!(on(&relay, x), power_on_direction(&relay, x, 20.0), "{x}");
        }
        assert_eq!(on(&relay, 24.04), 1.0);
    }

    /// The machines in f32 at 10 Hz, 100 Hz and 1 kHz against f64 at 10 Hz, on a fast
    /// warming and cooling with a 900 s lag, a 10 s rate (and a 2 s zero-lag one: the
    /// flight's is 4 s, the shorter the noisier) and a 1800 s warm-up: the model
    /// temperature within 2e-3 C and the rate within 1e-5 C/s at every step of the
    /// reference (held between steps: compared at the reference's step times). The
    /// relay's direction exactly; a play operator over 6 C (its state's f32 bound, 2
    /// ulp(|t| + d) / d, is 5e-6 here) within 1e-5.
    #[test]
    fn f32_machines_follow_f64_at_every_rate() {
        for (rate_tau_s, threshold) in [(10.0, 0.5), (-2.0, 0.5), (-2.0, -3.0)] {
            f32_machines_follow_f64_with(rate_tau_s, threshold);
        }
    }

    fn f32_machines_follow_f64_with(rate_tau_s: f64, threshold: f64) {
        let p64 = Physics::<f64> {
            lag_tau_s: 900.0,
            rate: [1.0, 0.0, 0.0],
            rate_tau_s,
            hysteresis: [0.0, 1.0, 0.0],
            hysteresis_threshold_c: threshold,
            hysteresis_initial: -1.0,
            k2: [0.0; 3],
            asymmetry: [0.0; 3],
            warmup: [0.0, 0.0, 1.0],
            warmup_tau_s: 1800.0,
        };
        let p32: Physics<f32> = p64.convert();
        // -20 C, warm at 5 C/min to 60 C, hold, cool at 3 C/min to 0 C: 3600 s
        let temp = |t: f64| {
            if t < 960.0 {
                -20.0 + 5.0 * t / 60.0
            } else if t < 1600.0 {
                60.0
            } else {
                (60.0 - 3.0 * (t - 1600.0) / 60.0).max(0.0)
            }
        };
        let mut reference = Machines::<f64>::default();
        let mut at = Vec::new();
        for k in 0..36_000 {
            let t = 0.1 * k as f64;
            reference.sample(&p64, temp(t), if k == 0 { 0.0 } else { 0.1 }, 20.0);
            at.push((reference.model_temperature(), reference.offset()));
        }
        for hz in [10u32, 100, 1000] {
            let per = (hz / 10) as usize;
            let mut m = Machines::<f32>::default();
            let dt = 1.0 / hz as f32;
            let (mut worst_t, mut worst_r) = (0.0f64, 0.0f64);
            for k in 0..36_000 * per {
                let t = k as f64 / f64::from(hz);
                m.sample(&p32, temp(t) as f32, if k == 0 { 0.0 } else { dt }, 20.0);
                if k % per == 0 {
                    let (tm, off) = at[k / per];
                    worst_t = worst_t.max((f64::from(m.model_temperature()) - tm).abs());
                    worst_r = worst_r.max((f64::from(m.offset()[0]) - off[0]).abs());
                    let dir = (f64::from(m.offset()[1]) - off[1]).abs();
                    let bound = if threshold < 0.0 { 1e-5 } else { 0.0 };
                    assert!(dir <= bound, "{hz} Hz direction at {t}: off by {dir}");
                    assert!(
                        (f64::from(m.offset()[2]) - off[2]).abs() < 1e-5,
                        "{hz} Hz warm-up"
                    );
                }
            }
            eprintln!("{hz} Hz, rate tau {rate_tau_s} s, threshold {threshold} C: model temperature within {worst_t:.2e} C, rate within {worst_r:.2e} C/s of f64");
            assert!(
                worst_t < 2e-3,
                "{hz} Hz: model temperature off by {worst_t} C"
            );
            assert!(worst_r < 1e-5, "{hz} Hz: rate off by {worst_r} C/s");
        }
    }
}
