//! The twin's temperatures: chamber air, case, sensing elements and the hysteresis state,
//! continuous in time (each lag advanced exactly over a tick of any length).
use crate::simulate::config::SimConfig;

/// `y` of a first-order lag with time constant `tau` after `h` seconds, its input moving
/// linearly from `x0` to `x1`: the exact solution (no half-step bias at any tick), with
/// `tau <= 0` no lag.
pub(super) fn follow(y: f64, x0: f64, x1: f64, h: f64, tau: f64) -> f64 {
    if tau <= 0.0 {
        return x1;
    }
    if h <= 0.0 {
        return y;
    }
    let u = h / tau;
    let d = (-u).exp();
    let b = -(-u).exp_m1() / u;
    x1 + (y - x0) * d - (x1 - x0) * b
}

/// Play operators of a Preisach ensemble (their half-widths spread evenly).
const PREISACH_PLAYS: usize = 24;

/// Chamber air, case and sensing elements (first-order lags, a second pole where
/// configured), the inner temperature of a gradient, and the hysteresis state: the
/// direction of the last temperature change of more than 0.5 C, reached at once or, with
/// a switching width, relaxing toward it over the temperature travelled. Continuous in
/// time: each lag advanced exactly over a tick of any length.
#[derive(Clone)]
pub(super) struct Thermal {
    tau_air: f64,
    tau_case: f64,
    lag: Option<[f64; 3]>,
    lag2: Option<[f64; 3]>,
    tau_inner: f64,
    pub(super) air: f64,
    pub(super) case: f64,
    elem1: [f64; 3],
    pub(super) elem: [f64; 3],
    pub(super) inner: f64,
    dir: f64,
    dir_ref: f64,
    width: Option<f64>,
    /// Play operators: (half-width C, the operator's output), the state the mean of
    /// `(case - output) / half-width` over them (one for a play, several for a Preisach).
    plays: Vec<(f64, f64)>,
    pub(super) state: f64,
    turn: (f64, f64),
}

impl Thermal {
    pub(super) fn new(cfg: &SimConfig) -> Self {
        let start = cfg.chamber.start_c;
        let e = &cfg.effects;
        let initial = e.hysteresis_initial.unwrap_or(1.0);
        // play operators of half-width d start with output start - initial d, so the
        // state starts at `initial`
        let plays: Vec<(f64, f64)> = match (e.hysteresis_play_c, e.hysteresis_preisach_c) {
            (Some(w), _) if w > 0.0 => vec![(w / 2.0, start - initial * w / 2.0)],
            (_, Some(w)) if w > 0.0 => (0..PREISACH_PLAYS)
                .map(|k| {
                    let d = w / 2.0 * (k as f64 + 0.5) / PREISACH_PLAYS as f64;
                    (d, start - initial * d)
                })
                .collect(),
            _ => Vec::new(),
        };
        Thermal {
            tau_air: cfg.chamber.tau_air_s,
            tau_case: cfg.chamber.tau_case_s,
            lag: e.thermal_lag.map(|l| l.value),
            lag2: e.thermal_lag2.map(|l| l.value),
            tau_inner: e.temp_gradient.map(|g| g.tau_s).unwrap_or(0.0),
            air: start,
            case: start,
            elem1: [start; 3],
            elem: [start; 3],
            inner: start,
            dir: initial,
            dir_ref: start,
            width: e.hysteresis_width_c,
            plays,
            state: initial,
            turn: (start, initial),
        }
    }

    /// Advance `h` seconds, the set point moving linearly from `set0` to `set1`.
    pub(super) fn step(&mut self, set0: f64, set1: f64, h: f64) {
        let air0 = self.air;
        self.air = follow(self.air, set0, set1, h, self.tau_air);
        let case0 = self.case;
        self.case = follow(self.case, air0, self.air, h, self.tau_case);
        self.inner = follow(self.inner, case0, self.case, h, self.tau_inner);
        for i in 0..3 {
            let e1 = self.elem1[i];
            self.elem1[i] = match self.lag {
                Some(l) => follow(e1, case0, self.case, h, l[i]),
                None => self.case,
            };
            self.elem[i] = match self.lag2 {
                Some(l) => follow(self.elem[i], e1, self.elem1[i], h, l[i]),
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
        if !self.plays.is_empty() {
            let x = self.case;
            let mut sum = 0.0;
            for (d, y) in self.plays.iter_mut() {
                *y = y.clamp(x - *d, x + *d);
                sum += (x - *y) / *d;
            }
            self.state = sum / self.plays.len() as f64;
            return;
        }
        self.state = match self.width {
            Some(w) => {
                self.dir - (self.dir - self.turn.1) * (-(self.case - self.turn.0).abs() / w).exp()
            }
            None => self.dir,
        };
    }

    /// The case's rate now, C/s (the derivative of its lag, not a difference of ticks).
    pub(super) fn rate(&self) -> f64 {
        if self.tau_case > 0.0 {
            (self.air - self.case) / self.tau_case
        } else {
            0.0
        }
    }
}
