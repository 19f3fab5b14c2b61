//! Physics beyond the catalogue that a short product of what a recording measures can
//! express, and some that it cannot: each written as the physics it is, with its own
//! parameters, on the twin's own clock (every time in seconds since the recording's first
//! tick, every event at the tick the twin plays it). Independent of the diagnosis's term
//! vocabulary: a blind test of the term search must not share its assumptions.
//!
//! Unit physics (in flight too): the IEEE Std 1293 second-order terms of each output
//! (its own K2 and the cross-axis Kip, Kio, Kpp, Koo, Kpo terms), a K2 with a
//! temperature coefficient, a scale factor that moves with the rate of temperature change
//! (a gradient across the spring while the case heats or cools), a turn-on transient
//! whose size grows with the distance from T0, the turn-on to turn-on repeatability of the
//! bias, and a bias that jumps between two levels (random telegraph noise from a charge
//! trap). Rig physics (the bench only): a settling of the signal chain after each tilter
//! move (triboelectric charge of the output leads flexed through the tilter) and after the
//! chamber reaches each new stop (the voltmeter's self-calibration, run by the test
//! sequence at each stop, and its input stage settling back), and the tilter's position
//! repeatability (each time it comes to rest, a fresh small rotation).
use crate::rng::Rng;
use crate::simulate::beyond_config::Relaxation;
use crate::simulate::config::Effects;

/// The events and random states of this physics along the twin's clock: the last tilter
/// arrival, the last stop reached, the power-ons, the current rest's rotation and the
/// telegraph's level. Its own random numbers, so the voltmeter's noise is the same draw
/// with or without it.
#[derive(Debug, Clone)]
pub struct State {
    moved_s: Option<f64>,
    stopped_s: Option<f64>,
    on_s: f64,
    power_ons: usize,
    tilt: [f64; 2],
    high: bool,
    last_s: Option<f64>,
    rng: Rng,
}

impl State {
    /// The state at the recording's start (powered on at `t = 0`), its random numbers from
    /// `seed`.
    pub fn new(seed: u64) -> State {
        State {
            moved_s: None,
            stopped_s: None,
            on_s: 0.0,
            power_ons: 0,
            tilt: [0.0; 2],
            high: false,
            last_s: None,
            rng: Rng::new(seed ^ 0x00BE_700D),
        }
    }

    /// The tilter came to rest at `t` (the end of a move to another position): the leads'
    /// charge starts again and, with a repeatability, the unit stops at a fresh rotation.
    pub fn arrived(&mut self, e: &Effects, t: f64) {
        self.moved_s = Some(t);
        self.rest(e);
    }

    /// The tilter at rest where the recording starts (no move before it): its rotation
    /// only.
    pub fn rest(&mut self, e: &Effects) {
        self.tilt = match e.tilter_repeatability {
            Some(r) => [
                r.sigma_rad * self.rng.normal(),
                r.sigma_rad * self.rng.normal(),
            ],
            None => [0.0; 2],
        };
    }

    /// The chamber's set point reached a new stop at `t` (a hold after a ramp).
    pub fn stopped(&mut self, t: f64) {
        self.stopped_s = Some(t);
    }

    /// The rotation of the current rest, rad (zero without a repeatability).
    pub fn tilt(&self) -> [f64; 2] {
        self.tilt
    }

    /// Advance to `t` with the unit last powered on at `on_s`: count a new power-on, and
    /// let the telegraph switch over the time since the last call.
    pub fn advance(&mut self, e: &Effects, on_s: f64, t: f64) {
        if on_s != self.on_s {
            self.on_s = on_s;
            self.power_ons += 1;
        }
        if let Some(tg) = e.telegraph {
            let h = self.last_s.map_or(0.0, |l| (t - l).max(0.0));
            // the chance of a switch within h of an exponential holding time
            if tg.mean_s > 0.0 && self.rng.uniform() < -(-h / tg.mean_s).exp_m1() {
                self.high = !self.high;
            }
        }
        self.last_s = Some(t);
    }

