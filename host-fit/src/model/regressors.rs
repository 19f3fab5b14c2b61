//! The regressors of the in-flight effects, made by stepping firmware-core's own state
//! machines (`firmware_core::inflight`) over the recording's rows on its own clock (each
//! row's time step, the stated power-ons), with the firmware's discretisation, so the
//! diagnosis fits what the firmware will apply on any row spacing, except across an
//! unlogged gap: there the lag is carried along the sensor's bend ([`Cubic`]), which the
//! host sees in the rows on both sides and the firmware in flight cannot, and the rate
//! of the diagnosis's own low-pass after a power-on, which is not held at 0 as the
//! firmware's is ([`rates`]); plus the recording's restart events.
use crate::data::recording::Recording;
use crate::model::rules::Rules;
use firmware_core::inflight::{rate_settled, Clock, Direction, Lag, Rate, Step, Tick, Warmup};
use firmware_core::temperature::Physics;

/// Where a warm-up clock may restart: after gaps in the recording, and after handling.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Events {
    /// First row after each gap.
    pub gaps: Vec<usize>,
    /// First row after each handling run.
    pub handling: Vec<usize>,
}

/// The recording's gaps (a step of [`Rules::gap_factor`] times the median one, and at
/// least [`Rules::gap_min_s`]: the unit may have been powered off) and handling runs (a
/// `-` run longer than [`Rules::handling_s`]: the unit re-mounted, turned by hand).
pub fn events(rec: &Recording, rules: &Rules) -> Events {
    let step = rec.median_step_s();
    let mut e = Events::default();
    let rows = &rec.rows;
    for k in 1..rows.len() {
        if rows[k].t_s - rows[k - 1].t_s > (rules.gap_factor * step).max(rules.gap_min_s) {
            e.gaps.push(k);
        }
    }
    let mut k = 0;
    while k < rows.len() {
        if rows[k].position.is_none() {
            let s = k;
            while k < rows.len() && rows[k].position.is_none() {
                k += 1;
            }
            let end_t = rows
                .get(k)
                .map(|r| r.t_s)
                .unwrap_or(rows[rows.len() - 1].t_s);
            if end_t - rows[s].t_s > rules.handling_s && k < rows.len() {
                e.handling.push(k);
            }
            continue;
        }
        k += 1;
    }
    e
}

/// Runs a machine over the recording on the firmware's clock: each row's time step and
/// the stated power-ons ([`Recording::clock`]) through firmware-core's [`Clock`], so the
/// machine starts and steps at the rows where the firmware's would (a power-on steps at
/// its row, across the gap, as `Compensator::power_on` makes the firmware do).
/// `on(tick, age, row, temp)` is called at a start or a step (`age`: the seconds stepped
/// since the start or the last power-on, as `Machines::rate_age_s` counts them) and
/// returns the machine's output, held between steps.
fn drive(rec: &Recording, mut on: impl FnMut(Tick<f64>, f64, usize, f64) -> f64) -> Vec<f64> {
    let mut clock = Clock::<f64>::default();
    let (mut held, mut age, mut powered_on) = (0.0, 0.0, false);
    rec.rows
        .iter()
        .zip(rec.clock())
        .enumerate()
        .map(|(k, (r, c))| {
            if c.power_on_s.is_some() && clock.started() {
                clock.force_step();
                powered_on = true;
            }
            let tick = clock.tick(c.dt_s);
            // the age as `Machines` keeps it: 0 at the start and across a power-on
            match tick {
                Tick::Start(_) => age = 0.0,
                Tick::Step(_) if powered_on => {
                    age = 0.0;
                    powered_on = false;
                }
                Tick::Step(h) => age += h,
                Tick::Hold => {}
            }
            if tick != Tick::Hold {
                held = on(tick, age, k, r.temp_c);
            }
            held
        })
        .collect()
}

