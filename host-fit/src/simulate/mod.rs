//! The digital twin of the production temperature test: chamber, case, sensor, tilter
//! and unit, with every effect of physics-catalogue.md switchable; writes recordings in
//! recording-format v1. Independent of the fitting code (it shares only the forward
//! model `U = K a + U0` of firmware-core).
pub mod config;
pub mod unit;

pub use config::{
    parse_config, Bend, BiasStep, Chamber, Curvature, Effects, Fixture, Gradient, PerAxis,
    Periodic, Schedule, Sensor, SimConfig, Stop, Unit, Warmup,
};
pub use unit::{TrueUnit, PAPER_UNIT, PAPER_UNIT_TEMPS};

use crate::data::positions::Positions;
use crate::error::{HostError, Result};
use crate::rng::Rng;
use firmware_core::model::Coeffs;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Rest,
    Move(usize, usize),
    Dwell(usize),
}

struct Segment {
    duration_s: f64,
    set_from: f64,
    set_to: f64,
    phase: Phase,
}

fn rotate(a: [f64; 3], angles: [f64; 2]) -> [f64; 3] {
    // Two axes perpendicular to `a`, then a small rotation about each.
    let helper = if a[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let norm = |v: [f64; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|x| x / n)
    };
    let e1 = norm(cross(a, helper));
    let e2 = cross(a, e1);
    let v: [f64; 3] = std::array::from_fn(|i| a[i] + angles[0] * e2[i] - angles[1] * e1[i]);
    norm(v)
}

/// The simulated recording as text, with the positions used.
pub struct Simulation {
    /// The recording (recording-format v1).
    pub csv: String,
    /// Number of sample rows.
    pub rows: usize,
}

/// The built-in positions plus the schedule's extra ones.
fn positions(cfg: &SimConfig) -> Result<Positions> {
    let mut positions = Positions::default();
    for (n, v) in &cfg.schedule.extra_positions {
        let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if norm == 0.0 || !norm.is_finite() {
            return Err(HostError::msg(format!(
                "schedule.extra_positions `{n}` has a zero-length vector"
            )));
        }
        positions.set(n, v.map(|x| x / norm), None);
    }
    Ok(positions)
}

fn position_index(positions: &Positions, n: &str) -> Result<usize> {
    positions
        .index(n)
        .ok_or_else(|| HostError::msg(format!("unknown position `{n}` in the schedule")))
}

/// The profile as segments: per stop a ramp and a soak at rest, then move/dwell through
/// the positions and back to rest.
fn plan(cfg: &SimConfig, positions: &Positions, rest: usize) -> Result<Vec<Segment>> {
    let sch = &cfg.schedule;
    let mut segs = Vec::new();
    let mut set = cfg.chamber.start_c;
    let hold = |duration_s: f64, set: f64, phase: Phase| Segment {
        duration_s,
        set_from: set,
        set_to: set,
        phase,
    };
    for stop in &sch.stops {
        if stop.ramp_c_per_min.is_nan() || stop.ramp_c_per_min <= 0.0 {
            return Err(HostError::msg(format!(
                "stop at {} C: ramp_c_per_min must be > 0",
                stop.temp_c
            )));
        }
        let ramp_s = (stop.temp_c - set).abs() / stop.ramp_c_per_min * 60.0;
        segs.push(Segment {
            duration_s: ramp_s,
            set_from: set,
            set_to: stop.temp_c,
            phase: Phase::Rest,
        });
        set = stop.temp_c;
        segs.push(hold(stop.soak_s, set, Phase::Rest));
        let names = stop.positions.as_ref().unwrap_or(&sch.positions);
        let mut prev = rest;
        for n in names {
            let p = position_index(positions, n)?;
            segs.push(hold(sch.move_s, set, Phase::Move(prev, p)));
            segs.push(hold(sch.dwell_s, set, Phase::Dwell(p)));
            prev = p;
        }
        segs.push(hold(sch.move_s, set, Phase::Move(prev, rest)));
    }
    Ok(segs)
}

/// Chamber air, case and sensing elements (first-order lags, a second pole where
/// configured), the inner temperature of a gradient, and the hysteresis state: the
/// direction of the last temperature change of more than 0.5 C, reached at once or, with
/// a switching width, relaxing toward it over the temperature travelled.
struct Thermal {
    k_air: f64,
    k_case: f64,
    lag: Option<[f64; 3]>,
    lag2: Option<[f64; 3]>,
    k_inner: f64,
    air: f64,
    case: f64,
    elem1: [f64; 3],
    elem: [f64; 3],
    inner: f64,
    dir: f64,
    dir_ref: f64,
    width: Option<f64>,
    state: f64,
    turn: (f64, f64),
}