    /// What this physics adds to output `i` at time `t` in orientation `a`: `k_ii` the
    /// output's scale factor (V/g), `temp` the element's temperature and `t0` the
    /// reference (C), `rate` the case's rate (C/s).
    #[allow(clippy::too_many_arguments)]
    pub fn output(
        &self,
        e: &Effects,
        i: usize,
        a: [f64; 3],
        k_ii: f64,
        temp: f64,
        t0: f64,
        rate: f64,
        t: f64,
    ) -> f64 {
        let mut u = 0.0;
        if let Some(q) = e.quadratic {
            let m = [
                a[0] * a[0],
                a[1] * a[1],
                a[2] * a[2],
                a[0] * a[1],
                a[0] * a[2],
                a[1] * a[2],
            ];
            u += q.value[i].iter().zip(m).map(|(c, x)| c * x).sum::<f64>();
        }
        if let Some(k) = e.k2_temp {
            u += k.value[i] * (temp - t0) * a[i] * a[i];
        }
        if let Some(s) = e.scale_rate {
            u += k_ii * s.value[i] * rate * 60.0 * a[i];
        }
        if let Some(w) = e.warmup_temp {
            u += w.v_per_c[i] * (temp - t0) * (-(t - self.on_s) / w.tau_s).exp();
        }
        if let Some(b) = &e.turn_on_bias {
            // the n-th power-off's value, the last one beyond the list
            let n = self.power_ons.min(b.value.len());
            if n > 0 {
                u += b.value.get(n - 1).map_or(0.0, |v| v[i]);
            }
        }
        let relax = |r: Option<Relaxation>, at: Option<f64>| match (r, at) {
            (Some(r), Some(at)) if t >= at => r.d_v[i] * (-(t - at) / r.tau_s).exp(),
            _ => 0.0,
        };
        u += relax(e.move_settle, self.moved_s);
        u += relax(e.stop_settle, self.stopped_s);
        if let (Some(tg), true) = (e.telegraph, self.high) {
            u += tg.value[i];
        }
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::beyond_config::{Quadratic, Repeatability, Telegraph, TempWarmup, TurnOn};
    use crate::simulate::config::{PerAxis, SimConfig, Stop};
    use crate::simulate::simulate;

    /// One row of a recording.
    #[derive(Debug, Clone)]
    struct Row {
        /// Time, s.
        t: f64,
        /// The position's name.
        pos: String,
        /// The temperature, C.
        temp: f64,
        /// The outputs.
        u: [f64; 3],
    }

    const H: f64 = std::f64::consts::FRAC_1_SQRT_2;
    /// Half a volt step of the voltmeter's resolution, and a little: what two runs with
    /// the same noise differ by besides the concealed term.
    const ROUND: f64 = 1.1e-7;

    /// A short test: from 20 C to one stop at -20 C at 4 C/min (600 s), a 600 s soak,
    /// then TP1..TP6 and two edge diagonals, E1 = (1, 1, 0)/sqrt 2 and E2 = (1, -1, 0)/sqrt
    /// 2, 70 s each.
    fn short(effects: Effects) -> SimConfig {
        let mut c = SimConfig::default();
        let pos: Vec<String> = ["TP1", "TP2", "TP3", "TP4", "TP5", "TP6", "E1", "E2"]
            .map(String::from)
            .to_vec();
        c.schedule.extra_positions = vec![("E1".into(), [H, H, 0.0]), ("E2".into(), [H, -H, 0.0])];
        c.schedule.stops = vec![Stop {
            temp_c: -20.0,
            soak_s: 600.0,
            ramp_c_per_min: 4.0,
            positions: Some(pos.clone()),
        }];
        c.schedule.positions = pos;
        c.effects = effects;
        c
    }

    fn rows(c: &SimConfig) -> (String, Vec<Row>) {
        let csv = simulate(c, |_| {}).unwrap().csv;
        let rows = csv
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("t_s"))
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                let n = |k: usize| f[k].parse::<f64>().unwrap();
                Row {
                    t: n(0),
                    pos: f[1].to_string(),
                    temp: n(2),
                    u: [n(4), n(5), n(6)],
                }
            })
            .collect();
        (csv, rows)
    }

    /// Rows of `c` beside the same recording without its effects (the same noise): time,
    /// position, temperature and the outputs' differences.
    fn delta(c: &SimConfig) -> Vec<Row> {
        let mut bare = c.clone();
        bare.effects = Effects::default();
        let (_, with) = rows(c);
        let (_, without) = rows(&bare);
        assert_eq!(with.len(), without.len());
        with.iter()
            .zip(&without)
            .map(|(a, b)| {
                assert_eq!(a.t, b.t);
                Row {
                    t: a.t,
                    pos: a.pos.clone(),
                    temp: a.temp,
                    u: std::array::from_fn(|i| a.u[i] - b.u[i]),
                }
            })
            .collect()
    }

    fn at<'a>(d: &'a [Row], pos: &'a str) -> impl Iterator<Item = &'a Row> + 'a {
        d.iter().filter(move |r| r.pos == pos)
    }

    /// The IEEE 1293 terms: a_x a_y on y is c/2 at E1, -c/2 at E2, nothing at TP; a_x^2 on
    /// y is c at TP5 and TP6, c/2 at the edges; the other outputs untouched.
    #[test]
    fn cross_coupling_and_cross_squares_at_their_positions() {
        let c = 2e-4;
        let mut q = [[0.0; 6]; 3];
        q[1][3] = c;
        let d = delta(&short(Effects {
            quadratic: Some(Quadratic { value: q }),
            ..Effects::default()
        }));
        let close = |r: &Row, want: [f64; 3]| (0..3).all(|i| (r.u[i] - want[i]).abs() < ROUND);
        assert!(at(&d, "E1").all(|r| close(r, [0.0, c / 2.0, 0.0])));
        assert!(at(&d, "E2").all(|r| close(r, [0.0, -c / 2.0, 0.0])));
        assert!(at(&d, "TP6").all(|r| close(r, [0.0; 3])));
        assert!(at(&d, "E1").count() > 50);
        let mut q = [[0.0; 6]; 3];
        q[1][0] = c;
        let d = delta(&short(Effects {
            quadratic: Some(Quadratic { value: q }),
            ..Effects::default()
        }));
        assert!(at(&d, "TP5").all(|r| close(r, [0.0, c, 0.0])));
        assert!(at(&d, "E2").all(|r| close(r, [0.0, c / 2.0, 0.0])));
        assert!(at(&d, "TP1").all(|r| close(r, [0.0; 3])));
    }

    /// K2 with temperature: at TP6 at -20 C the x output moves by c (T - T0), negative
    /// for a positive c; nothing on y or z, nothing at TP1.
    #[test]
    fn k2_follows_the_distance_from_t0() {
        let c = 2e-6;
        let d = delta(&short(Effects {
            k2_temp: Some(PerAxis {
                value: [c, 0.0, 0.0],
            }),
            ..Effects::default()
        }));
        for r in at(&d, "TP6") {
            let want = c * (r.temp - 20.0);
            assert!((r.u[0] - want).abs() < 0.02 * want.abs() + ROUND, "{r:?}");
            assert!(r.u[0] < 0.0 && r.u[1].abs() < ROUND && r.u[2].abs() < ROUND);
        }
        assert!(at(&d, "TP1").all(|r| r.u[0].abs() < ROUND));
    }

    /// A scale with the rate: while the chamber cools, the z output at rest (a_z = 1)
    /// moves by K_zz s dT/dt, dT/dt in C/min measured from the sensor's own readings.
    #[test]
    fn the_scale_moves_with_the_rate_of_temperature() {
        let s = 1e-3;
        let d = delta(&short(Effects {
            scale_rate: Some(PerAxis {
                value: [0.0, 0.0, s],
            }),
            ..Effects::default()
        }));
        let k_zz = crate::simulate::TrueUnit::new(&SimConfig::default())
            .unwrap()
            .coeffs(0.0)[2];
        let mut checked = 0;
        for w in d
            .windows(121)
            .filter(|w| w[60].t > 300.0 && w[60].t < 900.0)
        {
            let rate = (w[120].temp - w[0].temp) / (w[120].t - w[0].t) * 60.0;
            let want = k_zz * s * rate;
            assert!(
                (w[60].u[2] - want).abs() < 0.05 * want.abs(),
                "{:?} {want}",
                w[60]
            );
            assert!(rate < -0.5 && w[60].u[0].abs() < ROUND);
            checked += 1;
        }
        assert!(checked > 100);
    }

    /// A stated power-off at -20 C: the temperature-sized warm-up starts again at its end
    /// and decays with its time constant on the recording's own clock, also when the
    /// logger writes rows late and sparsely (an uneven clock).
    #[test]
    fn the_warmup_sized_by_temperature_restarts_after_the_stated_power_off() {
        let (k, tau) = (1e-6, 300.0);
        for uneven in [false, true] {
            let mut c = short(Effects {
                warmup_temp: Some(TempWarmup {
                    v_per_c: [0.0, k, 0.0],
                    tau_s: tau,
                }),
                ..Effects::default()
            });
            c.schedule.power_offs = vec![[1100.0, 100.0]];
            c.logger.power_off_metadata = true;
            if uneven {
                c.logger.jitter_s = 0.4;
                c.logger.rest_rate_hz = 0.2;
            }
            let (csv, _) = rows(&c);
            assert!(csv.contains("# power_off_s=1100-1200\n"));
            let d = delta(&c);
            assert!(!d.iter().any(|r| r.t >= 1100.0 && r.t < 1200.0));
            let after: Vec<&Row> = d.iter().filter(|r| r.t >= 1200.0).collect();
            for r in &after {
                let want = k * (r.temp - 20.0) * (-(r.t - 1200.0) / tau).exp();
                assert!(
                    (r.u[1] - want).abs() < 0.01 * want.abs() + 2.0 * ROUND,
                    "{r:?} {want}"
                );
            }
            // sized by the temperature at the power-on (the case still cooling to -20 C)
            let first = after[0];
            assert!(first.temp < -5.0, "{first:?}");
            assert!(
                (first.u[1] / (k * (first.temp - 20.0)) - 1.0).abs() < 0.01,
                "{first:?}"
            );
        }
    }

    /// Turn-on to turn-on repeatability: nothing before the stated power-off, the step on
    /// every row after it.
    #[test]
    fn the_bias_steps_at_the_stated_power_off() {
        let mut c = short(Effects {
            turn_on_bias: Some(TurnOn {
                value: vec![[0.0, 0.0, -5e-5]],
            }),
            ..Effects::default()
        });
        c.schedule.power_offs = vec![[1100.0, 100.0]];
        c.logger.power_off_metadata = true;
        let d = delta(&c);
        assert!(d
            .iter()
            .filter(|r| r.t < 1100.0)
            .all(|r| r.u[2].abs() < ROUND));
        let after: Vec<&Row> = d.iter().filter(|r| r.t >= 1200.0).collect();
        assert!(after.len() > 500);
        assert!(after
            .iter()
            .all(|r| (r.u[2] + 5e-5).abs() < ROUND && r.u[0] == 0.0));
    }

    /// After each move the output relaxes from d with its time constant from the moment
    /// the tilter comes to rest, on the rows' own times, also on an uneven clock; a stop
    /// settles from the end of the ramp (600 s), nothing before it.
    #[test]
    fn settlings_decay_from_their_events_on_the_recordings_clock() {
        let r = Relaxation {
            d_v: [1e-4, 0.0, 0.0],
            tau_s: 20.0,
        };
        for uneven in [false, true] {
            let mut c = short(Effects {
                move_settle: Some(r),
                ..Effects::default()
            });
            if uneven {
                c.logger.jitter_s = 0.5;
            }
            let d = delta(&c);
            let mut dwells = 0;
            for pos in ["TP2", "TP3", "E1"] {
                let rows: Vec<&Row> = at(&d, pos).collect();
                // the tilter stopped at the tick before the dwell's first row
                let arrived = rows[0].t.floor();
                for row in &rows {
                    let want = 1e-4 * (-(row.t - arrived) / 20.0).exp();
                    assert!(
                        (row.u[0] - want).abs() < 2.0 * ROUND,
                        "{pos} {row:?} {want}"
                    );
                }
                dwells += 1;
            }
            assert_eq!(dwells, 3);
        }
        let d = delta(&short(Effects {
            stop_settle: Some(Relaxation {
                d_v: [0.0, -1e-4, 0.0],
                tau_s: 300.0,
            }),
            ..Effects::default()
        }));
        for row in &d {
            let want = if row.t < 600.0 {
                0.0
            } else {
                -1e-4 * (-(row.t - 600.0) / 300.0).exp()
            };
            assert!((row.u[1] - want).abs() < 2.0 * ROUND, "{row:?} {want}");
        }
    }

    /// The tilter's repeatability: each rest its own rotation, held through the dwell,
    /// of about the stated size (0.55 V/g times 1 sigma); a telegraph takes its two levels
    /// only, both, and switches about as often as its mean time says.
    #[test]
    fn repeatability_and_telegraph_are_random_in_their_own_ways() {
        let sigma = 1e-3;
        let d = delta(&short(Effects {
            tilter_repeatability: Some(Repeatability { sigma_rad: sigma }),
            ..Effects::default()
        }));
        let mut per_dwell = Vec::new();
        for pos in ["TP2", "TP3", "TP4", "TP5", "TP6", "E1", "E2"] {
            let rows: Vec<&Row> = at(&d, pos).collect();
            let first = rows[0].u;
            assert!(rows
                .iter()
                .all(|r| (0..3).all(|i| (r.u[i] - first[i]).abs() < 1e-6)));
            per_dwell.push(first.iter().map(|x| x * x).sum::<f64>().sqrt());
        }
        let rms = (per_dwell.iter().map(|x| x * x).sum::<f64>() / 7.0).sqrt();
        assert!(
            rms > 0.3 * 0.55 * sigma && rms < 3.0 * 0.55 * sigma,
            "{per_dwell:?}"
        );
        assert!(per_dwell.windows(2).all(|w| w[0] != w[1]));
        let v = 3e-5;
        let d = delta(&short(Effects {
            telegraph: Some(Telegraph {
                value: [v, 0.0, 0.0],
                mean_s: 150.0,
            }),
            ..Effects::default()
        }));
        assert!(d
            .iter()
            .all(|r| r.u[0].abs() < ROUND || (r.u[0] - v).abs() < ROUND));
        let high: Vec<bool> = d.iter().map(|r| r.u[0] > v / 2.0).collect();
        let switches = high.windows(2).filter(|w| w[0] != w[1]).count();
        // about 1770 s / 150 s
        assert!((4..=30).contains(&switches), "{switches}");
    }

    #[test]
    fn a_time_constant_that_is_not_positive_is_refused() {
        let c = short(Effects {
            move_settle: Some(Relaxation {
                d_v: [1e-4, 0.0, 0.0],
                tau_s: 0.0,
            }),
            ..Effects::default()
        });
        let e = simulate(&c, |_| {}).err().unwrap();
        assert!(e.to_string().contains("move_settle"), "{e}");
    }
}
