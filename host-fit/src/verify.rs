//! Verification, formula (13): |a| - 1 in tilted positions, before and after compensation.
use crate::data::recording::Recording;
use crate::model::basis::temperature_clusters;
use firmware_core::blob::Blob;
use firmware_core::compensate::{Compensator, Method};
use firmware_core::model::{apply, dg, invert, Coeffs};
use serde::Serialize;

/// One verification dwell.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DwellCheck {
    /// Position name.
    pub position: String,
    /// Mean sensor temperature, C.
    pub temp_c: f64,
    /// dg with the T0 constants, mg.
    pub dg_mg_uncompensated: f64,
    /// dg compensated by firmware-core (f32), mg.
    pub dg_mg: f64,
    /// Samples, and samples whose output carried a status flag.
    pub samples: usize,
    /// Samples flagged by the compensator (out of range etc.).
    pub flagged: usize,
}

/// Max |dg| at one verification temperature.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct TempMax {
    /// Temperature (cluster mean), C.
    pub temp_c: f64,
    /// Max |dg| with the T0 constants, mg.
    pub max_abs_dg_mg_uncompensated: f64,
    /// Max |dg| compensated, mg.
    pub max_abs_dg_mg: f64,
}

/// The verification of one recording with one blob and method.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Verification {
    /// Per dwell.
    pub dwells: Vec<DwellCheck>,
    /// Per temperature.
    pub max_by_temperature: Vec<TempMax>,
}

/// Compensate the whole recording sample by sample in time order, as the MCU would, on
/// the recording's own clock (each row's time step, the stated power-ons of the sensor:
/// [`Recording::clock`]),
/// and evaluate formula (13) on the mean acceleration of every selected dwell.
pub fn verify(
    rec: &Recording,
    blob: &Blob,
    method: Method,
    select: &dyn Fn(usize) -> bool,
) -> Option<Verification> {
    let cal = &blob.calibration;
    let c0: Coeffs<f64> = Coeffs::from_array(&cal.at_t0().map(f64::from));
    let n0 = invert(&c0.k)?;
    // every row is given its own time step; the period is only the constructor's
    let period = rec.median_step_s() as f32;
    // the blob's discovered terms too: what the MCU compensates
    let mut comp = Compensator::with_terms(cal, &blob.terms, method, period.max(1e-6)).ok()?;
    let mut acc: Vec<([f64; 3], usize, usize)> = vec![([0.0; 3], 0, 0); rec.dwells.len()];
    let mut dwell_of_row = vec![usize::MAX; rec.rows.len()];
    for (i, d) in rec.dwells.iter().enumerate() {
        if select(d.position) {
            dwell_of_row[d.start..d.end].iter_mut().for_each(|x| *x = i);
        }
    }
    for (r, (row, clock)) in rec.rows.iter().zip(rec.clock()).enumerate() {
        if let Some(on) = clock.power_on_s {
            comp.power_on(on as f32);
        }
        let out = comp.compensate_dt(
            row.u.map(|v| v as f32),
            row.temp_c as f32,
            clock.dt_s as f32,
        );
        if let Some(slot) = acc.get_mut(dwell_of_row[r]) {
            if out.accel.iter().all(|v| v.is_finite()) {
                for (s, v) in slot.0.iter_mut().zip(out.accel) {
                    *s += f64::from(v);
                }
                slot.1 += 1;
            }
            if !out.status.is_ok() {
                slot.2 += 1;
            }
        }
    }
    let mut dwells = Vec::new();
    for (i, d) in rec.dwells.iter().enumerate() {
        if !select(d.position) || acc[i].1 == 0 {
            continue;
        }
        let (sum, n, flagged) = acc[i];
        let mean = sum.map(|v| v / n as f64);
        let unc = apply(&n0, d.u_mean, c0.u0);
        dwells.push(DwellCheck {
            position: rec.positions.name(d.position).to_string(),
            temp_c: d.temp_c,
            dg_mg_uncompensated: dg(&unc) * 1e3,
            dg_mg: dg(&mean) * 1e3,
            samples: d.len(),
            flagged,
        });
    }
    let temps: Vec<f64> = dwells.iter().map(|d| d.temp_c).collect();
    let max_by_temperature = temperature_clusters(&temps)
        .into_iter()
        .map(|t| {
            let near = dwells.iter().filter(|d| (d.temp_c - t).abs() <= 2.5);
            let (mut u, mut c) = (0.0f64, 0.0f64);
            for d in near {
                u = u.max(d.dg_mg_uncompensated.abs());
                c = c.max(d.dg_mg.abs());
            }
            TempMax {
                temp_c: t,
                max_abs_dg_mg_uncompensated: u,
                max_abs_dg_mg: c,
            }
        })
        .collect();
    Some(Verification {
        dwells,
        max_by_temperature,
    })
}