/// An unlogged stretch this long or longer (s) is crossed by [`Cubic`] when it is at a
/// stated power-on, or [`GAP_STEPS`] times the recording's median step: within a few
/// logged rows the sensor's temperature is as straight as the rows show it, and the
/// chamber's and the case's time constants (minutes) bend it only over longer stretches.
/// These are the numerical method's constants, not judgements of the data, so they are
/// not [`Rules`]; and lower than the warm-up's restart gap ([`events`]: ten median steps
/// and more than a minute), since a straight crossing errs on any bent stretch while a
/// restart is a claim about the unit.
const GAP_CROSSING_MIN_S: f64 = 60.0;
/// See [`GAP_CROSSING_MIN_S`]: a step of this many median steps is a gap, not the
/// logger's own pace.
const GAP_STEPS: f64 = 5.0;
/// The sensor's slope at each end of a gap is fitted over the rows within this (s) of
/// the end: a few of the twin's slowest rows (0.1 Hz at rest), short beside the case's
/// time constant (600 s), long enough that a quantised sensor's steps average out.
const GAP_SLOPE_WINDOW_S: f64 = 120.0;
/// The cubic is followed in straight pieces of at most this (s): the lag's step is exact
/// for a straight input, and over 10 s a cubic of the case's bend is straight to well
/// under the sensor's noise.
const GAP_PIECE_S: f64 = 10.0;
/// At most this many pieces per gap: a stretch of days (recordings joined weeks apart)
/// is crossed in longer pieces, the lag having long forgotten its start.
const GAP_MAX_PIECES: f64 = 1000.0;

/// The sensor's temperature across an unlogged gap, as the host estimates it: the cubic
/// (Hermite) through the straight lines the rows beside each end show (fitted over
/// [`GAP_SLOPE_WINDOW_S`], each taken at its rows' mean time, where a line's value and
/// slope are a smooth curve's to second order; at the gap's end itself its slope would
/// be off by the curve's bend over half the window; a side with fewer than three rows
/// there takes the chord across the gap, and with both sides so the crossing is
/// straight). The firmware in flight steps a power-on's gap straight (it has no rows
/// after it yet); the host has the recording's rows on both sides, and a gap
/// met while the case still settles after a ramp bends: crossed straight, the lag's
/// element temperature after it is wrong by a share of the bend, which a fit takes out
/// of the lag's time constant and the terms beside it (a rate term on one twin: its
/// time constant 0.7 % short, its `r` 1.6 % high). Only the lag is carried along it:
/// the rate estimator and the hysteresis's direction see the gap's chord as the
/// firmware does (the rate's low-pass forgets it within a minute or two, and a
/// direction changes only with the temperature's net travel).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cubic {
    /// The knots: the mean times of the rows before and after the gap, s.
    pub knots_s: [f64; 2],
    /// The lines' temperatures there, C.
    pub values_c: [f64; 2],
    /// Their slopes, C/s.
    pub slopes_c_per_s: [f64; 2],
    /// The gap's length (its rows' step), s.
    pub span_s: f64,
}

impl Cubic {
    /// The temperature at time `t_s`, C.
    pub fn at(&self, t_s: f64) -> f64 {
        let [t0, t1] = self.knots_s;
        let w = t1 - t0;
        let u = (t_s - t0) / w;
        let (u2, u3) = (u * u, u * u * u);
        let [a, b] = self.values_c;
        let [ma, mb] = self.slopes_c_per_s.map(|m| m * w);
        (2.0 * u3 - 3.0 * u2 + 1.0) * a
            + (u3 - 2.0 * u2 + u) * ma
            + (-2.0 * u3 + 3.0 * u2) * b
            + (u3 - u2) * mb
    }
}

/// A straight line fitted to the sensor's rows: at the rows' mean time, its value and
/// slope.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Line {
    t_s: f64,
    value_c: f64,
    slope_c_per_s: f64,
}

/// Per row, the cubic that crosses the gap ending at that row, where one does (see
/// [`GAP_CROSSING_MIN_S`]).
pub fn gap_crossings(rec: &Recording) -> Vec<Option<Cubic>> {
    let long = (GAP_STEPS * rec.median_step_s()).max(GAP_CROSSING_MIN_S);
    rec.clock()
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let span = c.dt_s;
            let crossed =
                k > 0 && (span >= long || (c.power_on_s.is_some() && span >= GAP_CROSSING_MIN_S));
            if !crossed {
                return None;
            }
            let rows = &rec.rows;
            let chord = (rows[k].temp_c - rows[k - 1].temp_c) / span;
            let end = |j: usize| Line {
                t_s: rows[j].t_s,
                value_c: rows[j].temp_c,
                slope_c_per_s: chord,
            };
            let (a, b) = match (line_near(rec, k - 1, false), line_near(rec, k, true)) {
                (None, None) => return None,
                (a, b) => (a.unwrap_or_else(|| end(k - 1)), b.unwrap_or_else(|| end(k))),
            };
            Some(Cubic {
                knots_s: [a.t_s, b.t_s],
                values_c: [a.value_c, b.value_c],
                slopes_c_per_s: [a.slope_c_per_s, b.slope_c_per_s],
                span_s: span,
            })
        })
        .collect()
}

