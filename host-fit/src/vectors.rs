//! Test vectors for the firmware on the target: an input table (each sample with its own
//! time step, as an MCU with gaps or a logger gives them), and the f32 results the host
//! gets from the same firmware-core code (compared bit for bit with the MCU's), checked
//! against the f64 evaluation within the documented bound.
use crate::model::precision::F32_BOUND_G;
use crate::rng::Rng;
use firmware_core::blob::Blob;
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::model::Coeffs;
use firmware_core::terms::TermEntry;

/// The methods in the order the firmware harness runs them.
pub const METHODS: [(&str, Method); 3] = [
    ("m1", Method::CorrectConstants),
    ("m2full", Method::CorrectResult(ErrorModel::Full)),
    ("m2simp", Method::CorrectResult(ErrorModel::Simplified)),
];

/// Bytes of one input record: ux uy uz temp dt, f32 LE.
pub const RECORD: usize = 20;
/// The sample period the firmware harnesses make their compensators with (100 Hz), s:
/// every input record still gives its own time step.
pub const PERIOD_S: f32 = 0.01;

/// `n` samples of a unit at rest in random orientations, at temperatures wandering over
/// the valid range and 10 C beyond it (steps of up to 2 C, a jump in one sample of ten),
/// each with its own time step (mostly 10 ms, bursts of 1 ms, 0.1-3 s gaps, a minute now
/// and then); then the edge cases: NaN, infinite, huge and subnormal voltages, NaN and
/// far-out temperatures, negative, NaN and infinite time steps. [`RECORD`] bytes each.
pub fn make_inputs(blob: &Blob, n: usize, seed: u64) -> Vec<u8> {
    let cal = blob.calibration.convert::<f64>();
    let mut rng = Rng::new(seed);
    let mut out = Vec::new();
    let mut push = |u: [f32; 3], t: f32, dt: f32| {
        for v in [u[0], u[1], u[2], t, dt] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    };
    let (lo, hi) = (cal.t_min_c - 10.0, cal.t_max_c + 10.0);
    let mut temp = rng.range(lo, hi);
    for _ in 0..n {
        temp = if rng.uniform() < 0.1 {
            rng.range(lo, hi)
        } else {
            (temp + rng.range(-2.0, 2.0)).clamp(lo, hi)
        };
        let t = temp as f32;
        let dt = match rng.uniform() {
            x if x < 0.6 => PERIOD_S,
            x if x < 0.8 => 0.001,
            x if x < 0.98 => rng.range(0.1, 3.0) as f32,
            _ => 60.0,
        };
        let z = rng.range(-1.0, 1.0);
        let phi = rng.range(0.0, std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        let a = [r * phi.cos(), r * phi.sin(), z];
        let u = Coeffs::from_array(&cal.model.eval(cal.t0_c, f64::from(t))).forward(a);
        push(u.map(|v| v as f32), t, dt);
    }
    let good = [0.0045f32, -0.0044, -0.5521];
    for (u, t, dt) in [
        ([f32::NAN, good[1], good[2]], 20.0, PERIOD_S),
        ([good[0], f32::INFINITY, good[2]], 20.0, PERIOD_S),
        (good, f32::NAN, PERIOD_S),
        (good, f32::INFINITY, PERIOD_S),
        ([3e38, -3e38, 3e38], 25.0, PERIOD_S),
        ([1e-40, -1e-41, 1e-45], 25.0, PERIOD_S),
        (good, -1000.0, PERIOD_S),
        (good, 1.0e6, PERIOD_S),
        (good, 21.0, -1.0),
        (good, 21.0, f32::NAN),
        (good, 21.0, f32::INFINITY),
        (good, 21.0, 0.0),
        (good, 21.5, 0.5),
    ] {
        push(u, t, dt);
    }
    out
}

fn inputs(bytes: &[u8]) -> Vec<([f32; 3], f32, f32)> {
    bytes
        .chunks_exact(RECORD)
        .map(|c| {
            let f =
                |k: usize| f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]]);
            ([f(0), f(1), f(2)], f(3), f(4))
        })
        .collect()
}

/// The expected firmware output lines, and the largest |f32 - f64| / max(1, |a|) (g)
/// over the finite in-range-or-near samples (method by method, the f64 run of the same
/// code).
pub fn expected(blob: &Blob, bytes: &[u8], prefix: &str) -> (Vec<String>, f64) {
    let cal64 = blob.calibration.convert::<f64>();
    let terms64: Vec<TermEntry<f64>> = blob.terms.iter().map(TermEntry::convert).collect();
    let mut lines = Vec::new();
    let mut worst: f64 = 0.0;
    for (tag, m) in METHODS {
        let (Ok(mut c32), Ok(mut c64)) = (
            Compensator::with_terms(&blob.calibration, &blob.terms, m, PERIOD_S),
            Compensator::with_terms(&cal64, &terms64, m, f64::from(PERIOD_S)),
        ) else {
            continue;
        };
        for (i, (u, t, dt)) in inputs(bytes).into_iter().enumerate() {
            let o = c32.compensate_dt(u, t, dt);
            let r = c64.compensate_dt(u.map(f64::from), f64::from(t), f64::from(dt));
            if o.status.bits() & !1 == 0
                && (cal64.t_min_c - 10.0..=cal64.t_max_c + 10.0).contains(&f64::from(t))
            {
                for (x, y) in o.accel.iter().zip(r.accel) {
                    // the bound is for |a| <= 1 g; relative beyond
                    let d = (f64::from(*x) - y).abs() / y.abs().max(1.0);
                    if d > crate::model::precision::F32_BOUND_G {
                        log::debug!(
                            "{prefix}{tag} input {i}: u {u:?} t {t}: f32 {:?} f64 {:?}",
                            o.accel,
                            r.accel
                        );
                    }
                    worst = worst.max(d);
                }
            }
            lines.push(format!(
                "vec {prefix}{tag} {i} {:08x} {:08x} {:08x} {}",
                o.accel[0].to_bits(),
                o.accel[1].to_bits(),
                o.accel[2].to_bits(),
                o.status.bits()
            ));
        }
    }
    (lines, worst)
}

/// Whether `worst` is within the documented bound.
pub fn within_bound(worst: f64) -> bool {
    worst <= F32_BOUND_G
}
