//! The digital twin of the production temperature test: chamber, case, sensor, tilter
//! and unit, with every effect of physics-catalogue.md switchable; writes recordings in
//! recording-format v1. Independent of the fitting code (it shares only the forward
//! model `U = K a + U0` of firmware-core).
pub mod config;
pub mod unit;

pub use config::{
    parse_config, Chamber, Curvature, Effects, Fixture, PerAxis, Schedule, Sensor, SimConfig, Stop,
    Unit, Warmup,
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

/// Chamber air, case and sensing elements (first-order lags), and the direction of the
/// last temperature change of more than 0.5 C (hysteresis).
struct Thermal {
    k_air: f64,
    k_case: f64,
    lag: Option<[f64; 3]>,
    air: f64,
    case: f64,
    elem: [f64; 3],
    dir: f64,
    dir_ref: f64,
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
        Thermal {
            k_air: fall(cfg.chamber.tau_air_s),
            k_case: fall(cfg.chamber.tau_case_s),
            lag: cfg.effects.thermal_lag.map(|l| l.value.map(fall)),
            air: start,
            case: start,
            elem: [start; 3],
            dir: 1.0,
            dir_ref: start,
        }
    }

    /// One sample toward the set point; returns the case's rate, C/s.
    fn step(&mut self, setp: f64, dt: f64) -> f64 {
        self.air += (setp - self.air) * self.k_air;
        let case_prev = self.case;
        self.case += (self.air - self.case) * self.k_case;
        for i in 0..3 {
            self.elem[i] = match self.lag {
                Some(l) => self.elem[i] + (self.case - self.elem[i]) * l[i],
                None => self.case,
            };
        }
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
        (self.case - case_prev) / dt
    }
}

/// The voltmeter readings of the unit in orientation `a` at time `t`.
fn readings(
    cfg: &SimConfig,
    unit: &TrueUnit,
    th: &Thermal,
    a: [f64; 3],
    rate: f64,
    t: f64,
    rng: &mut Rng,
) -> [f64; 3] {
    let e = &cfg.effects;
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
        if let Some(h) = e.hysteresis {
            ui += th.dir * h.value[i] / 2.0;
        }
        if let Some(w) = e.warmup_drift {
            ui += w.d_v[i] * (-t / w.tau_s).exp();
        }
        ui += cfg.unit.noise_v * rng.normal();
        if cfg.unit.resolution_v > 0.0 {
            ui = (ui / cfg.unit.resolution_v).round() * cfg.unit.resolution_v;
        }
        u[i] = ui;
    }
    u
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
    let mut rng = Rng::new(cfg.seed);
    let mut w = RecordingWriter::new(cfg)?;
    let mut th = Thermal::new(cfg, dt);
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
            let u = readings(cfg, &unit, &th, a, rate, t, &mut rng);
            let mut ts = th.case + cfg.sensor.noise_c * rng.normal();
            if cfg.sensor.quantum_c > 0.0 {
                ts = (ts / cfg.sensor.quantum_c).round() * cfg.sensor.quantum_c;
            }
            w.row(t, name, ts, th.air, u)?;
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

/// The recording's metadata lines, then its rows through a CSV writer.
struct RecordingWriter {
    head: String,
    csv: csv::Writer<Vec<u8>>,
    rows: usize,
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
        Ok(RecordingWriter { head, csv, rows: 0 })
    }

    fn err(e: csv::Error) -> HostError {
        HostError::msg(format!("cannot write the recording: {e}"))
    }

    fn row(&mut self, t: f64, name: &str, ts: f64, air: f64, u: [f64; 3]) -> Result<()> {
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

    fn finish(self) -> Result<Simulation> {
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