impl Thermal {
    fn new(cfg: &SimConfig, dt: f64) -> Self {
        let fall = |tau: f64| {
            if tau > 0.0 {
                1.0 - (-dt / tau).exp()
            } else {
                1.0
            }
        };
        let start = cfg.chamber.start_c;
        let e = &cfg.effects;
        let initial = e.hysteresis_initial.unwrap_or(1.0);
        Thermal {
            k_air: fall(cfg.chamber.tau_air_s),
            k_case: fall(cfg.chamber.tau_case_s),
            lag: e.thermal_lag.map(|l| l.value.map(fall)),
            lag2: e.thermal_lag2.map(|l| l.value.map(fall)),
            k_inner: e.temp_gradient.map(|g| fall(g.tau_s)).unwrap_or(1.0),
            air: start,
            case: start,
            elem1: [start; 3],
            elem: [start; 3],
            inner: start,
            dir: initial,
            dir_ref: start,
            width: e.hysteresis_width_c,
            state: initial,
            turn: (start, initial),
        }
    }

    /// One sample toward the set point; returns the case's rate, C/s.
    fn step(&mut self, setp: f64, dt: f64) -> f64 {
        self.air += (setp - self.air) * self.k_air;
        let case_prev = self.case;
        self.case += (self.air - self.case) * self.k_case;
        self.inner += (self.case - self.inner) * self.k_inner;
        for i in 0..3 {
            self.elem1[i] = match self.lag {
                Some(l) => self.elem1[i] + (self.case - self.elem1[i]) * l[i],
                None => self.case,
            };
            self.elem[i] = match self.lag2 {
                Some(l) => self.elem[i] + (self.elem1[i] - self.elem[i]) * l[i],
                None => self.elem1[i],
            };
        }
        let before = self.dir;
        if self.case - self.dir_ref > 0.5 {
            self.dir = 1.0;
            self.dir_ref = self.case;
        } else if self.dir_ref - self.case > 0.5 {
            self.dir = -1.0;
            self.dir_ref = self.case;
        }
        if (self.case - self.dir_ref) * self.dir > 0.0 {
            self.dir_ref = self.case;
        }
        if self.dir != before {
            self.turn = (self.case, self.state);
        }
        self.state = match self.width {
            Some(w) => {
                self.dir - (self.dir - self.turn.1) * (-(self.case - self.turn.0).abs() / w).exp()
            }
            None => self.dir,
        };
        (self.case - case_prev) / dt
    }
}

/// Sample-to-sample state of the disturbances: the bias random walk, the voltmeter's
/// correlated noise, the last power-on, and the random numbers behind all noise.
struct Disturbance {
    walk: [f64; 3],
    noise: [f64; 3],
    on_s: f64,
    rng: Rng,
}

/// The voltmeter readings of the unit in orientation `a` at time `t`.
fn readings(
    cfg: &SimConfig,
    unit: &TrueUnit,
    th: &Thermal,
    dist: &mut Disturbance,
    a: [f64; 3],
    rate: f64,
    t: f64,
) -> [f64; 3] {
    let e = &cfg.effects;
    let dt = 1.0 / cfg.schedule.rate_hz;
    let since_on = t - dist.on_s;
    let mut u = [0.0; 3];
    for i in 0..3 {
        let c = Coeffs::from_array(&unit.coeffs(th.elem[i]));
        let mut ui = c.forward(a)[i];
        if let Some(k2) = e.nonlinearity_k2 {
            ui += k2.value[i] * a[i] * a[i];
        }
        if let Some(sa) = e.scale_asymmetry {
            ui += c.k[i][i] * sa.value[i] * a[i].abs();
        }
        if let Some(r) = e.temp_rate {
            ui += r.value[i] * rate;
        }
        if let Some(g) = e.temp_gradient {
            ui += g.value[i] * (th.case - th.inner);
        }
        if let Some(h) = e.hysteresis {
            ui += th.state * h.value[i] / 2.0;
        }
        if let Some(h) = e.scale_hysteresis {
            ui += c.k[i][i] * h.value[i] * th.state / 2.0 * a[i];
        }
        for w in [e.warmup_drift, e.warmup_drift2].into_iter().flatten() {
            ui += w.d_v[i] * (-since_on / w.tau_s).exp();
        }
        if let Some(b) = e.bias_step {
            ui += if t >= b.at_s { b.value[i] } else { 0.0 };
        }
        if let Some(w) = e.bias_walk {
            dist.walk[i] += w.value[i] * dt.sqrt() * dist.rng.normal();
            ui += dist.walk[i];
        }
        if let Some(k3) = e.nonlinearity_k3 {
            ui += k3.value[i] * a[i] * a[i] * a[i];
        }
        if let Some(p) = e.periodic {
            ui += p.value[i] * (std::f64::consts::TAU * t / p.period_s).sin();
        }
        if let Some(g) = e.scale_aging {
            ui += c.k[i][i] * g.value[i] * t / 3600.0 * a[i];
        }
        ui += noise(cfg, &mut dist.noise[i], &mut dist.rng);
        if cfg.unit.spike_rate > 0.0 && dist.rng.uniform() < cfg.unit.spike_rate {
            ui += if dist.rng.uniform() < 0.5 { -1.0 } else { 1.0 } * cfg.unit.spike_v;
        }
        if cfg.unit.resolution_v > 0.0 {
            ui = (ui / cfg.unit.resolution_v).round() * cfg.unit.resolution_v;
        }
        u[i] = ui;
    }
    u
}

