//! A blind case as a twin configuration: the catalogue's forms here, the others in
//! [`crate::blind::forms`].
use crate::blind::cases::{profile, Case};
use crate::blind::forms::axes3;
use crate::diagnose::EffectId;
use crate::rng::Rng;
use crate::simulate::{Curvature, Fixture, PerAxis, SimConfig, Warmup};

/// Conceal the effects of `case` in the profile; returns the config.
pub fn configure(case: &Case) -> SimConfig {
    let mut c = profile(case.tp_only);
    c.seed = case.seed;
    let mut rng = Rng::new(case.seed ^ 0xB11D);
    if let Some(form) = case.form {
        form.apply(case.scale, &mut c, &mut rng);
        return c;
    }
    for e in &case.effects {
        conceal(*e, case.scale, &mut c, &mut rng);
    }
    c
}

/// Conceal catalogue effect `e` in its catalogue form at `s` times its nominal size, its
/// random sizes, signs and axes drawn from `rng`.
pub fn conceal(e: EffectId, s: f64, c: &mut SimConfig, rng: &mut Rng) {
    match e {
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
