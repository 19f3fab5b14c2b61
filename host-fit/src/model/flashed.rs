//! The diagnosed model in the firmware's form, for `diagnose --out`: the final model in
//! the forms the firmware applies (one lag pole for all axes, hysteresis of the offsets,
//! one warm-up since power-on, a rate estimator smoothing for flight), refitted in those
//! forms where the diagnosis found another, so the blob carries exactly a model that was
//! fitted; every time constant in seconds (the firmware derives its per-step constants
//! from its own clock); its coefficients as
//! the polynomial itself or a piecewise-linear table over the data's temperatures, and
//! its in-flight physics terms.
use crate::error::{ErrorKind, HostError, Result};
use crate::model::basis::{Basis, POLY_SCALE_C};
use crate::model::cache::Cache;
use crate::model::data::Data;
use crate::model::effects::Extra;
use crate::model::library::Timed;
use crate::model::params::{Param, Term};
use crate::model::profile::{time_constant, Grid};
use crate::model::solve::{Depth, Fit};
use crate::terms::AxisTerm;
use firmware_core::model::{K_INDEX, U0_INDEX};
use firmware_core::temperature::{Calibration, Physics, TempModel};
use firmware_core::terms::Axis;

/// The model the blob carries.
#[derive(Debug, Clone)]
pub struct Flashed {
    /// The final model in the firmware's forms, refitted where it differs.
    pub fit: Fit,
    /// Its coefficients on a grid over the data's temperatures: `(temperature, the 12
    /// coefficients)`.
    pub table: Vec<(f64, [f64; 12])>,
    /// The floor of a window mean, output units: the firmware's cache step is chosen to
    /// cost no more than it.
    pub noise_rms: f64,
}

impl Flashed {
    /// The final model `f` of `data` in the firmware's forms; `noise_rms` the floor of
    /// a window mean (output units).
    pub fn of(data: &Data, f: &Fit, noise_rms: f64) -> Flashed {
        let fit = flashable(data, f);
        Flashed {
            table: table(data, &fit),
            noise_rms,
            fit,
        }
    }

    /// The extended model as a firmware calibration: the coefficients as the polynomial
    /// itself, or as a piecewise-linear table (which also carries a temp_curvature
    /// finding), and the in-flight physics terms (fixture_error only corrects the
    /// calibration, which the final fit already does); the firmware's cache step `given`,
    /// or chosen within the floor of a window mean (in g: over the mean scale factor at
    /// T0), as `fit` keeps it within a dwell's own noise.
    pub fn calibration(&self, t0: f64, given: Option<f64>) -> Result<(Calibration<f64>, Cache)> {
        let (lo, hi) = (
            self.table.first().map(|r| r.0).unwrap_or(t0 - 1.0),
            self.table.last().map(|r| r.0).unwrap_or(t0 + 1.0),
        );
        let mut cal = Calibration {
            t0_c: t0,
            t_min_c: lo,
            t_max_c: hi.max(lo + 1.0),
            clamp: false,
            update_step_c: 0.0,
            model: self.poly_table().unwrap_or_else(|| TempModel::Pwl {
                breakpoints: self.table.iter().map(|r| r.0).collect(),
                values: self.table.iter().map(|r| r.1).collect(),
            }),
            physics: self.physics()?,
        };
        let c0 = cal.at_t0();
        let k = (c0[0].abs() + c0[1].abs() + c0[2].abs()) / 3.0;
        let floor_mg = (k > 0.0).then(|| self.noise_rms / k * 1e3);
        let cache = Cache::choose(&cal, floor_mg, given);
        cal.update_step_c = cache.step_c;
        Ok((cal, cache))
    }