/// The line through the sensor's rows within [`GAP_SLOPE_WINDOW_S`] of row `k`, before
/// it or (`after`) after it, by least squares; None with fewer than three rows there (a
/// slope of two noisy rows is noise).
fn line_near(rec: &Recording, k: usize, after: bool) -> Option<Line> {
    let rows = &rec.rows;
    let t0 = rows[k].t_s;
    let near = |j: &usize| (rows[*j].t_s - t0).abs() <= GAP_SLOPE_WINDOW_S;
    let side: Vec<usize> = if after {
        (k..rows.len()).take_while(near).collect()
    } else {
        (0..=k).rev().take_while(near).collect()
    };
    if side.len() < 3 {
        return None;
    }
    let n = side.len() as f64;
    let mt = side.iter().map(|&j| rows[j].t_s - t0).sum::<f64>() / n;
    let my = side.iter().map(|&j| rows[j].temp_c).sum::<f64>() / n;
    let (sxy, sxx) = side.iter().fold((0.0, 0.0), |(sxy, sxx), &j| {
        let dt = rows[j].t_s - t0 - mt;
        (sxy + dt * (rows[j].temp_c - my), sxx + dt * dt)
    });
    (sxx > 0.0).then(|| Line {
        t_s: t0 + mt,
        value_c: my,
        slope_c_per_s: sxy / sxx,
    })
}

/// Per row, each axis's element temperature through the lag of time constants
/// `taus[axis] = [tau1, tau2]` (tau2 = 0: one pole), as the firmware steps it, except
/// that an unlogged gap is crossed along its [`Cubic`] (the element's physics ran on
/// through it), from the last stepped row.
pub fn lagged(rec: &Recording, taus: &[[f64; 2]; 3]) -> [Vec<f64>; 3] {
    let crossings = gap_crossings(rec);
    std::array::from_fn(|axis| {
        let (mut lag, mut x) = (Lag::<f64>::default(), 0.0);
        let [t1, t2] = taus[axis];
        drive(rec, |tick, _, k, t| {
            let cubic = crossings.get(k).copied().flatten();
            let out = match (tick, cubic) {
                (Tick::Step(h), Some(c)) => {
                    // straight pieces along the cubic, the last ending at this row
                    // from the last stepped row (a held row before the gap is spanned)
                    let n = (h / GAP_PIECE_S).ceil().clamp(1.0, GAP_MAX_PIECES);
                    let piece = h / n;
                    let (mut from, mut out) = (x, t);
                    for i in 1..=(n as usize) {
                        let to = if i == n as usize {
                            t
                        } else {
                            c.at(rec.rows[k].t_s - h + piece * i as f64)
                        };
                        out = lag.step(Step::new(piece, t1), Step::new(piece, t2), to, to - from);
                        from = to;
                    }
                    out
                }
                (Tick::Step(h), None) => lag.step(Step::new(h, t1), Step::new(h, t2), t, t - x),
                _ => {
                    lag.start();
                    t
                }
            };
            x = t;
            out
        })
    })
}

