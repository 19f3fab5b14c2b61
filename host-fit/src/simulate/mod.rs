//! The digital twin of the production temperature test: chamber, case, sensor, tilter
//! and unit, with every effect of physics-catalogue.md switchable; writes recordings in
//! recording-format v1. Independent of the fitting code (it shares only the forward
//! model `U = K a + U0` of firmware-core).
pub mod beyond;
pub mod beyond_config;
pub mod checks;
pub mod config;
pub mod flight;
pub mod program;
mod readings;
mod rotation;
mod thermal;
pub mod unit;
mod writer;

pub use beyond_config::{Quadratic, Relaxation, Repeatability, Telegraph, TempWarmup, TurnOn};
pub use checks::parse_config;
pub use config::{
    Bend, BiasStep, Chamber, Curvature, Effects, Fixture, FixtureChange, Flight, Gradient, Interp,
    Leg, Logger, Output, PerAxis, Periodic, Schedule, Sensor, Settle, SimConfig, Stop, Sweep, Unit,
    UnitModel, Warmup,
};
pub use unit::{TrueUnit, PAPER_UNIT, PAPER_UNIT_TEMPS};
pub use writer::Simulation;

use readings::{sample, within, Disturbance};
use rotation::rotate;
use thermal::Thermal;
use writer::RecordingWriter;

use crate::data::positions::Positions;
use crate::error::{ErrorKind, HostError, Result};
use crate::rng::Rng;

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

/// The built-in positions plus the schedule's extra ones.
fn positions(cfg: &SimConfig) -> Positions {
    let mut positions = Positions::default();
    for (n, v) in &cfg.schedule.extra_positions {
        // a zero or non-finite vector is refused with the configuration (`checks`)
        let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        positions.set(n, v.map(|x| x / norm), None);
    }
    positions
}

fn position_index(positions: &Positions, n: &str) -> Result<usize> {
    positions.index(n).ok_or_else(|| {
        HostError::new(
            ErrorKind::Invalid,
            format!("unknown position `{n}` in the schedule"),
        )
    })
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

/// A sweep as segments: the set point follows the legs (a piecewise-linear profile from
/// `chamber.start_c`) while the tilter turns through the positions in turn, move then
/// dwell, until the profile ends; each segment's set point runs linearly between the
/// profile's values at its ends (a leg's corner inside a dwell is rounded off over that
/// dwell, far shorter than the chamber air's own lag).
fn sweep_plan(
    cfg: &SimConfig,
    sweep: &Sweep,
    positions: &Positions,
    rest: usize,
) -> Result<Vec<Segment>> {
    let sch = &cfg.schedule;
    let mut knots = vec![(0.0, cfg.chamber.start_c)];
    // the legs' ranges are checked with the configuration (`checks`)
    for leg in &sweep.legs {
        let (t, from) = knots[knots.len() - 1];
        let t1 = t + (leg.to_c - from).abs() / leg.c_per_min * 60.0;
        knots.push((t1, leg.to_c));
        knots.push((t1 + leg.hold_s, leg.to_c));
    }
    let end = knots[knots.len() - 1].0;
    let durations_ok = sch.dwell_s > 0.0 && sch.move_s >= 0.0;
    if sch.positions.is_empty() || !durations_ok || end <= 0.0 {
        return Err(HostError::new(
            ErrorKind::Invalid,
            "schedule.sweep needs legs of some duration, positions, dwell_s > 0 and move_s >= 0",
        ));
    }
    let set_at = |t: f64| program::set_point_at(&knots, t);
    let names: Vec<usize> = sch
        .positions
        .iter()
        .map(|n| position_index(positions, n))
        .collect::<Result<_>>()?;
    let (mut segs, mut t, mut prev) = (Vec::new(), 0.0, rest);
    let push = |segs: &mut Vec<Segment>, t: &mut f64, d: f64, phase: Phase| {
        segs.push(Segment {
            duration_s: d,
            set_from: set_at(*t),
            set_to: set_at(*t + d),
            phase,
        });
        *t += d;
    };
    'turning: loop {
        for &p in &names {
            if t + sch.move_s + sch.dwell_s > end {
                break 'turning;
            }
            push(&mut segs, &mut t, sch.move_s, Phase::Move(prev, p));
            push(&mut segs, &mut t, sch.dwell_s, Phase::Dwell(p));
            prev = p;
        }
    }
    push(&mut segs, &mut t, sch.move_s, Phase::Move(prev, rest));
    Ok(segs)
}