    /// The discovered terms of the unit's state in the model (force factors, `dT`,
    /// `dTdt`, `decay(power_on,TAU)`), as a blob's term table carries them with their
    /// fitted coefficients; the terms of the rig or the recording's time correct the
    /// calibration only and are left out (they are reported, never flashed).
    pub fn terms(&self) -> Result<Vec<AxisTerm>> {
        let mut out = Vec::new();
        for (e, x) in self.fit.spec.extras.iter().enumerate() {
            let Extra::Discovered { term, axis } = x else {
                continue;
            };
            if !term.of_unit() {
                continue;
            }
            // typed, not through the report's text: the time constant as fitted
            let parsed = term.term().map_err(|err| {
                HostError::new(
                    ErrorKind::Internal,
                    format!("the discovered term `{term}` is not in the blob's vocabulary: {err}"),
                )
            })?;
            let Some(&fw_axis) = Axis::ALL.get(*axis) else {
                continue;
            };
            out.push(AxisTerm {
                term: parsed,
                axis: fw_axis,
                coefficient: self.fit.term(e, Term::Discovered)[*axis],
            });
        }
        Ok(out)
    }

    /// The in-flight terms in the firmware's form, every time constant in seconds (the
    /// firmware derives its per-step constants from its own clock); `None` when there
    /// are none.
    fn physics(&self) -> Result<Option<Physics<f64>>> {
        let mut ph = Physics::<f64>::neutral();
        ph.hysteresis_threshold_c = 0.5;
        let refuse = |what: &str| {
            Err(HostError::new(ErrorKind::Unsupported, format!(
                "the fitted {what} cannot be flashed by this firmware's physics block; the blob would not compensate what was fitted"
            )))
        };
        let mut any = false;
        for (e, x) in self.fit.spec.extras.iter().enumerate() {
            any |= !matches!(
                x,
                Extra::Curvature(_)
                    | Extra::Bend { .. }
                    | Extra::Fixture(..)
                    | Extra::Discovered { .. }
            );
            match x {
                Extra::Lag { taus } => {
                    if taus.iter().any(|t| *t != taus[0] || t[1] > 0.0) {
                        return refuse("thermal lag (per-axis or two-pole)");
                    }
                    ph.lag_tau_s = taus[0][0];
                }
                // a centred slope never reaches here ([`rate_for_flight`]); if one did, the
                // firmware would read it as a low-pass, so the flight's estimator is flown
                Extra::Rate { tau_s, centred } => {
                    ph.rate = self.fit.term(e, Term::Rate);
                    ph.rate_tau_s = if *centred { -FLIGHT_RATE_TAU_S } else { *tau_s };
                }
                Extra::Hysteresis {
                    threshold_c,
                    initial,
                    scale,
                } => {
                    if *scale {
                        return refuse("hysteresis of the scale factors");
                    }
                    ph.hysteresis = self.fit.term(e, Term::Hysteresis);
                    ph.hysteresis_threshold_c = *threshold_c;
                    ph.hysteresis_initial = *initial;
                }
                Extra::K2 => ph.k2 = self.fit.term(e, Term::K2),
                Extra::Asymmetry => ph.asymmetry = self.fit.term(e, Term::Asymmetry),
                Extra::Warmup { tau_s, .. } => {
                    // in flight the clock restarts at power-on only, as it does here at
                    // the recording's start and its stated power-offs; handling does not
                    // happen
                    if ph.warmup != [0.0; 3] {
                        return refuse("second warm-up time constant");
                    }
                    ph.warmup = self.fit.term(e, Term::Warmup);
                    ph.warmup_tau_s = *tau_s;
                }
                // rig terms correct the calibration only; the unit's terms are in the
                // blob's term table (Flashed::terms), not the physics block
                Extra::Curvature(_)
                | Extra::Bend { .. }
                | Extra::Fixture(..)
                | Extra::Discovered { .. } => {}
            }
        }
        // A discovered term's `dTdt` is read from the block's rate estimator. Without a
        // rate effect (whose estimator is chosen for flight already) the firmware's neutral
        // block differences the sensor per step: a quantised reading at 20 Hz is a spike of
        // tens of C/min, and a dwell's mean rate is off by a quantum over the dwell (the
        // scale-with-rate blind unit flew at 4x the clean unit's error). The flight's
        // estimator is flashed instead, as for the catalogue's rate: the host found the
        // term with a half-minute zero-lag estimator (`library::RATE_TAU_S`), which smooths a
        // chamber recording's quantised steps; the estimator only measures the rate the
        // term multiplies.
        if ph.rate_tau_s == 0.0 && self.rate_terms() {
            ph.rate_tau_s = -FLIGHT_RATE_TAU_S;
            any = true;
        }
        Ok(any.then_some(ph))
    }

