//! The in-flight state machines of the physics terms (physics-catalogue.md), written once:
//! the firmware steps them on every sample, and host-fit's diagnosis steps the very same
//! code over a recording to build its regressors, so what is flashed is what was fitted.
//!
//! Each machine takes its per-step constants from the caller (a low-pass `alpha =
//! 1 - exp(-dt / tau)`, a decay `exp(-dt / tau)`): the firmware uses the blob's
//! constants for its sample period, the host computes them for each row's actual time
//! step. No `exp` on the MCU (libm's `expf` works in f64 and would pull soft-double code
//! in). Every step is a fixed number of operations.
use crate::real::Real;

/// A first-order low-pass, `y += alpha (x - y)`.
///
/// Error bound (f32): one step adds at most `2 eps max(|y|, |x|)` (two roundings); the
/// filter is a contraction, so errors do not grow over steps (at most `2 eps max|x| /
/// alpha` accumulated in the steady state).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LowPass<R> {
    y: R,
}

impl<R: Real> LowPass<R> {
    /// Settle at `x` (the first input).
    #[inline]
    pub fn start(&mut self, x: R) {
        self.y = x;
    }

    /// Step with input `x`; returns the new output.
    #[inline]
    pub fn step(&mut self, alpha: R, x: R) -> R {
        self.y = self.y + alpha * (x - self.y);
        self.y
    }

    /// The output.
    pub fn value(&self) -> R {
        self.y
    }
}

/// `thermal_lag`: the sensing element's temperature as up to two cascaded first-order
/// lags of the sensor's (`alpha2 = 1` is a single pole).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Lag<R> {
    first: LowPass<R>,
    second: LowPass<R>,
}

impl<R: Real> Lag<R> {
    /// Settle at temperature `t`.
    pub fn start(&mut self, t: R) {
        self.first.start(t);
        self.second.start(t);
    }

    /// Step with the sensor temperature `t`; returns the element's.
    #[inline]
    pub fn step(&mut self, alpha1: R, alpha2: R, t: R) -> R {
        let a = self.first.step(alpha1, t);
        self.second.step(alpha2, a)
    }
}

/// `temp_rate`: the rate of the temperature, C/s, as the per-step change of its low-pass
/// (time constant tau_r) divided by the step's duration: a lagging, smoothed derivative
/// that needs one state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rate<R> {
    lp: LowPass<R>,
}

impl<R: Real> Rate<R> {
    /// Settle at temperature `t` (rate 0).
    pub fn start(&mut self, t: R) {
        self.lp.start(t);
    }

    /// Step with temperature `t` over a step of `dt_s` seconds; returns the rate.
    #[inline]
    pub fn step(&mut self, alpha: R, t: R, dt_s: R) -> R {
        let before = self.lp.y;
        (self.lp.step(alpha, t) - before) / dt_s
    }
}

/// `hysteresis`: the direction of the last temperature change larger than a threshold
/// (+1 heated to here, -1 cooled, the initial state until the first such change).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Direction<R> {
    dir: R,
    reference: R,
}

impl<R: Real> Direction<R> {
    /// In state `initial` (+1, -1, or 0 for unknown), at temperature `t`.
    pub fn start(&mut self, initial: R, t: R) {
        self.dir = initial;
        self.reference = t;
    }

    /// Step with temperature `t`; returns the direction. A change of more than
    /// `threshold` from the reference sets the direction; moving on in the same
    /// direction moves the reference with it (so a reversal is measured from the turn).
    #[inline]
    pub fn step(&mut self, threshold: R, t: R) -> R {
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
}

/// `warmup_drift`: the weight of the settling offset, 1 at power-on, multiplied by the
/// decay `exp(-dt / tau_w)` at every step.
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
    /// Returns the weight of this step, then decays it for the next.
    #[inline]
    pub fn step(&mut self, decay: R) -> R {
        let w = self.w;
        self.w = self.w * decay;
        w
    }

    /// Power-on again: the weight back to 1.
    pub fn restart(&mut self) {
        self.w = R::ONE;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn low_pass_starts_at_its_input_and_converges() {
        let mut lp = LowPass::<f64>::default();
        lp.start(10.0);
        assert_eq!(lp.step(0.5, 10.0), 10.0);
        assert_eq!(lp.step(0.5, 20.0), 15.0);
        for _ in 0..60 {
            lp.step(0.5, 20.0);
        }
        assert!((lp.value() - 20.0).abs() < 1e-12);
    }

    #[test]
    fn rate_of_a_ramp_settles_at_its_slope() {
        let mut r = Rate::<f64>::default();
        r.start(0.0);
        let alpha = 1.0 - (-1.0f64 / 30.0).exp();
        let mut last = 0.0;
        for k in 0..2000 {
            last = r.step(alpha, 0.02 * k as f64, 1.0);
        }
        assert!((last - 0.02).abs() < 1e-9, "{last}");
    }

    #[test]
    fn direction_follows_changes_beyond_the_threshold() {
        let mut d = Direction::<f64>::default();
        d.start(-1.0, 20.0);
        let seq = [20.0, 20.3, 20.6, 21.0, 25.0, 24.8, 24.4, 23.0, 23.2];
        let got: Vec<f64> = seq.iter().map(|t| d.step(0.5, *t)).collect();
        assert_eq!(got, [-1.0, -1.0, 1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0]);
    }

    #[test]
    fn warmup_decays_and_restarts() {
        let mut w = Warmup::<f64>::default();
        assert_eq!(w.step(0.5), 1.0);
        assert_eq!(w.step(0.5), 0.5);
        w.restart();
        assert_eq!(w.step(0.5), 1.0);
    }

    #[test]
    fn two_poles_lag_more_than_one() {
        let (mut one, mut two) = (Lag::<f64>::default(), Lag::<f64>::default());
        one.start(0.0);
        two.start(0.0);
        one.step(0.1, 1.0, 0.0);
        two.step(0.1, 0.1, 0.0);
        let (a, b) = (one.step(0.1, 1.0, 10.0), two.step(0.1, 0.1, 10.0));
        assert!(a > b && b > 0.0, "{a} {b}");
    }
}