/// A program as segments (see [`program`]): row by row, the set point from the row's
/// value to the next row's, the tilter dwelling at the row's position or moving (`-`)
/// from the last named position to the next.
fn program_plan(
    steps: &[program::Step],
    positions: &Positions,
    rest: usize,
) -> Result<Vec<Segment>> {
    let named = |i: usize| -> Result<Option<usize>> {
        match steps.get(i).map(|s| s.position.as_str()) {
            None | Some("-") => Ok(None),
            Some(n) => position_index(positions, n).map(Some),
        }
    };
    let mut segs = Vec::new();
    let mut prev = rest;
    for i in 0..steps.len().saturating_sub(1) {
        let (a, b) = (&steps[i], &steps[i + 1]);
        let phase = match named(i)? {
            Some(p) => {
                prev = p;
                Phase::Dwell(p)
            }
            None => {
                let next = (i + 1..steps.len())
                    .find_map(|j| named(j).ok().flatten())
                    .unwrap_or(rest);
                Phase::Move(prev, next)
            }
        };
        segs.push(Segment {
            duration_s: b.time_s - a.time_s,
            set_from: a.setpoint_c,
            set_to: b.setpoint_c,
            phase,
        });
    }
    Ok(segs)
}

/// Each stop's span `[start, end]` on the twin's clock, s: from the start of its ramp to
/// the end of its last move back to rest (a blind case places a fixture change between
/// two stops by it).
pub fn stop_spans(cfg: &SimConfig) -> Result<Vec<[f64; 2]>> {
    checks::check(cfg)?;
    let positions = positions(cfg);
    let rest = position_index(&positions, &cfg.schedule.rest_position)?;
    let segs = plan(cfg, &positions, rest)?;
    // per stop: a ramp, a soak, then a move and a dwell per position, and a move to rest
    let mut spans = Vec::new();
    let (mut t, mut k) = (0.0, 0);
    for stop in &cfg.schedule.stops {
        let n = 3 + 2 * stop
            .positions
            .as_ref()
            .unwrap_or(&cfg.schedule.positions)
            .len();
        let d: f64 = segs[k..k + n].iter().map(|s| s.duration_s).sum();
        spans.push([t, t + d]);
        t += d;
        k += n;
    }
    Ok(spans)
}

/// The logger's decisions per tick ([`Logger`]): which ticks become rows and how late
/// each is taken; its own random numbers, so the noise of the rows is the same draw
/// whatever the logger does.
struct Clock {
    rest_every: u64,
    jitter_s: f64,
    drop_rate: f64,
    rng: Rng,
}

impl Clock {
    fn new(cfg: &SimConfig, rate_hz: f64) -> Self {
        // the logger's ranges are checked with the configuration (`checks`)
        let l = &cfg.logger;
        let rest_every = if l.rest_rate_hz > 0.0 {
            ((rate_hz / l.rest_rate_hz).round() as u64).max(1)
        } else {
            1
        };
        Clock {
            rest_every,
            jitter_s: l.jitter_s,
            drop_rate: l.drop_rate,
            rng: Rng::new(cfg.seed ^ 0xC10C),
        }
    }

    /// Whether tick `k` becomes a row (`at_rest`: the unit rests through a ramp or soak).
    fn writes(&mut self, k: u64, at_rest: bool) -> bool {
        let kept = !at_rest || k.is_multiple_of(self.rest_every);
        let lost = self.drop_rate > 0.0 && self.rng.uniform() < self.drop_rate;
        kept && !lost
    }

    /// How long after its tick the row is taken, s.
    fn delay(&mut self) -> f64 {
        if self.jitter_s > 0.0 {
            self.jitter_s * self.rng.uniform()
        } else {
            0.0
        }
    }
}

/// The orientation of a tilter phase at fraction `f` of it.
fn phase_vector(phase: Phase, f: f64, rest: usize, vector: &dyn Fn(usize) -> [f64; 3]) -> [f64; 3] {
    match phase {
        Phase::Rest => vector(rest),
        Phase::Dwell(p) => vector(p),
        Phase::Move(p, q) => {
            let (u, v) = (vector(p), vector(q));
            let m: [f64; 3] = std::array::from_fn(|i| u[i] * (1.0 - f) + v[i] * f);
            let nrm = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
            if nrm > 0.1 {
                m.map(|x| x / nrm)
            } else {
                u
            }
        }
    }
}

/// What the start of segment `seg` (at `t`, after `prev`) is to the physics beyond the
/// catalogue: the end of a move to another position (the tilter comes to rest), or a hold
/// after a ramp (the chamber reached a new stop).
fn segment_events(
    dist: &mut Disturbance,
    cfg: &SimConfig,
    prev: Option<&Segment>,
    seg: &Segment,
    t: f64,
) {
    let Some(p) = prev else { return };
    // a move split over several segments (a power-off on the way) arrives once
    let moving = matches!(seg.phase, Phase::Move(..));
    if matches!(p.phase, Phase::Move(a, b) if a != b) && !moving {
        dist.beyond.arrived(&cfg.effects, t);
    }
    if p.set_from != p.set_to && seg.set_from == seg.set_to {
        dist.beyond.stopped(t);
    }
}