    /// Whether a discovered term of the unit's state multiplies the temperature's rate.
    fn rate_terms(&self) -> bool {
        self.fit.spec.extras.iter().any(|x| {
            matches!(x, Extra::Discovered { term, .. }
                if term.of_unit() && term.timed.contains(&Timed::Rate))
        })
    }

    /// The model's polynomial itself, when its temperature dependence is one (no bend,
    /// no fine offsets): exact, where a table through it would interpolate.
    fn poly_table(&self) -> Option<TempModel<f64>> {
        let f = &self.fit;
        let Basis::Poly { order } = f.spec.basis else {
            return None;
        };
        if f.spec
            .extras
            .iter()
            .any(|e| matches!(e, Extra::Curvature(_) | Extra::Bend { .. }))
        {
            return None;
        }
        // the offsets may carry an order above the K rows' (their terms beyond it are
        // zero in the K slots)
        let top = f.spec.offset_order.map_or(order, |o| o.max(order));
        let mut terms = vec![[0.0; 12]; (top + 1).max(2)];
        for (c, l) in f.labels.iter().enumerate() {
            let (slot, k) = match *l {
                Param::K { i, j, k } => (K_INDEX[i][j], k),
                Param::U0 { i, k } => (U0_INDEX[i], k),
                Param::Effect { .. } | Param::FixtureAngle { .. } => continue,
            };
            // the fit's basis is powers of dT / POLY_SCALE_C
            terms[k][slot] += f.x[c] / POLY_SCALE_C.powi(k as i32);
        }
        Some(TempModel::Poly {
            terms: terms.into_iter().collect(),
        })
    }
}

/// The rate estimator the blob carries, s: the zero-lag estimator of this time constant
/// (flashed as `rate_tau_s = -4`), chosen for flight, not for the chamber (the other
/// coefficients are refitted with it, `r` held). `r` is the unit's physics, an offset per
/// C/s of its temperature's rate; the estimator only measures that rate. A low-pass
/// estimator fitted to a chamber recording (the search's; the final model's is a centred
/// slope, `model::profile::centred_rate`) smooths its 10-s rows of a quantised sensor over
/// tens of seconds, which in flight lags a fast change by as much (the twin's
/// flight, warming and cooling at 5-8 C/min: 0.44 mg at the chamber's 40 s); a 2-s
/// low-pass still trails by 2 s, `r` times 2 s times the temperature's acceleration as
/// the case's 120-s time constant turns a ramp: 0.049 mg on the rate alone, 0.059 mg
/// beside a lag. The zero-lag estimator (`2 L1 - L2` of two low-passes,
/// `firmware_core::inflight::Rate`) does not trail: its error is of the order of `tau^2`
/// times the temperature's third derivative. Its price is noise, up to twice the
/// low-pass's, which a longer time constant pays back: the mean of the estimate over a
/// held attitude of D seconds is the change of its smoothed temperature over the hold
/// over D, about sigma sqrt(h / tau) / D (sigma the sensor's 0.027 C, h the 0.1 s step:
/// 1.1e-4 C/s over 40 s at 4 s, times `r`); each sample's, about sigma / tau (0.007 C/s at
/// 4 s). Measured with `tests/tests/time_true.rs`'s twins (docs/diagnosis.md): zero-lag
/// over 2 s the rate unit flew at 0.037 mg, the lag + rate unit at 0.038 mg, but the
/// chamber recording at 1 Hz of a unit with 3x the nominal rate term was compensated at
/// worst to 0.063 mg (its noise); over 4 s 0.035, 0.030 and 0.048 mg; over 8 s 0.035,
/// 0.046 and 0.042 mg (the corners' `tau^2` error returning; measured with the settling
/// after a power-on capped at 25.5 s, an earlier form of it).
pub const FLIGHT_RATE_TAU_S: f64 = 4.0;