/// Per row, the rate estimate (C/s) of a causal estimator of time constant `tau_s`.
///
/// Negative: the firmware's flight estimator, the zero-lag one of time constant
/// `|tau_s|` (as the blob's `rate_tau_s` says it,
/// `firmware_core::temperature::Physics::rate_zero_lag`), row by row what the firmware
/// gives: 0 until it has settled after the start and after each stated power-on
/// (`firmware_core::inflight::rate_settled`). Positive: a low-pass, 0 until settled
/// after the start only: the estimator the search judges a `temp_rate` with, and which
/// locates where the temperature moves ([`crate::model::data::Data::rate`]); the final
/// model describes the unit's physics with [`centred_rates`]
/// (`model::profile::centred_rate`). Across a stated power-off both step
/// the gap as the firmware does, so after a power-on in a ramp the low-pass already
/// holds the ramp's rate; the firmware's hold after a power-on is its caution against
/// one reading's noise, not the unit's physics: a unit switched on in a ramp feels the
/// rate at once, and a regressor held at 0 there leaves the rate's whole effect in the
/// residual (20 s at 80x the floor on a 1.5 C/min sweep), enough to make a hysteresis
/// beside it look inadequate where it acts. The `dTdt` of a discovered term is found
/// with the zero-lag estimator held after the start only
/// ([`crate::model::library::RATE_TAU_S`]) and flown with the flight's, or with the
/// catalogue rate's estimator where the unit has one.
pub fn rates(rec: &Recording, tau_s: f64) -> Vec<f64> {
    let flight = tau_s < 0.0;
    let hold = if flight {
        Settle::AfterEachPowerOn
    } else {
        Settle::AfterStart
    };
    rates_of(rec, tau_s.abs(), flight, hold)
}

/// Per row, the temperature's rate (C/s) the unit's physics is described with: the
/// slope of the least-squares line through the sensor's readings within `half_s` seconds
/// of the row on both sides (on one side at the recording's ends and beside a gap longer
/// than `half_s`; 0 where fewer than two readings differ in time).
///
/// Centred, not causal: the host has the whole recording, and a causal estimator trails
/// the rate where the case turns a ramp (`model::profile::centred_rate` says what that
/// cost). A centred slope does not trail: on a quadratic stretch of readings evenly
/// spaced it is the derivative at the row, its error of the order of `half_s^2` times the
/// third derivative, and its noise about `sigma sqrt(3 / n) / half_s` over `n` readings.
/// The firmware cannot look ahead; it measures the same rate with its zero-lag estimator
/// (`model::flashed::FLIGHT_RATE_TAU_S`), and `r` is the unit's, estimated here.
///
/// The sums run from an anchor moved every [`RESUM_ROWS`] rows and are then taken again,
/// so that no rounding accumulates over a long recording: the slope holds to 1e-9
/// relative of the direct sums (unit test).
pub fn centred_rates(rec: &Recording, half_s: f64) -> Vec<f64> {
    /// Least-squares sums of (time from the anchor, temperature).
    #[derive(Default)]
    struct Sums {
        n: f64,
        t: f64,
        tt: f64,
        y: f64,
        ty: f64,
    }
    impl Sums {
        fn add(&mut self, t: f64, y: f64, sign: f64) {
            self.n += sign;
            self.t += sign * t;
            self.tt += sign * t * t;
            self.y += sign * y;
            self.ty += sign * t * y;
        }
        fn slope(&self) -> f64 {
            if self.n < 2.0 {
                return 0.0;
            }
            let sxx = self.tt - self.t * self.t / self.n;
            let sxy = self.ty - self.t * self.y / self.n;
            // readings at one instant (or within rounding of it) carry no slope
            if sxx > 1e-9 * self.n {
                sxy / sxx
            } else {
                0.0
            }
        }
    }
    let rows = &rec.rows;
    let (mut lo, mut hi) = (0, 0);
    let (mut sums, mut anchor) = (Sums::default(), 0.0);
    let mut out = Vec::with_capacity(rows.len());
    for (k, row) in rows.iter().enumerate() {
        while let Some(r) = rows.get(hi).filter(|r| r.t_s <= row.t_s + half_s) {
            sums.add(r.t_s - anchor, r.temp_c, 1.0);
            hi += 1;
        }
        while let Some(r) = rows.get(lo).filter(|r| r.t_s < row.t_s - half_s) {
            sums.add(r.t_s - anchor, r.temp_c, -1.0);
            lo += 1;
        }
        if k % RESUM_ROWS == 0 {
            anchor = row.t_s;
            sums = Sums::default();
            for r in rows.get(lo..hi).unwrap_or_default() {
                sums.add(r.t_s - anchor, r.temp_c, 1.0);
            }
        }
        out.push(sums.slope());
    }
    out
}

/// How often [`centred_rates`] takes its sums again from a new anchor, rows.
const RESUM_ROWS: usize = 512;

