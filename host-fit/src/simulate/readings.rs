//! What the unit outputs and its sensor reads at one instant: the true coefficients at the
//! elements' temperatures, every configured effect, and the voltmeter's and sensor's noise.
use crate::rng::Rng;
use crate::simulate::config::SimConfig;
use crate::simulate::thermal::Thermal;
use crate::simulate::unit::TrueUnit;
use firmware_core::model::Coeffs;

/// Sample-to-sample state of the disturbances: the bias random walk, the voltmeter's
/// correlated noise, the last power-on, and the random numbers behind all noise.
pub(super) struct Disturbance {
    pub(super) walk: [f64; 3],
    pub(super) noise: [f64; 3],
    pub(super) on_s: f64,
    pub(super) rng: Rng,
    /// Events and states of the physics beyond the catalogue ([`crate::simulate::beyond`]).
    pub(super) beyond: crate::simulate::beyond::State,
}

impl Disturbance {
    /// At the recording's start (powered on at `t = 0`, the tilter at rest), its random
    /// numbers from `seed`.
    pub(super) fn new(seed: u64, e: &crate::simulate::config::Effects) -> Disturbance {
        let mut beyond = crate::simulate::beyond::State::new(seed);
        beyond.rest(e);
        Disturbance {
            walk: [0.0; 3],
            noise: [0.0; 3],
            on_s: 0.0,
            rng: Rng::new(seed),
            beyond,
        }
    }
}

/// The voltmeter readings of the unit in orientation `a` at time `t`.
pub(super) fn readings(
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
    dist.beyond.advance(e, dist.on_s, t);
    // the tilter's repeatability: this rest's own small rotation
    let a = match dist.beyond.tilt() {
        [0.0, 0.0] => a,
        ang => crate::simulate::rotation::rotate(a, ang),
    };
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
            ui += b.value[i] * step_shape(t - b.at_s, b.rise_s);
        }
        if let Some(g) = e.bias_aging {
            ui += g.value[i] * t / 3600.0;
        }
        if let Some(b) = e.bias_settle {
            if t >= b.at_s {
                ui += b.value[i] * (1.0 - (-(t - b.at_s) / b.tau_s).exp());
            }
        }
        if let Some(w) = e.bias_walk {
            dist.walk[i] += w.value[i] * dt.sqrt() * dist.rng.normal();
            ui += dist.walk[i];
        }
        if let Some(k3) = e.nonlinearity_k3 {
            ui += k3.value[i] * a[i] * a[i] * a[i];
        }
        if let Some(p) = e.periodic {
            ui += p.value[i] * (std::f64::consts::TAU * t / p.period_s + p.phase_rad).sin();
        }
        if let Some(g) = e.scale_aging {
            ui += c.k[i][i] * g.value[i] * t / 3600.0 * a[i];
        }
        ui += dist
            .beyond
            .output(e, i, a, c.k[i][i], th.elem[i], cfg.t0_c, rate, t);
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

/// A step's progress `x` seconds after its middle: 0 before, 1 after, a raised cosine over
/// `rise_s` (0: sudden, at `x = 0`).
fn step_shape(x: f64, rise_s: f64) -> f64 {
    if rise_s <= 0.0 {
        return if x >= 0.0 { 1.0 } else { 0.0 };
    }
    let f = (x / rise_s + 0.5).clamp(0.0, 1.0);
    0.5 - 0.5 * (std::f64::consts::PI * f).cos()
}

/// One sample of voltmeter noise: white, or first-order autoregressive with the same
/// per-sample sigma.
pub(super) fn noise(cfg: &SimConfig, state: &mut f64, rng: &mut Rng) -> f64 {
    let sigma = cfg.unit.noise_v;
    if cfg.unit.noise_corr_s <= 0.0 {
        return sigma * rng.normal();
    }
    let rho = (-1.0 / (cfg.schedule.rate_hz * cfg.unit.noise_corr_s)).exp();
    *state = rho * *state + (1.0 - rho * rho).sqrt() * sigma * rng.normal();
    *state
}

/// Whether `t` falls in one of the spans `[start, duration]`.
pub(super) fn within(spans: &[[f64; 2]], t: f64) -> bool {
    spans.iter().any(|[s, d]| t >= *s && t < s + d)
}

/// The unit's readings and its temperature sensor's at time `t` in orientation `a`.
pub(super) fn sample(
    cfg: &SimConfig,
    unit: &TrueUnit,
    th: &Thermal,
    dist: &mut Disturbance,
    a: [f64; 3],
    t: f64,
) -> ([f64; 3], f64) {
    let u = readings(cfg, unit, th, dist, a, th.rate(), t);
    let sensed = th.case + cfg.sensor.offset_c + cfg.sensor.gain_error * (th.case - 20.0);
    let mut ts = sensed + cfg.sensor.noise_c * dist.rng.normal();
    if cfg.sensor.quantum_c > 0.0 {
        ts = (ts / cfg.sensor.quantum_c).round() * cfg.sensor.quantum_c;
    }
    (u, ts)
}