/// `f` with its rate estimator the flight's ([`FLIGHT_RATE_TAU_S`], zero-lag), `r` held
/// and every other coefficient refitted with it (`f` at its own coefficients with the
/// flight's estimator when the refit is not determined; `f` itself without a rate
/// term). `r` is not refitted with the flight's estimator: on a
/// chamber recording of a quantised sensor the fast estimator's noise dilutes the
/// regression (the window means of a 2-s estimate scattered by a tenth of a 1 C/min ramp),
/// so a refit shrinks `r`, by about 1 % alone and by 3-4 % beside a hysteresis, which
/// takes the rest on the ramps (where the direction and the rate's sign agree); in flight
/// at 6 C/min that missing part of `r` is 0.1 mg. The `r` the diagnosis estimated with the
/// estimator the data preferred is the unit's; the rest (the tables, a lag's or a
/// hysteresis's coefficients) is refitted around it.
fn rate_for_flight(data: &Data, f: Fit) -> Fit {
    let flight = -FLIGHT_RATE_TAU_S;
    let at =
        f.spec.extras.iter().position(
            |e| matches!(e, Extra::Rate { tau_s, centred } if *centred || *tau_s != flight),
        );
    let Some(i) = at else {
        return f;
    };
    let spec = f.spec.replaced(
        i,
        Extra::Rate {
            tau_s: flight,
            centred: false,
        },
    );
    let held: Vec<usize> = (0..f.labels.len())
        .filter(|&j| f.labels[j].extra() == Some(i))
        .collect();
    // never the host's centred slope in a blob: the firmware cannot look ahead, and it
    // reads a positive time constant as a low-pass, which would trail by as much; where
    // the refit is not determined the coefficients fly as estimated
    data.fit_holding(&spec, Some(&f.k_at), &f.x, &held)
        .or_else(|| data.evaluate(&spec, Some(&f.k_at), &f.x))
        .unwrap_or(f)
}

/// `f` in the firmware's forms, refitted (a single lag pole profiled again) where it
/// differs, its rate estimator for flight ([`FLIGHT_RATE_TAU_S`]); `f` itself when it is
/// already flashable or a refit is not determined.
fn flashable(data: &Data, f: &Fit) -> Fit {
    rate_for_flight(data, firmware_forms(data, f))
}

/// `f` in the firmware's forms, the rate estimator aside (see [`flashable`]).
fn firmware_forms(data: &Data, f: &Fit) -> Fit {
    let mut spec = f.spec.clone();
    let mut changed = false;
    let mut warmups = 0;
    spec.extras.retain(|e| {
        if let Extra::Warmup { .. } = e {
            warmups += 1;
            changed |= warmups > 1;
            warmups == 1
        } else {
            true
        }
    });
    let mut lag_at = None;
    for (i, e) in spec.extras.iter_mut().enumerate() {
        match e {
            Extra::Hysteresis { scale, .. } if *scale => {
                *scale = false;
                changed = true;
            }
            Extra::Lag { taus } if taus.iter().any(|t| *t != taus[0] || t[1] > 0.0) => {
                lag_at = Some((i, taus.iter().map(|t| t[0] + t[1]).sum::<f64>() / 3.0));
                changed = true;
            }
            Extra::Hysteresis { .. }
            | Extra::Lag { .. }
            | Extra::Curvature(_)
            | Extra::Bend { .. }
            | Extra::Rate { .. }
            | Extra::K2
            | Extra::Asymmetry
            | Extra::Fixture(..)
            | Extra::Warmup { .. }
            | Extra::Discovered { .. } => {}
        }
    }
    if !changed {
        return f.clone();
    }
    if let Some((i, tau)) = lag_at {
        let make = |t: f64| {
            let s = spec.replaced(
                i,
                Extra::Lag {
                    taus: [[t, 0.0]; 3],
                },
            );
            data.fit(&s, None, Depth::Profile)
        };
        if let Some((t, _)) = time_constant(&make, Grid::around(data, tau, 3, 7)) {
            spec.extras[i] = Extra::Lag {
                taus: [[t, 0.0]; 3],
            };
        }
    }
    data.fit(&spec, None, Depth::Full)
        .unwrap_or_else(|| f.clone())
}