/// Where a rate regressor is held at 0 until its estimator has settled
/// (`firmware_core::inflight::rate_settled`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Settle {
    /// After the recording's start only: the unit's physics, felt at once after a
    /// power-on (see [`rates`]).
    AfterStart,
    /// After the start and after each stated power-on, as the firmware holds it.
    AfterEachPowerOn,
}

/// Per row, the rate estimate (C/s) of time constant `tau_s` (not negative): the
/// zero-lag estimator (`zero_lag`) or the low-pass, stepped as the firmware steps them
/// (`firmware_core::inflight::Rate`), 0 until settled where `settle` says.
pub fn rates_of(rec: &Recording, tau_s: f64, zero_lag: bool, settle: Settle) -> Vec<f64> {
    // the sign is `rates`' flag for the flight's estimator, taken off before here
    debug_assert!(tau_s >= 0.0, "rates_of: tau_s {tau_s} is negative");
    let (mut m, mut x, mut run_s) = (Rate::<f64>::default(), 0.0, 0.0);
    drive(rec, |tick, age_s, _, t| {
        let out = match tick {
            Tick::Step(h) => {
                run_s += h;
                let r = m.step(Step::new(h, tau_s), t - x, h, zero_lag);
                let since = match settle {
                    Settle::AfterEachPowerOn => age_s,
                    Settle::AfterStart => run_s,
                };
                if rate_settled(since, tau_s) {
                    r
                } else {
                    0.0
                }
            }
            _ => {
                m.start();
                run_s = 0.0;
                0.0
            }
        };
        x = t;
        out
    })
}

/// Per row, the hysteresis direction (threshold in C; negative: a play operator of
/// half-width `-threshold_c`, its state in [-1, 1]; at the first row the state the
/// firmware takes at power-on, `firmware_core::inflight::Direction::power_on`: a relay
/// `initial` within the threshold of the recording's T0, else the way from T0; a play as
/// if moved from T0 in state `initial`).
pub fn directions(rec: &Recording, threshold_c: f64, initial: f64) -> Vec<f64> {
    let mut m = Direction::default();
    let p = Physics {
        hysteresis_threshold_c: threshold_c,
        hysteresis_initial: initial,
        ..Physics::neutral()
    };
    drive(rec, |tick, _, _, t| match tick {
        Tick::Step(_) => m.step(threshold_c, t),
        _ => {
            m.power_on(&p, t, rec.t0_c);
            m.value()
        }
    })
}

