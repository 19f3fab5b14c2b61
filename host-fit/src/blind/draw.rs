//! Random sizes, signs and axes of concealed effects, and the catalogue's own forms of
//! each effect at a size: what every class of the blind suite draws from.
use crate::diagnose::EffectId;
use crate::rng::Rng;
use crate::simulate::{Curvature, Fixture, PerAxis, SimConfig, Warmup};

/// One axis, random sign, 0.7..1.3 of `size`.
pub fn main_axis(rng: &mut Rng, size: f64) -> [f64; 3] {
    let mut v = [0.0; 3];
    let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
    v[(rng.next_u64() % 3) as usize] = s * size * rng.range(0.7, 1.3);
    v
}

/// Per-axis sizes: one or two axes, random signs, 0.7..1.3 of `size` times `scale`.
pub fn axes3(rng: &mut Rng, scale: f64, size: f64) -> [f64; 3] {
    // one or two axes, random signs, 0.7..1.3 of the size
    let main = (rng.next_u64() % 3) as usize;
    let mut v = [0.0; 3];
    for (i, x) in v.iter_mut().enumerate() {
        if i == main || rng.uniform() < 0.3 {
            let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            *x = s * size * scale * rng.range(0.7, 1.3);
        }
    }
    v
}

/// Conceal catalogue effect `e` in its catalogue form at `s` times its nominal size, its
/// random sizes, signs and axes drawn from `rng`.
pub fn conceal(e: EffectId, s: f64, c: &mut SimConfig, rng: &mut Rng) {
    match e {
        // not a catalogue form: the suite's classes beyond the catalogue conceal their
        // own physics (crate::blind::forms)
        EffectId::Discovered => {}
        EffectId::ThermalLag => {
            c.effects.thermal_lag = Some(PerAxis {
                value: [rng.range(300.0, 900.0); 3],
            })
        }
        EffectId::TempRate => {
            c.effects.temp_rate = Some(PerAxis {
                value: axes3(rng, s, 0.02),
            })
        }
        EffectId::Hysteresis => {
            c.effects.hysteresis = Some(PerAxis {
                value: axes3(rng, s, 1e-4),
            })
        }
        EffectId::NonlinearityK2 => {
            c.effects.nonlinearity_k2 = Some(PerAxis {
                value: axes3(rng, s, 1e-4),
            })
        }
        EffectId::ScaleAsymmetry => {
            c.effects.scale_asymmetry = Some(PerAxis {
                value: axes3(rng, s, 2e-4),
            })
        }
        EffectId::FixtureError => {
            let p = ["TP2", "TP3", "TP5", "PP1", "PP4"][(rng.next_u64() % 5) as usize];
            c.effects.fixture_error = Some(Fixture {
                position: p.into(),
                angles_rad: [
                    rng.range(-2e-4, 2e-4) * s + 2e-4 * s,
                    rng.range(-2e-4, 2e-4) * s,
                ],
            });
        }
        EffectId::WarmupDrift => {
            c.effects.warmup_drift = Some(Warmup {
                d_v: axes3(rng, s, 2e-4),
                tau_s: rng.range(600.0, 2400.0),
            })
        }
        EffectId::TempCurvature => {
            c.effects.temp_curvature = Some(Curvature {
                u0_v: axes3(rng, s, 1e-4),
                k_rel: [0.0; 3],
                period_c: 25.0,
            })
        }
    }
}