/// The grid of the blob's table over `(tmin, tmax)`: up to `max_points`, one per `step_c`;
/// each bend of `knots` moved onto the nearest interior point no other bend took (so the
/// table carries every bend sharp).
pub fn table_grid(
    (tmin, tmax): (f64, f64),
    step_c: f64,
    max_points: usize,
    knots: &[f64],
) -> Vec<f64> {
    let nb = max_points
        .min(((tmax - tmin) / step_c).floor() as usize + 1)
        .max(2);
    let mut grid: Vec<f64> = (0..nb)
        .map(|k| tmin + (tmax - tmin) * k as f64 / (nb - 1) as f64)
        .collect();
    let mut taken = vec![false; nb];
    for knot_c in knots {
        let nearest = (1..nb - 1).filter(|&i| !taken[i]).min_by(|&a, &b| {
            (grid[a] - knot_c)
                .abs()
                .total_cmp(&(grid[b] - knot_c).abs())
        });
        if let Some(i) = nearest {
            grid[i] = *knot_c;
            taken[i] = true;
        }
    }
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    grid
}

/// The model's coefficients on the table grid over the data's temperature range.
fn table(data: &Data, f: &Fit) -> Vec<(f64, [f64; 12])> {
    let knots: Vec<f64> = f
        .spec
        .extras
        .iter()
        .filter_map(|e| {
            if let Extra::Bend { knot_c } = e {
                Some(*knot_c)
            } else {
                None
            }
        })
        .collect();
    let r = &data.rules;
    let grid = table_grid(
        data.temperature_range(),
        r.table_step_c,
        r.max_breakpoints,
        &knots,
    );
    grid.iter()
        .zip(data.coefficients_at(f, &grid))
        .map(|(t, (k, u0))| (*t, firmware_core::model::Coeffs { k, u0 }.to_array()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_grid_spans_the_range_one_point_per_step_at_most_the_limit() {
        let g = table_grid((-20.0, 40.0), 2.0, 16, &[]);
        assert_eq!(g.len(), 16);
        assert_eq!((g[0], g[15]), (-20.0, 40.0));
        assert_eq!(table_grid((20.0, 21.0), 2.0, 16, &[]), vec![20.0, 21.0]);
    }

    /// Two bends near one grid point each get a point of their own: the table carries
    /// both sharp (the second must not move the point the first took).
    #[test]
    fn two_nearby_bends_do_not_move_the_same_grid_point() {
        let knots = [9.0, 9.5];
        let g = table_grid((-20.0, 40.0), 2.0, 16, &knots);
        for k in knots {
            assert!(g.contains(&k), "bend at {k} C is not on the grid {g:?}");
        }
        assert_eq!(g.len(), 16, "{g:?}");
        assert!(g.windows(2).all(|w| w[0] < w[1]), "{g:?}");
        assert_eq!((g[0], g[15]), (-20.0, 40.0), "the ends stay");
    }
}