/// Per row, the warm-up weight `exp(-t_on / tau_s)`, its clock started at each power-on
/// (the first row, and the end of each stated power-off) as the firmware's is, and
/// also at the rows `restarts` (sorted: gaps or handling, the diagnosis's other forms).
pub fn warmup(rec: &Recording, tau_s: f64, restarts: &[usize]) -> Vec<f64> {
    let mut m = Warmup::<f64>::default();
    let mut next = restarts.iter().copied().peekable();
    let mut clock = Clock::<f64>::default();
    rec.clock()
        .into_iter()
        .enumerate()
        .map(|(k, c)| {
            if c.power_on_s.is_some() && clock.started() {
                clock.force_step();
            }
            let tick = clock.tick(c.dt_s);
            match (tick, c.power_on_s) {
                (Tick::Start(on), _) => {
                    m.start(Step::new(on, tau_s));
                }
                (Tick::Step(_), Some(on)) => {
                    m.start(Step::new(on, tau_s));
                }
                (Tick::Step(h), None) => {
                    m.step(Step::new(h, tau_s));
                }
                (Tick::Hold, _) => {}
            }
            if next.peek() == Some(&k) {
                next.next();
                // a restart the recording does not state: from this row, weight 1
                m.start(Step::new(0.0, tau_s));
            }
            m.value()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::positions::Positions;

    /// The centred slope is the derivative where the readings are even and the
    /// temperature quadratic (no trail at a turn, where a causal estimator trails), exact
    /// on a line however the rows fall (uneven, a gap longer than the window), and 0
    /// where a window holds one reading.
    #[test]
    fn the_centred_slope_is_the_derivative_without_a_trail() {
        let even: Vec<f64> = (0..400).map(|k| 10.0 * f64::from(k)).collect();
        let quad = |t: f64| 20.0 + 0.01 * t - 2e-6 * t * t;
        let r = centred_rates(&recording_of("", &even, quad), 60.0);
        for (k, t) in even
            .iter()
            .enumerate()
            .filter(|(_, t)| (60.0..=3930.0).contains(*t))
        {
            let want = 0.01 - 4e-6 * t;
            assert!((r[k] - want).abs() < 1e-9, "row {k}: {} for {want}", r[k]);
        }
        // the causal low-pass of 30 s trails a turning ramp by about its time constant
        let lp = rates(&recording_of("", &even, quad), 30.0);
        assert!(
            (lp[200] - (0.01 - 4e-6 * 2000.0)).abs() > 6e-5,
            "{}",
            lp[200]
        );
        // uneven rows, a gap of 300 s, a line: exact wherever two readings are in reach
        let mut uneven: Vec<f64> = (0..300)
            .map(|k| 10.0 * f64::from(k) + 3.0 * (f64::from(k) * 1.7).sin())
            .filter(|t| !(1000.0..1300.0).contains(t))
            .collect();
        uneven.push(5000.0);
        let r = centred_rates(&recording_of("", &uneven, |t| -40.0 + 0.0167 * t), 40.0);
        for (k, v) in r.iter().enumerate().take(uneven.len() - 1) {
            assert!((v - 0.0167).abs() < 1e-9, "row {k} at {}: {v}", uneven[k]);
        }
        assert_eq!(r.last(), Some(&0.0), "one reading in its window: no slope");
    }

    /// Over a long recording far from t = 0 the running sums, taken again every
    /// [`RESUM_ROWS`] rows, hold the slope of the direct sums to 1e-9 relative (a day at
    /// 1 Hz starting at 1e6 s, a noisy sine).
    #[test]
    fn the_centred_slope_holds_over_a_long_recording() {
        let ts: Vec<f64> = (0..86_400).map(|k| 1e6 + f64::from(k)).collect();
        let temp = |t: f64| 20.0 + 30.0 * (t / 5000.0).sin() + 0.03 * (t * 12.9898).sin();
        let rec = recording_of("", &ts, temp);
        let r = centred_rates(&rec, 90.0);
        let mut worst: f64 = 0.0;
        for k in (0..ts.len()).step_by(997) {
            let w: Vec<&crate::data::recording::Row> = rec
                .rows
                .iter()
                .filter(|x| (x.t_s - rec.rows[k].t_s).abs() <= 90.0)
                .collect();
            let n = w.len() as f64;
            let (mt, my) = (
                w.iter().map(|x| x.t_s).sum::<f64>() / n,
                w.iter().map(|x| x.temp_c).sum::<f64>() / n,
            );
            let sxy: f64 = w.iter().map(|x| (x.t_s - mt) * (x.temp_c - my)).sum();
            let sxx: f64 = w.iter().map(|x| (x.t_s - mt).powi(2)).sum();
            let direct = sxy / sxx;
            worst = worst.max((r[k] - direct).abs() / direct.abs().max(1e-4));
        }
        assert!(worst < 1e-9, "worst relative departure {worst:e}");
    }

    /// A case settling after a ramp (10 C below its set point, one time constant of
    /// 600 s), logged every 10 s, the unit powered off from 120 s to 720 s (no rows).
    /// With an element lagging the case by 600 s its temperature is
    /// 20 - 10 (1 + t/600) exp(-t/600).
    fn settling_with_a_power_off() -> Recording {
        let mut csv = String::from("# power_off_s=120-720\nt_s,position,temp_c,ux_v,uy_v,uz_v\n");
        let mut t: f64 = 0.0;
        while t <= 3000.0 {
            if !(120.0..720.0).contains(&t) {
                let c = 20.0 - 10.0 * (-t / 600.0).exp();
                csv.push_str(&format!("{t:.1},TP1,{c:.6},0.0,0.0,1.0\n"));
            }
            t += 10.0;
        }
        Recording::from_reader(
            std::path::Path::new("off.csv"),
            csv.as_bytes(),
            Positions::default(),
        )
        .unwrap()
    }

    /// Across the power-off the element's temperature is carried along the cubic: at the
    /// first row after it within 0.01 C of the truth (0.0055 C), where a straight crossing
    /// (the firmware's in flight) is off by more than 0.2 C (0.27 C).
    #[test]
    fn a_gap_while_the_case_settles_is_crossed_along_its_bend() {
        let rec = settling_with_a_power_off();
        let k = rec.rows.iter().position(|r| r.t_s >= 720.0).unwrap();
        assert_eq!(rec.rows[k - 1].t_s, 110.0);
        let truth = |t: f64| 20.0 - 10.0 * (1.0 + t / 600.0) * (-t / 600.0).exp();
        let crossings = gap_crossings(&rec);
        assert!(crossings[k].is_some());
        assert_eq!(crossings.iter().filter(|c| c.is_some()).count(), 1);
        let lag = lagged(&rec, &[[600.0, 0.0]; 3]);
        let cubic = (lag[0][k] - truth(720.0)).abs();
        // the same lag stepped straight across the gap from the row before it
        let mut straight = Lag::<f64>::default();
        straight.start();
        let (mut x, mut e) = (rec.rows[0].temp_c, 0.0);
        for r in &rec.rows[1..=k] {
            let h = r.t_s - rec.rows.iter().rev().find(|q| q.t_s < r.t_s).unwrap().t_s;
            e = straight.step(
                Step::new(h, 600.0),
                Step::new(h, 0.0),
                r.temp_c,
                r.temp_c - x,
            );
            x = r.temp_c;
        }
        let straight = (e - truth(720.0)).abs();
        assert!(cubic < 0.01, "along the cubic {cubic:.4} C off");
        assert!(straight > 0.2, "straight {straight:.4} C off");
        // long after the gap both forget it; the cubic's row stays near the truth
        assert!((lag[0][rec.rows.len() - 1] - truth(3000.0)).abs() < 0.01);
    }

    /// A recording of `temp(t)` at the times `times`, with `header` lines before the
    /// columns.
    fn recording_of(header: &str, times: &[f64], temp: impl Fn(f64) -> f64) -> Recording {
        let mut csv = format!("{header}t_s,position,temp_c,ux_v,uy_v,uz_v\n");
        for &t in times {
            csv.push_str(&format!("{t:.6},TP1,{:.12},0.0,0.0,1.0\n", temp(t)));
        }
        Recording::from_reader(
            std::path::Path::new("g.csv"),
            csv.as_bytes(),
            Positions::default(),
        )
        .unwrap()
    }

    /// On a straight ramp a crossing is exact however few rows a side has: a side with
    /// fewer than three rows takes the chord (a flat end would bend a straight ramp),
    /// and a logger too slow for any line crosses straight, as the firmware does.
    #[test]
    fn a_side_with_few_rows_takes_the_chord() {
        let ramp = |t: f64| 0.01 * t;
        // rows every 10 s up to 110 s, the power-off, then two rows only
        let mut times: Vec<f64> = (0..12).map(|i| 10.0 * f64::from(i)).collect();
        times.extend([720.0, 730.0]);
        let rec = recording_of("# power_off_s=120-720\n", &times, ramp);
        let k = rec.rows.len() - 2;
        let c = gap_crossings(&rec)[k].expect("crossed");
        for t in [200.0, 400.0, 650.0] {
            assert!((c.at(t) - ramp(t)).abs() < 1e-9, "{t}: {}", c.at(t));
        }
        // the lag through the ramp: tau * slope behind it once settled, exactly
        let lag = lagged(&rec, &[[60.0, 0.0]; 3]);
        let want = ramp(730.0) - 0.01 * 60.0 * (1.0 - (-730.0_f64 / 60.0).exp());
        assert!(
            (lag[0][k + 1] - want).abs() < 1e-6,
            "{} {want}",
            lag[0][k + 1]
        );
        // a logger writing every 5 minutes: no side has three rows within the window
        let slow: Vec<f64> = (0..20).map(|i| 300.0 * f64::from(i)).collect();
        let rec = recording_of("# power_off_s=3100-3300\n", &slow, ramp);
        assert!(gap_crossings(&rec).iter().all(Option::is_none));
    }

    /// The rate regressor is the firmware's: on a ramp logged every 2 s with a stated
    /// power-off, row by row what `Machines` gives through the same clock, 0 for five
    /// time constants after the start and after the power-on, then the ramp's slope
    /// (within 5 % at once, to 1e-6 after 100 s).
    #[test]
    fn the_rate_regressor_settles_as_the_firmware_does() {
        let rec = ramp_with_a_power_off((0..400).map(|i| 2.0 * f64::from(i)), [300.0, 400.0]);
        let tau = -4.0;
        let host = rates(&rec, tau);
        let p = Physics::<f64> {
            rate: [1.0, 0.0, 0.0],
            rate_tau_s: tau,
            ..Physics::neutral()
        };
        let mut m = firmware_core::inflight::Machines::<f64>::default();
        for (k, (r, c)) in rec.rows.iter().zip(rec.clock()).enumerate() {
            if let Some(on) = c.power_on_s {
                m.power_on(on);
            }
            m.sample(&p, r.temp_c, c.dt_s, 20.0);
            assert_eq!(host[k], m.offset()[0], "row {k} at {} s", r.t_s);
            let since = if r.t_s < 300.0 { r.t_s } else { r.t_s - 400.0 };
            if since < 19.0 {
                assert_eq!(host[k], 0.0, "{} s: not settled", r.t_s);
            } else if since > 21.0 {
                // the filters start settled, off the ramp's steady state: what is left of
                // that at five time constants (zero-lag: (1 + 5) e^-5 of it), then none
                let tol = if since < 100.0 { 0.05 } else { 1e-6 };
                assert!(
                    (host[k] - 0.02).abs() < tol * 0.02,
                    "{} s: {}",
                    r.t_s,
                    host[k]
                );
            }
        }
    }

    /// The ramp of [`the_rate_regressor_settles_as_the_firmware_does`] (0.02 C/s from
    /// -10 C) logged at `times`, the unit powered off over `off` (s; no rows there, the
    /// span stated).
    fn ramp_with_a_power_off(times: impl Iterator<Item = f64>, off: [f64; 2]) -> Recording {
        let times: Vec<f64> = times.filter(|t| !(off[0]..off[1]).contains(t)).collect();
        let header = format!("# power_off_s={}-{}\n", off[0], off[1]);
        recording_of(&header, &times, |t| -10.0 + 0.02 * t)
    }

    /// The diagnosis's low-pass (a positive time constant) is the unit's physics, not the
    /// firmware's caution: on the same ramp, logged unevenly (1-s rows jittered by up to
    /// 0.3 s in 50-s dwells, a row every 10 s between them) with a power-off, it is held at
    /// 0 after the start only, and at the first row after the power-on it already gives the
    /// ramp's slope (the gap stepped straight, the low-pass at the ramp's steady state),
    /// where the flight's estimator is held at 0 for 20 s.
    #[test]
    fn the_diagnosis_low_pass_feels_a_ramp_at_once_after_a_power_on() {
        let uneven = (0..1200u32).filter_map(|i| {
            let t = f64::from(i);
            let logged = t % 60.0 < 50.0 || i % 10 == 0;
            logged.then(|| t + 0.3 * (1.7 * t).sin())
        });
        let rec = ramp_with_a_power_off(uneven, [300.0, 700.0]);
        let tau = 40.0;
        let host = rates(&rec, tau);
        let flight = rates(&rec, -4.0);
        for (k, r) in rec.rows.iter().enumerate() {
            if r.t_s < 19.0 {
                assert_eq!(host[k], 0.0, "{} s: settling after the start", r.t_s);
            }
            if (700.0..720.0).contains(&r.t_s) {
                // the start's deficit is e^-7 of the rate at the power-off; the gap, ten
                // time constants, leaves none of it
                assert!(
                    (host[k] - 0.02).abs() < 1e-3 * 0.02,
                    "{} s: {}",
                    r.t_s,
                    host[k]
                );
                assert_eq!(flight[k], 0.0, "{} s: the flight's estimator holds", r.t_s);
            }
        }
    }

    /// A stretch of years between two rows is crossed in at most a thousand pieces.
    #[test]
    fn a_very_long_gap_is_crossed_in_few_pieces() {
        let mut times: Vec<f64> = (0..30).map(|i| 10.0 * f64::from(i)).collect();
        times.extend((0..30).map(|i| 1e9 + 10.0 * f64::from(i)));
        let rec = recording_of("", &times, |t| if t < 1e6 { 10.0 } else { 20.0 });
        let lag = lagged(&rec, &[[600.0, 0.0]; 3]);
        assert!((lag[0][30] - 20.0).abs() < 1e-6, "{}", lag[0][30]);
    }
}
