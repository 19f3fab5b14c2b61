//! The regressors of the in-flight effects, made by stepping firmware-core's own state
//! machines (`firmware_core::inflight`) over the recording's rows on its own clock (each
//! row's time step, the stated power-ons), with the firmware's discretisation, so the
//! diagnosis fits exactly what the firmware will apply on any row spacing; plus the
//! recording's restart events.
use crate::data::recording::Recording;
use crate::model::rules::Rules;
use firmware_core::inflight::{
    power_on_direction, Clock, Direction, Lag, Rate, Step, Tick, Warmup,
};
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
/// `on(tick, temp)` is called at a start or a step and returns the machine's output,
/// held between steps.
fn drive(rec: &Recording, mut on: impl FnMut(Tick<f64>, f64) -> f64) -> Vec<f64> {
    let mut clock = Clock::<f64>::default();
    let mut held = 0.0;
    rec.rows
        .iter()
        .zip(rec.clock())
        .map(|(r, c)| {
            if c.power_on_s.is_some() && clock.started() {
                clock.force_step();
            }
            let tick = clock.tick(c.dt_s);
            if tick != Tick::Hold {
                held = on(tick, r.temp_c);
            }
            held
        })
        .collect()
}

/// Per row, each axis's element temperature through the lag of time constants
/// `taus[axis] = [tau1, tau2]` (tau2 = 0: one pole), as the firmware steps it.
pub fn lagged(rec: &Recording, taus: &[[f64; 2]; 3]) -> [Vec<f64>; 3] {
    std::array::from_fn(|axis| {
        let (mut lag, mut x) = (Lag::<f64>::default(), 0.0);
        let [t1, t2] = taus[axis];
        drive(rec, |tick, t| {
            let out = match tick {
                Tick::Step(h) => lag.step(Step::new(h, t1), Step::new(h, t2), t, t - x),
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

/// Per row, the firmware's rate estimate (C/s) with low-pass time constant `tau_s`.
pub fn rates(rec: &Recording, tau_s: f64) -> Vec<f64> {
    let (mut m, mut x) = (Rate::<f64>::default(), 0.0);
    drive(rec, |tick, t| {
        let out = match tick {
            Tick::Step(h) => m.step(Step::new(h, tau_s), t - x, h),
            _ => {
                m.start();
                0.0
            }
        };
        x = t;
        out
    })
}

/// Per row, the hysteresis direction (threshold in C; at the first row the state the
/// firmware takes at power-on: `initial` within the threshold of the recording's T0, else
/// the way from T0, `firmware_core::inflight::power_on_direction`).
pub fn directions(rec: &Recording, threshold_c: f64, initial: f64) -> Vec<f64> {
    let mut m = Direction::default();
    let p = Physics {
        hysteresis_threshold_c: threshold_c,
        hysteresis_initial: initial,
        ..Physics::neutral()
    };
    drive(rec, |tick, t| match tick {
        Tick::Step(_) => m.step(threshold_c, t),
        _ => {
            m.start(power_on_direction(&p, t, rec.t0_c), t);
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