/// Run the simulation: the production test, or the flight when the configuration has
/// one.
pub fn simulate(cfg: &SimConfig, mut progress: impl FnMut(f64)) -> Result<Simulation> {
    if let Some(f) = &cfg.flight {
        return flight::simulate(cfg, f, progress);
    }
    checks::check(cfg)?;
    let unit = TrueUnit::new(cfg)?;
    let positions = positions(cfg);
    let sch = &cfg.schedule;
    if sch.rate_hz.is_nan()
        || sch.rate_hz <= 0.0
        || (sch.stops.is_empty() && sch.sweep.is_none() && sch.program.is_empty())
    {
        return Err(HostError::new(
            ErrorKind::Invalid,
            "schedule needs rate_hz > 0 and at least one stop (or a sweep)",
        ));
    }
    let rest = position_index(&positions, &sch.rest_position)?;
    let segs = match (&sch.sweep, sch.program.is_empty()) {
        (_, false) => program_plan(&sch.program, &positions, rest)?,
        (Some(sw), true) => sweep_plan(cfg, sw, &positions, rest)?,
        (None, true) => plan(cfg, &positions, rest)?,
    };
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
    let change = match &cfg.effects.fixture_change {
        Some(f) => Some((position_index(&positions, &f.position)?, f.clone())),
        None => None,
    };
    // a re-clamped position: its own angles before the change and after it
    let vector_at = |p: usize, t: f64| match &change {
        Some((fp, f)) if *fp == p => {
            let ang = if t >= f.at_s {
                f.angles_rad
            } else {
                f.before_rad
            };
            rotate(vector(p), ang)
        }
        _ => vector(p),
    };
    let mut clock = Clock::new(cfg, sch.rate_hz);
    let mut w = RecordingWriter::new(cfg, &sch.power_offs, clock.jitter_s > 0.0)?;
    let mut th = Thermal::new(cfg);
    let mut dist = Disturbance::new(cfg.seed, &cfg.effects);
    let (mut t, mut last_report, mut tick) = (0.0, 0.0, 0u64);
    for (s, seg) in segs.iter().enumerate() {
        segment_events(&mut dist, cfg, s.checked_sub(1).map(|p| &segs[p]), seg, t);
        let n = (seg.duration_s * sch.rate_hz).round() as usize;
        let set_at = |f: f64| seg.set_from + (seg.set_to - seg.set_from) * f;
        for k in 0..n {
            let f = k as f64 / n as f64;
            let (set0, set1) = (set_at(f), set_at((k + 1) as f64 / n as f64));
            let name = match seg.phase {
                Phase::Rest if cfg.logger.rest_unnamed => "-",
                Phase::Rest => positions.name(rest),
                Phase::Dwell(p) => positions.name(p),
                Phase::Move(..) => "-",
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
            // the row is taken `late` after the tick: the physics advanced to that time
            let late = clock.delay();
            let (u, ts, air) = if late > 0.0 {
                let mut at = th.clone();
                at.step(set0, set0 + (set1 - set0) * late / dt, late);
                let a = phase_vector(seg.phase, f + late / dt / n as f64, rest, &|p| {
                    vector_at(p, t + late)
                });
                let (u, ts) = sample(cfg, &unit, &at, &mut dist, a, t + late);
                (u, ts, at.air)
            } else {
                let a = phase_vector(seg.phase, f, rest, &|p| vector_at(p, t));
                let (u, ts) = sample(cfg, &unit, &th, &mut dist, a, t);
                (u, ts, th.air)
            };
            let logged = clock.writes(tick, seg.phase == Phase::Rest);
            if logged && !within(&sch.dropouts, t) && !within(&sch.power_offs, t) {
                let measuring = matches!(seg.phase, Phase::Dwell(_));
                w.row(t + late, name, ts, air, u, measuring)?;
            }
            th.step(set0, set1, dt);
            t += dt;
            tick += 1;
            if t - last_report > 600.0 {
                progress(t / total);
                last_report = t;
            }
        }
    }
    progress(1.0);
    let mut sim = w.finish()?;
    sim.positions_csv = extra_positions_csv(cfg);
    Ok(sim)
}

/// The positions file a recording visiting `schedule.extra_positions` is read with (None
/// without them): `simulate --positions-out` writes it.
fn extra_positions_csv(cfg: &SimConfig) -> Option<String> {
    let extra = &cfg.schedule.extra_positions;
    (!extra.is_empty()).then(|| {
        let mut s = String::from("name,fx,fy,fz\n");
        for (n, v) in extra {
            s.push_str(&format!("{n},{:.9},{:.9},{:.9}\n", v[0], v[1], v[2]));
        }
        s
    })
}