/// One sample of voltmeter noise: white, or first-order autoregressive with the same
/// per-sample sigma.
fn noise(cfg: &SimConfig, state: &mut f64, rng: &mut Rng) -> f64 {
    let sigma = cfg.unit.noise_v;
    if cfg.unit.noise_corr_s <= 0.0 {
        return sigma * rng.normal();
    }
    let rho = (-1.0 / (cfg.schedule.rate_hz * cfg.unit.noise_corr_s)).exp();
    *state = rho * *state + (1.0 - rho * rho).sqrt() * sigma * rng.normal();
    *state
}

/// Whether `t` falls in one of the spans `[start, duration]`.
fn within(spans: &[[f64; 2]], t: f64) -> bool {
    spans.iter().any(|[s, d]| t >= *s && t < s + d)
}

/// Run the simulation.
pub fn simulate(cfg: &SimConfig, mut progress: impl FnMut(f64)) -> Result<Simulation> {
    let unit = TrueUnit::new(cfg)?;
    let positions = positions(cfg)?;
    let sch = &cfg.schedule;
    if sch.rate_hz.is_nan() || sch.rate_hz <= 0.0 || sch.stops.is_empty() {
        return Err(HostError::msg(
            "schedule needs rate_hz > 0 and at least one stop",
        ));
    }
    let rest = position_index(&positions, &sch.rest_position)?;
    let segs = plan(cfg, &positions, rest)?;
    let total: f64 = segs.iter().map(|s| s.duration_s).sum();
    let dt = 1.0 / sch.rate_hz;
    let fixture = match &cfg.effects.fixture_error {
        Some(f) => Some((position_index(&positions, &f.position)?, f.angles_rad)),
        None => None,
    };
    let vector = |p: usize| match fixture {
        Some((fp, ang)) if fp == p => rotate(positions.vector(p), ang),
        _ => positions.vector(p),
    };
    let fixture2 = match &cfg.effects.fixture_error2 {
        Some(f) => Some((position_index(&positions, &f.position)?, f.angles_rad)),
        None => None,
    };
    let vector = |p: usize| match fixture2 {
        Some((fp, ang)) if fp == p => rotate(positions.vector(p), ang),
        _ => vector(p),
    };
    let mut w = RecordingWriter::new(cfg)?;
    let mut th = Thermal::new(cfg, dt);
    let mut dist = Disturbance {
        walk: [0.0; 3],
        noise: [0.0; 3],
        on_s: 0.0,
        rng: Rng::new(cfg.seed),
    };
    let (mut t, mut last_report) = (0.0, 0.0);
    for seg in &segs {
        let n = (seg.duration_s * sch.rate_hz).round() as usize;
        for k in 0..n {
            let f = if n > 0 { k as f64 / n as f64 } else { 0.0 };
            let rate = th.step(seg.set_from + (seg.set_to - seg.set_from) * f, dt);
            let (name, a) = match seg.phase {
                Phase::Rest => (positions.name(rest), vector(rest)),
                Phase::Dwell(p) => (positions.name(p), vector(p)),
                Phase::Move(p, q) => {
                    let (u, v) = (vector(p), vector(q));
                    let m: [f64; 3] = std::array::from_fn(|i| u[i] * (1.0 - f) + v[i] * f);
                    let nrm = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
                    ("-", if nrm > 0.1 { m.map(|x| x / nrm) } else { u })
                }
            };
            if let Some(end) = sch
                .power_offs
                .iter()
                .map(|[s, d]| s + d)
                .filter(|e| *e <= t)
                .reduce(f64::max)
            {
                dist.on_s = end;
            }
            let u = readings(cfg, &unit, &th, &mut dist, a, rate, t);
            let sensed = th.case + cfg.sensor.offset_c + cfg.sensor.gain_error * (th.case - 20.0);
            let mut ts = sensed + cfg.sensor.noise_c * dist.rng.normal();
            if cfg.sensor.quantum_c > 0.0 {
                ts = (ts / cfg.sensor.quantum_c).round() * cfg.sensor.quantum_c;
            }
            if !within(&sch.dropouts, t) && !within(&sch.power_offs, t) {
                let measuring = matches!(seg.phase, Phase::Dwell(_));
                w.row(t, name, ts, th.air, u, measuring)?;
            }
            t += dt;
            if t - last_report > 600.0 {
                progress(t / total);
                last_report = t;
            }
        }
    }
    progress(1.0);
    w.finish()
}

