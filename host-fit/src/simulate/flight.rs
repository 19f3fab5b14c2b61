//! The twin in flight: the same unit, sensor and effects as the production test, on a
//! flight-like history (power-on at a cold start, fast warming and cooling both ways, a
//! second power cycle, static attitudes all over the sphere), sampled at an MCU rate.
//! What a blob diagnosed from the production recording must compensate, on a temperature
//! history it was not fitted on.
use crate::error::Result;
use crate::simulate::config::{Flight, SimConfig};
use crate::simulate::readings::{sample, within, Disturbance};
use crate::simulate::thermal::Thermal;
use crate::simulate::unit::TrueUnit;
use crate::simulate::writer::{RecordingWriter, Simulation};

/// `n` directions spread evenly over the sphere (a Fibonacci lattice).
pub fn attitudes(n: usize) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

/// The name of attitude `i` (`A01`, `A02`, ...).
pub fn attitude_name(i: usize) -> String {
    format!("A{:02}", i + 1)
}

/// The environment's temperature at `t` (s after power-on): the legs' ramps and holds,
/// the last temperature held after them.
fn environment(f: &Flight, t: f64) -> f64 {
    let (mut at, mut temp) = (0.0, f.start_c);
    for leg in &f.legs {
        let ramp = (leg.to_c - temp).abs() / leg.c_per_min * 60.0;
        if t < at + ramp {
            return temp + (leg.to_c - temp) * (t - at) / ramp;
        }
        at += ramp;
        temp = leg.to_c;
        if t < at + leg.hold_s {
            return temp;
        }
        at += leg.hold_s;
    }
    temp
}

/// Seconds from power-on to the end of the last leg.
fn duration(f: &Flight) -> f64 {
    let (mut total, mut temp) = (0.0, f.start_c);
    for leg in &f.legs {
        total += (leg.to_c - temp).abs() / leg.c_per_min * 60.0 + leg.hold_s;
        temp = leg.to_c;
    }
    total
}

/// The flight's own ranges and finiteness ([`crate::simulate::checks::flight`]): a
/// flight given apart from its configuration is checked as one read with it.
fn check(f: &Flight) -> Result<()> {
    crate::simulate::checks::flight(f).map_or(Ok(()), |r| Err(r.error()))
}

/// The flight recording of `cfg`'s unit, with the positions file of its attitudes.
pub fn simulate(cfg: &SimConfig, f: &Flight, mut progress: impl FnMut(f64)) -> Result<Simulation> {
    check(f)?;
    crate::simulate::checks::check(cfg)?;
    let unit = TrueUnit::new(cfg)?;
    // the unit soaked at the cold start, in the hysteresis state that got it there; the
    // air and case follow the flight's own time constants
    let mut here = cfg.clone();
    here.chamber.start_c = f.start_c;
    here.chamber.tau_air_s = f.tau_air_s;
    here.chamber.tau_case_s = f.tau_case_s;
    here.effects.hysteresis_initial = Some(f.initial_direction);
    // a flight logger knows when the unit was off
    here.logger.power_off_metadata = true;
    let mut th = Thermal::new(&here);
    let dirs = attitudes(f.attitudes);
    let dt = 1.0 / f.rate_hz;
    let total = duration(f);
    let n = (total * f.rate_hz).round() as u64;
    let cycle = f.hold_s + f.move_s;
    let mut w = RecordingWriter::new(&here, &f.power_offs, f.rate_hz > 100.0)?;
    let mut dist = Disturbance::new(cfg.seed ^ 0xF117, &cfg.effects);
    let mut last_report = 0.0;
    for k in 0..n {
        let t = k as f64 * dt;
        let (set0, set1) = (environment(f, t), environment(f, t + dt));
        if let Some(end) = f
            .power_offs
            .iter()
            .map(|[s, d]| s + d)
            .filter(|e| *e <= t)
            .reduce(f64::max)
        {
            dist.on_s = end;
        }
        let slot = (t / cycle).floor();
        let i = slot as usize % dirs.len();
        let into = t - slot * cycle;
        let (name, a) = if into < f.hold_s {
            (attitude_name(i), dirs[i])
        } else {
            let g = (into - f.hold_s) / f.move_s.max(1e-9);
            let (u, v) = (dirs[i], dirs[(i + 1) % dirs.len()]);
            let m: [f64; 3] = std::array::from_fn(|j| u[j] * (1.0 - g) + v[j] * g);
            let nrm = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
            (
                "-".to_string(),
                if nrm > 0.1 { m.map(|x| x / nrm) } else { u },
            )
        };
        let (u, ts) = sample(&here, &unit, &th, &mut dist, a, t);
        if !within(&f.power_offs, t) {
            w.row(t, &name, ts, th.air, u, false)?;
        }
        th.step(set0, set1, dt);
        if t - last_report > 600.0 {
            progress(t / total);
            last_report = t;
        }
    }
    progress(1.0);
    let mut sim = w.finish()?;
    let mut pos = String::from("name,fx,fy,fz,role\n");
    for (i, d) in dirs.iter().enumerate() {
        pos.push_str(&format!(
            "{},{:.9},{:.9},{:.9},verification\n",
            attitude_name(i),
            d[0],
            d[1],
            d[2]
        ));
    }
    sim.positions_csv = Some(pos);
    Ok(sim)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attitudes_cover_the_sphere_and_are_unit_vectors() {
        let a = attitudes(24);
        for d in &a {
            assert!((d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.0).abs() < 1e-12);
        }
        for axis in 0..3 {
            assert!(a.iter().any(|d| d[axis] > 0.5) && a.iter().any(|d| d[axis] < -0.5));
        }
    }

    #[test]
    fn the_environment_follows_the_legs() {
        let f = Flight::default();
        assert_eq!(environment(&f, 0.0), -30.0);
        assert_eq!(environment(&f, 599.0), -30.0);
        // warming at 6 C/min from 600 s
        assert!((environment(&f, 660.0) - -24.0).abs() < 1e-9);
        assert!((duration(&f) - 4380.0).abs() < 1e-9, "{}", duration(&f));
    }
}
