//! Random but physically shaped units for property tests.
#![allow(dead_code)]
use firmware_core::temperature::{Calibration, TempModel};
use proptest::prelude::*;

/// A unit: K diagonal 0.4..0.6 V/g (either sign), cross terms up to 0.03 V/g,
/// offsets up to 0.02 V, at -40/+20/+70 C with temperature changes of up to 0.3% of
/// K and 10 mV of offset across the range; PWL through the three temperatures.
pub fn unit() -> impl Strategy<Value = Calibration<f32>> {
    let row = (
        prop::array::uniform3(0.4f64..0.6),
        prop::array::uniform3(prop::bool::ANY),
        prop::array::uniform6(-0.03f64..0.03),
        prop::array::uniform3(-0.02f64..0.02),
    );
    let drift = (
        prop::array::uniform12(-0.003f64..0.003),
        prop::array::uniform12(-0.003f64..0.003),
    );
    (row, drift).prop_map(|((diag, neg, cross, u0), (lo, hi))| {
        let d: [f64; 3] = core::array::from_fn(|i| if neg[i] { -diag[i] } else { diag[i] });
        let mid: [f64; 12] = [
            d[0], d[1], d[2], cross[0], cross[1], cross[2], cross[3], cross[4], cross[5], u0[0],
            u0[1], u0[2],
        ];
        // K terms change relative to |K_ii|, offsets absolute (V).
        let at = |dr: &[f64; 12], sign: f64| -> [f32; 12] {
            core::array::from_fn(|i| {
                let scale = if i < 9 { 0.55 } else { 3.3 };
                (mid[i] + sign * dr[i] * scale) as f32
            })
        };
        Calibration {
            t0_c: 20.0,
            t_min_c: -40.0,
            t_max_c: 70.0,
            clamp: false,
            update_step_c: 0.0,
            model: TempModel::Pwl {
                breakpoints: [-40.0f32, 20.0, 70.0].into_iter().collect(),
                values: [at(&lo, 1.0), mid.map(|v| v as f32), at(&hi, 1.0)]
                    .into_iter()
                    .collect(),
            },
            physics: None,
        }
    })
}

/// A unit vector (specific force at rest, in g).
pub fn direction() -> impl Strategy<Value = [f64; 3]> {
    (-1.0f64..1.0, 0.0f64..std::f64::consts::TAU).prop_map(|(z, phi)| {
        let r = (1.0 - z * z).sqrt();
        [r * phi.cos(), r * phi.sin(), z]
    })
}