/// The recording's metadata lines, then its rows through a CSV writer; with
/// `dwell_means`, one row per tilter dwell (its mean) and nothing else.
struct RecordingWriter {
    head: String,
    csv: csv::Writer<Vec<u8>>,
    rows: usize,
    dwell_means: bool,
    /// The open dwell: its name, and the sums of t, temperature, air and outputs.
    acc: Option<(String, usize, [f64; 6])>,
}

impl RecordingWriter {
    fn new(cfg: &SimConfig) -> Result<Self> {
        let head = format!(
            "# format=at-recording/1\n# unit={}\n# t0_c={}\n# g_local=9.80665\n# simulated by host-fit simulate, seed {}\n",
            cfg.unit.serial, cfg.t0_c, cfg.seed
        );
        let mut csv = csv::Writer::from_writer(Vec::new());
        csv.write_record([
            "t_s",
            "position",
            "temp_c",
            "chamber_c",
            "ux_v",
            "uy_v",
            "uz_v",
        ])
        .map_err(Self::err)?;
        Ok(RecordingWriter {
            head,
            csv,
            rows: 0,
            dwell_means: cfg.schedule.dwell_means,
            acc: None,
        })
    }

    fn err(e: csv::Error) -> HostError {
        HostError::msg(format!("cannot write the recording: {e}"))
    }

    fn write(&mut self, t: f64, name: &str, ts: f64, air: f64, u: [f64; 3]) -> Result<()> {
        self.rows += 1;
        self.csv
            .write_record([
                format!("{t:.2}"),
                name.to_string(),
                format!("{ts:.4}"),
                format!("{air:.3}"),
                format!("{:.8}", u[0]),
                format!("{:.8}", u[1]),
                format!("{:.8}", u[2]),
            ])
            .map_err(Self::err)
    }

    /// Write the open dwell's mean.
    fn flush(&mut self) -> Result<()> {
        if let Some((name, n, s)) = self.acc.take() {
            let m = s.map(|v| v / n as f64);
            self.write(m[0], &name, m[1], m[2], [m[3], m[4], m[5]])?;
        }
        Ok(())
    }

    fn row(
        &mut self,
        t: f64,
        name: &str,
        ts: f64,
        air: f64,
        u: [f64; 3],
        measuring: bool,
    ) -> Result<()> {
        if !self.dwell_means {
            return self.write(t, name, ts, air, u);
        }
        let same = self.acc.as_ref().is_some_and(|(n, _, _)| n == name) && measuring;
        if !same {
            self.flush()?;
        }
        if measuring {
            let (_, n, s) = self
                .acc
                .get_or_insert_with(|| (name.to_string(), 0, [0.0; 6]));
            *n += 1;
            for (a, v) in s.iter_mut().zip([t, ts, air, u[0], u[1], u[2]]) {
                *a += v;
            }
        }
        Ok(())
    }

    fn finish(mut self) -> Result<Simulation> {
        self.flush()?;
        let body = self
            .csv
            .into_inner()
            .map_err(|e| HostError::msg(format!("cannot write the recording: {e}")))?;
        let body = String::from_utf8(body).map_err(|e| HostError::msg(e.to_string()))?;
        Ok(Simulation {
            csv: self.head + &body,
            rows: self.rows,
        })
    }
}
