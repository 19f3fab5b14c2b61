//! From a fitted model to a flashed blob and back: f32 tables, the discovered terms'
//! table, the f32-vs-f64 check, encoding, reading a blob file, and what `inspect` shows
//! of it.
use crate::data::recording::Recording;
use crate::error::{HostError, Result};
use crate::fit::noise::Noise;
use crate::fit::pipeline::FitOutcome;
use crate::fit::predict::{directions, sigma_dwell_noise};
use crate::fit::temperature::ModelFit;
use crate::terms::{unit_table, AxisTerm};
use firmware_core::blob::{Blob, OutputUnit, RunId, MAGIC, MAX_BLOB_LEN, MAX_SERIAL_LEN};
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::model::{Coeffs, COEFF_NAMES};
use firmware_core::temperature::{Calibration, Physics, TempModel};
use firmware_core::terms::{TermEntry, TermList};
use serde::Serialize;
use std::path::Path;

/// Documented bound: the firmware's f32 path (f32 tables, f32 arithmetic) stays within
/// this many g of the f64 evaluation of the unrounded model, for |a| <= 1 g, inside the
/// valid temperature range. Held by [`build_blob`] on every blob built; the departure in
/// the 10 C beyond the range (extrapolation, where a high-order polynomial loses f32
/// digits) is measured and reported.
pub const F32_BOUND_G: f64 = 2e-6;

/// 26 unit directions: the axes, the face diagonals and the cube's corners, both signs.
fn directions26() -> Vec<[f64; 3]> {
    let mut dirs = Vec::new();
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                let v = [f64::from(x), f64::from(y), f64::from(z)];
                let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if n > 0.0 {
                    dirs.push(v.map(|c| c / n));
                }
            }
        }
    }
    dirs
}

/// The largest cache step `fit`, `diagnose --out`, `batch` and the demo give the
/// firmware by default, C.
pub const MAX_CACHE_STEP_C: f64 = 0.1;
/// Grid of [`cache_slope`], C.
const CACHE_GRID_C: f64 = 0.05;

/// How fast |a| drifts while the firmware holds its cached coefficients and the unit's
/// temperature moves, g/C: `|d|a|/dT| = |a^T N (dK/dT a + dU0/dT)|` of the calibration's
/// own model, by differences over every 0.05 C cell of the valid range (exact within a
/// piecewise-linear segment), worst of 26 directions (any attitude: in flight too).
pub fn cache_slope(cal: &Calibration<f64>) -> f64 {
    let dirs = directions26();
    let eval = |t: f64| Coeffs::from_array(&cal.model.eval(cal.t0_c, t));
    let mut worst: f64 = 0.0;
    let mut t = cal.t_min_c;
    while t < cal.t_max_c {
        let h = CACHE_GRID_C.min(cal.t_max_c - t).max(1e-6);
        let (c0, c1) = (eval(t), eval(t + h));
        let Some(n) = firmware_core::model::invert(&c0.k) else {
            t += CACHE_GRID_C;
            continue;
        };
        for a in &dirs {
            // d|a'|/dT for the reading U(T + h) compensated with the coefficients of T
            let du: [f64; 3] = std::array::from_fn(|i| {
                (0..3)
                    .map(|j| (c1.k[i][j] - c0.k[i][j]) * a[j])
                    .sum::<f64>()
                    + c1.u0[i]
                    - c0.u0[i]
            });
            let da: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| n[i][j] * du[j]).sum());
            let d = (a[0] * da[0] + a[1] * da[1] + a[2] * da[2]).abs() / h;
            worst = worst.max(d);
        }
        t += CACHE_GRID_C;
    }
    worst
}

/// A fitted model of a recording, as the cache's floor needs it.
#[derive(Debug, Clone, Copy)]
pub struct Model<'a> {
    /// The recording.
    pub rec: &'a Recording,
    /// Its positions, every pose with a vector (the estimated ones where unknown).
    pub positions: &'a crate::data::positions::Positions,
    /// The model.
    pub fit: &'a ModelFit,
    /// Its noise.
    pub noise: &'a Noise,
}

/// The firmware's cache of N(T): its step and the most it can cost.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Cache {
    /// The update step written into the blob, C.
    pub step_c: f64,
    /// The most the cache can add to |dg| anywhere in the valid range, at any attitude
    /// (`cache_slope` x step), mg.
    pub worst_mg: f64,
    /// The noise floor the default step keeps it within (a verification dwell's own
    /// noise, 1 sigma), mg; None when none is known.
    pub floor_mg: Option<f64>,
    /// Whether the step was chosen from the unit's slopes (true) or given.
    pub chosen: bool,
}

impl Cache {
    /// `given` (`--update-step`), or by default the largest step up to
    /// [`MAX_CACHE_STEP_C`] whose worst cost stays within `floor_mg` (rounded down to
    /// 1e-4 C); with no floor known, 0 (the model at every temperature).
    pub fn choose(cal: &Calibration<f64>, floor_mg: Option<f64>, given: Option<f64>) -> Cache {
        let slope_mg = cache_slope(cal) * 1e3;
        let step_c = match (given, floor_mg) {
            (Some(s), _) => s,
            (None, Some(f)) if f > 0.0 && slope_mg > 0.0 => {
                (((f / slope_mg).min(MAX_CACHE_STEP_C) * 1e4).floor() / 1e4).max(0.0)
            }
            (None, Some(f)) if f > 0.0 => MAX_CACHE_STEP_C,
            (None, _) => 0.0,
        };
        Cache {
            step_c,
            worst_mg: slope_mg * step_c,
            floor_mg,
            chosen: given.is_none(),
        }
    }

    /// The cache of a fitted model's calibration (`fit`, `batch`): `given`
    /// (`--update-step`), or chosen within a verification dwell's own noise as the fit
    /// predicts it ([`Cache::for_model`], with the poses it estimated); `cal` takes the
    /// step.
    pub fn for_fit(
        rec: &Recording,
        oc: &FitOutcome,
        cal: &mut Calibration<f64>,
        given: Option<f64>,
    ) -> Cache {
        // the estimated poses' vectors, carried with the fit
        let positions = oc
            .orientation
            .as_ref()
            .map_or(&rec.positions, |o| &o.positions);
        let model = Model {
            rec,
            positions,
            fit: &oc.fit,
            noise: &oc.noise,
        };
        Cache::for_model(&model, cal, given)
    }

    /// [`Cache::choose`] for the model `fit` of `rec`: the floor is the noise a
    /// verification dwell of the recording's median length adds of its own (1 sigma,
    /// worst of its verification directions, as `fit` predicts it); `cal` takes the step.
    pub fn for_model(m: &Model, cal: &mut Calibration<f64>, given: Option<f64>) -> Cache {
        let (fit, noise) = (m.fit, m.noise);
        let floor = (!fit.axis_cov.is_empty()).then(|| {
            let (dirs, n) = directions(m.rec, m.positions);
            dirs.iter()
                .map(|d| sigma_dwell_noise(fit, noise, fit.t0_c, d.a, n))
                .fold(0.0, f64::max)
                * 1e3
        });
        let cache = Cache::choose(cal, floor, given);
        cal.update_step_c = cache.step_c;
        cache
    }

    /// One line for the command's text output.
    pub fn text(&self) -> String {
        let how = if self.chosen {
            match self.floor_mg {
                Some(f) => format!(
                    "chosen from the unit's slopes to stay within the dwell-noise floor {f:.4} mg"
                ),
                None => "no noise floor known: the model at every temperature".to_string(),
            }
        } else {
            "as given (--update-step)".to_string()
        };
        format!(
            "firmware cache: N(T) recomputed after {} C ({how}); it costs at most {:.4} mg anywhere in the valid range, at any attitude",
            self.step_c, self.worst_mg
        )
    }
}

/// Largest |a_f32 - a_f64| (g) over a grid of temperatures (0.5 C steps) and 26
/// directions, for method 1 and method 2 (full): inside the valid range, and in the
/// 10 C beyond it.
pub fn f32_departure(cal64: &Calibration<f64>, cal32: &Calibration<f32>) -> Result<(f64, f64)> {
    f32_departure_with_terms(cal64, &[], cal32, &[])
}

/// [`f32_departure`] of a calibration with its discovered terms (each side's own: the
/// f64 table and the f32 one the blob holds).
pub fn f32_departure_with_terms(
    cal64: &Calibration<f64>,
    terms64: &[TermEntry<f64>],
    cal32: &Calibration<f32>,
    terms32: &[TermEntry<f32>],
) -> Result<(f64, f64)> {
    let mut c64 = cal64.clone();
    c64.update_step_c = 0.0;
    let mut c32 = cal32.clone();
    c32.update_step_c = 0.0;
    let dirs = directions26();
    let (mut inside, mut beyond): (f64, f64) = (0.0, 0.0);
    for method in [
        Method::CorrectConstants,
        Method::CorrectResult(ErrorModel::Full),
    ] {
        // one sample a second: the physics terms' machines follow the sweep alike in both
        let mut m64 = Compensator::with_terms(&c64, terms64, method, 1.0)
            .map_err(|e| HostError::msg(e.to_string()))?;
        let mut m32 = Compensator::with_terms(&c32, terms32, method, 1.0)
            .map_err(|e| HostError::msg(e.to_string()))?;
        let mut t = cal64.t_min_c - 10.0;
        while t <= cal64.t_max_c + 10.0 {
            let t32 = t as f32;
            let coeffs = Coeffs::from_array(&cal64.model.eval(cal64.t0_c, f64::from(t32)));
            for a in &dirs {
                let u = coeffs.forward(*a).map(|v| f64::from(v as f32));
                let r64 = m64.compensate(u, f64::from(t32)).accel;
                let r32 = m32.compensate(u.map(|v| v as f32), t32).accel;
                let in_range = (cal64.t_min_c..=cal64.t_max_c).contains(&f64::from(t32));
                for (x, y) in r64.iter().zip(r32.iter()) {
                    let d = (x - f64::from(*y)).abs();
                    if in_range {
                        inside = inside.max(d);
                    } else {
                        beyond = beyond.max(d);
                    }
                }
            }
            t += 0.5;
        }
    }
    Ok((inside, beyond))
}

/// Build and encode the blob for `serial` from an f64 calibration whose K and U0 are in
/// `output_unit` (the recording's `output_unit`, recorded in the blob); checks the f32
/// path against [`F32_BOUND_G`]. Returns the blob, its bytes and the measured departure.
pub fn build_blob(
    serial: &str,
    output_unit: &str,
    cal64: &Calibration<f64>,
) -> Result<(Blob, Vec<u8>, f64)> {
    let (blob, bytes, (inside, _)) = build_blob_checked(serial, output_unit, cal64)?;
    Ok((blob, bytes, inside))
}

/// [`build_blob`], returning the departure inside the range and beyond it.
pub fn build_blob_checked(
    serial: &str,
    output_unit: &str,
    cal64: &Calibration<f64>,
) -> Result<(Blob, Vec<u8>, (f64, f64))> {
    build_blob_with_terms(serial, output_unit, cal64, &[])
}

/// [`build_blob_checked`] with discovered terms of the unit's state on their axes (the
/// `discovered` findings a diagnosis flashes): the blob's term table (format 5; a term of
/// the rig or the recording's time, more than 8 terms, a term twice on one axis or a
/// non-finite coefficient are refused, each error naming the term). The f32 check covers
/// the terms too.
pub fn build_blob_with_terms(
    serial: &str,
    output_unit: &str,
    cal64: &Calibration<f64>,
    terms: &[AxisTerm],
) -> Result<(Blob, Vec<u8>, (f64, f64))> {
    let s = blob_serial(serial)?;
    let terms64 =
        unit_table(terms).map_err(|e| HostError::msg(format!("cannot build the blob: {e}")))?;
    let blob = Blob {
        serial: s,
        output_unit: OutputUnit::from_label(output_unit),
        run_id: RunId::NONE,
        calibration: cal64.convert(),
        terms: terms64
            .iter()
            .map(TermEntry::convert)
            .collect::<TermList<f32>>(),
    };
    let mut buf = [0u8; MAX_BLOB_LEN];
    let n = blob
        .encode(&mut buf)
        .map_err(|e| HostError::msg(format!("cannot build the blob: {e}")))?;
    let (dep, beyond) = f32_departure_with_terms(cal64, &terms64, &blob.calibration, &blob.terms)?;
    if dep.is_nan() || dep > F32_BOUND_G {
        return Err(HostError::msg(format!(
            "the f32 firmware path departs from the f64 model by {dep:.3e} g, over the bound {F32_BOUND_G:.1e} g: the unit's K is too ill-conditioned for f32"
        )));
    }
    Ok((blob, buf[..n].to_vec(), (dep, beyond)))
}

/// The serial as the blob stores it: printable ASCII of at most the blob format's limit
/// (`firmware_core::blob::MAX_SERIAL_LEN` bytes), or an error that states which rule it
/// breaks.
pub fn blob_serial(serial: &str) -> Result<heapless::String<MAX_SERIAL_LEN>> {
    if let Some(c) = serial.chars().find(|c| !(' '..='~').contains(c)) {
        return Err(HostError::msg(format!(
            "unit serial `{serial}` has `{c}`: the blob stores printable ASCII only (the firmware checks it in place); give another (`fit --serial`, `diagnose --serial`)"
        )));
    }
    let mut s = heapless::String::<MAX_SERIAL_LEN>::new();
    s.push_str(serial).map_err(|_| {
        HostError::msg(format!(
            "unit serial `{serial}` is {} bytes; the blob format holds at most {MAX_SERIAL_LEN} bytes (firmware_core::blob::MAX_SERIAL_LEN): give a shorter one (`fit --serial`, `diagnose --serial`)",
            serial.len()
        ))
    })?;
    Ok(s)
}

/// Read and decode a blob file; the error names the file and why it is invalid. A file
/// without the magic bytes is "not a blob" (a recording given by mistake, say), said
/// before any check that would call it a corrupted one.
pub fn read_blob(path: &Path) -> Result<(Blob, Vec<u8>)> {
    let bytes = std::fs::read(path).map_err(|e| HostError::io(path, &e))?;
    if !bytes.starts_with(&MAGIC) {
        return Err(HostError::in_file(path, not_a_blob(&bytes)));
    }
    let b =
        Blob::decode(&bytes).map_err(|e| HostError::in_file(path, format!("invalid blob: {e}")))?;
    Ok((b, bytes))
}

/// Why `bytes` is not a blob: the magic is missing; what the file starts with instead,
/// as text when it is printable, else as hex.
fn not_a_blob(bytes: &[u8]) -> String {
    let magic = String::from_utf8_lossy(&MAGIC);
    if bytes.is_empty() {
        return format!("not a blob: the file is empty (a blob starts with `{magic}`)");
    }
    let head = &bytes[..bytes.len().min(16)];
    let text = |b: &u8| (b' '..=b'~').contains(b) || b"\t\r\n".contains(b);
    let shown = if head.iter().all(text) {
        format!("`{}`", head.escape_ascii())
    } else {
        head.iter()
            .map(|b| format!("{b:02x}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    format!(
        "not a blob: it starts with {shown}{}, not with the blob's magic `{magic}` (a blob is written by `fit` or `diagnose --out`)",
        if bytes.len() > head.len() { "..." } else { "" }
    )
}

/// What `inspect` shows of a blob.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Inspection {
    /// Blob format version.
    pub format_version: u16,
    /// Size, bytes.
    pub bytes: usize,
    /// Unit serial.
    pub serial: String,
    /// The unit K and U0 are in (`V`, `m/s2`, ...; `unstated`, `other`).
    pub output_unit: &'static str,
    /// The host-fit run that made the blob (32 hex digits), None when it has none.
    pub run_id: Option<String>,
    /// Reference temperature, C.
    pub t0_c: f32,
    /// Valid range, C.
    pub t_min_c: f32,
    /// Valid range, C.
    pub t_max_c: f32,
    /// Outside the range: clamp (true) or extrapolate.
    pub clamp: bool,
    /// Cache update step, C.
    pub update_step_c: f32,
    /// `polyN` or `pwl`.
    pub model: String,
    /// The coefficient names, in table order.
    pub columns: [&'static str; 12],
    /// The table rows.
    pub rows: Vec<InspectRow>,
    /// The in-flight physics terms (`diagnose --out`), every one of them; None when the
    /// blob has none.
    pub physics: Option<PhysicsTerms>,
    /// The discovered terms of the blob's term table (format 5), in table order; empty
    /// when it has none.
    pub terms: Vec<InspectTerm>,
}

/// One entry of a blob's table of discovered terms.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct InspectTerm {
    /// The axis whose output it enters (`x`, `y`, `z`).
    pub axis: &'static str,
    /// The term in the vocabulary's canonical text.
    pub term: crate::terms::Term,
    /// Its coefficient (output units per the term's units), as stored.
    pub coefficient: f32,
}

impl InspectTerm {
    fn of(e: &TermEntry<f32>) -> Self {
        let t = AxisTerm::of_entry(e);
        InspectTerm {
            axis: t.axis.name(),
            term: t.term,
            coefficient: e.coefficient,
        }
    }
}

/// Every in-flight term of a blob, as stored (time constants in seconds).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PhysicsTerms {
    /// `thermal_lag`: the time constant, s (0: no lag).
    pub lag_tau_s: f32,
    /// `temp_rate`: offset per C/s, per axis.
    pub rate: [f32; 3],
    /// The rate estimator's low-pass time constant, s.
    pub rate_tau_s: f32,
    /// `hysteresis`: the offset split, per axis.
    pub hysteresis: [f32; 3],
    /// The change that sets the direction, C.
    pub hysteresis_threshold_c: f32,
    /// The direction at power-on (+1 heated, -1 cooled, 0 unknown).
    pub hysteresis_initial: f32,
    /// `nonlinearity_k2`, per axis.
    pub k2: [f32; 3],
    /// `scale_asymmetry`, per axis.
    pub asymmetry: [f32; 3],
    /// `warmup_drift` amplitude, per axis.
    pub warmup: [f32; 3],
    /// Its time constant since power-on, s (0: no warm-up).
    pub warmup_tau_s: f32,
}

impl PhysicsTerms {
    fn of(p: &Physics<f32>) -> Self {
        PhysicsTerms {
            lag_tau_s: p.lag_tau_s,
            rate: p.rate,
            rate_tau_s: p.rate_tau_s,
            hysteresis: p.hysteresis,
            hysteresis_threshold_c: p.hysteresis_threshold_c,
            hysteresis_initial: p.hysteresis_initial,
            k2: p.k2,
            asymmetry: p.asymmetry,
            warmup: p.warmup,
            warmup_tau_s: p.warmup_tau_s,
        }
    }

    fn text(&self) -> String {
        let tau = |t: f32| {
            if t > 0.0 {
                format!("{t:.4e} s")
            } else {
                "none".to_string()
            }
        };
        let v = |a: [f32; 3]| format!("[{:.4e}, {:.4e}, {:.4e}]", a[0], a[1], a[2]);
        [
            "in-flight terms (time constants in seconds; the firmware steps them on its own sample period):".to_string(),
            format!("  thermal_lag      tau {}", tau(self.lag_tau_s)),
            format!(
                "  temp_rate        r {} per C/s, rate low-pass tau {}",
                v(self.rate),
                tau(self.rate_tau_s)
            ),
            format!(
                "  hysteresis       h {}, threshold {} C, direction at power-on {}",
                v(self.hysteresis),
                self.hysteresis_threshold_c,
                self.hysteresis_initial
            ),
            format!("  nonlinearity_k2  k2 {}", v(self.k2)),
            format!("  scale_asymmetry  c {}", v(self.asymmetry)),
            format!(
                "  warmup_drift     d {}, tau {} since power-on",
                v(self.warmup),
                tau(self.warmup_tau_s)
            ),
        ]
        .join("\n")
    }
}

/// The discovered terms' lines of `inspect`: each as the output it enters, its
/// coefficient and its canonical text.
fn terms_text(terms: &[InspectTerm]) -> String {
    if terms.is_empty() {
        return "discovered terms: none".to_string();
    }
    let mut s = format!(
        "discovered terms ({}; U_axis += c * term, c in output units per the term's units: g^k, C of dT, C/min of dTdt; decays since power-on):",
        terms.len()
    );
    for t in terms {
        s.push_str(&format!(
            "\n  {} += {:>10.4e} * {}",
            t.axis, t.coefficient, t.term
        ));
    }
    s
}

/// One table row: `dT^k` (poly) or a breakpoint (pwl).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct InspectRow {
    /// `dT^k` or `T C`.
    pub at: String,
    /// The 12 values.
    pub values: Vec<f32>,
}

impl Inspection {
    /// Describe a decoded blob of `bytes` bytes.
    pub fn of(b: &Blob, bytes: usize) -> Self {
        let c = &b.calibration;
        let (model, rows) = match &c.model {
            TempModel::Poly { terms } => (
                format!("poly{}", terms.len() - 1),
                terms
                    .iter()
                    .enumerate()
                    .map(|(k, r)| InspectRow {
                        at: format!("dT^{k}"),
                        values: r.to_vec(),
                    })
                    .collect(),
            ),
            TempModel::Pwl {
                breakpoints,
                values,
            } => (
                "pwl".to_string(),
                breakpoints
                    .iter()
                    .zip(values)
                    .map(|(t, r)| InspectRow {
                        at: format!("{t} C"),
                        values: r.to_vec(),
                    })
                    .collect(),
            ),
        };
        Inspection {
            format_version: b.version(),
            bytes,
            serial: b.serial.to_string(),
            output_unit: b.output_unit.label(),
            run_id: (!b.run_id.is_none()).then(|| b.run_id.to_string()),
            t0_c: c.t0_c,
            t_min_c: c.t_min_c,
            t_max_c: c.t_max_c,
            clamp: c.clamp,
            update_step_c: c.update_step_c,
            model,
            columns: COEFF_NAMES,
            rows,
            physics: c.physics.as_ref().map(PhysicsTerms::of),
            terms: b.terms.iter().map(InspectTerm::of).collect(),
        }
    }

    /// As text (the blob's path as given on the command line).
    pub fn text(&self, path: &Path) -> String {
        let mut s = format!(
            "blob {} ({} bytes, format {}): serial {}, run {}\n",
            path.display(),
            self.bytes,
            self.format_version,
            self.serial,
            self.run_id.as_deref().unwrap_or("not recorded")
        );
        // the header's values are f32: two decimals say what they mean, not their rounding
        s.push_str(&format!(
            "T0 {:.2} C, valid {:.2}..{:.2} C, {}, update step {:.2} C, model {}\n",
            self.t0_c,
            self.t_min_c,
            self.t_max_c,
            if self.clamp {
                "clamped"
            } else {
                "extrapolated"
            },
            self.update_step_c,
            self.model
        ));
        let unit = match self.output_unit {
            "unstated" => "the output unit (not stated in the blob)".to_string(),
            "other" => "the recording's own output unit (not one the format lists)".to_string(),
            u => u.to_string(),
        };
        s.push_str(&format!(
            "table (K in {unit} per g, U0 in {unit}; a polynomial's row dT^k per C^k):\n"
        ));
        s.push_str(&format!(
            "{:>10} {}\n",
            "",
            self.columns.map(|n| format!("{n:>12}")).join("")
        ));
        for r in &self.rows {
            s.push_str(&format!(
                "{:>10} {}\n",
                r.at,
                r.values
                    .iter()
                    .map(|v| format!("{v:>12.4e}"))
                    .collect::<String>()
            ));
        }
        match &self.physics {
            Some(p) => s.push_str(&p.text()),
            None => s.push_str("in-flight terms: none"),
        }
        s.push('\n');
        s.push_str(&terms_text(&self.terms));
        s.trim_end().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::Term;
    use firmware_core::blob::example_blob;
    use firmware_core::terms::Axis;

    fn t(text: &str, axis: Axis, coefficient: f64) -> AxisTerm {
        AxisTerm {
            term: text.parse::<Term>().unwrap(),
            axis,
            coefficient,
        }
    }

    /// Typed terms with coefficients -> a format-5 blob -> the same terms read back (the
    /// coefficients rounded to f32), shown by `inspect` in canonical text.
    #[test]
    fn terms_are_written_and_read_back() {
        let cal: Calibration<f64> = example_blob().calibration.convert();
        let terms = [
            t("a_y*a_x", Axis::Z, 1.5e-4),
            t("dT*decay(power_on,1200s)", Axis::X, -3e-6),
            t("a_x^3", Axis::X, 8e-5),
        ];
        let (blob, bytes, (dep, _)) = build_blob_with_terms("U-1", "V", &cal, &terms).unwrap();
        assert_eq!(u16::from_le_bytes([bytes[4], bytes[5]]), 5);
        assert!(dep <= F32_BOUND_G, "{dep:e}");
        let back = Blob::decode(&bytes).unwrap();
        assert_eq!(back, blob);
        let read: Vec<AxisTerm> = back.terms.iter().map(AxisTerm::of_entry).collect();
        for (r, w) in read.iter().zip(&terms) {
            assert_eq!((&r.term, r.axis), (&w.term, w.axis));
            assert_eq!(r.coefficient, f64::from(w.coefficient as f32));
        }
        let i = Inspection::of(&back, bytes.len());
        assert_eq!(i.format_version, 5);
        let text = i.text(Path::new("u.blob"));
        assert!(
            text.contains("discovered terms (3; U_axis += c * term"),
            "{text}"
        );
        assert!(text.contains("\n  z +=  1.5000e-4 * a_x*a_y"), "{text}");
        assert!(
            text.contains("\n  x += -3.0000e-6 * dT*decay(power_on,20min)"),
            "{text}"
        );
        assert!(text.contains("\n  x +=  8.0000e-5 * a_x^3"), "{text}");
        let j = serde_json::to_value(&i).unwrap();
        assert_eq!(j["terms"][0]["term"], "a_x*a_y");
        assert_eq!(j["terms"][1]["axis"], "x");
        // without terms: format 4, as before
        let (_, plain, _) = build_blob("U-1", "V", &cal).unwrap();
        assert_eq!(plain[4], 4);
        let i = Inspection::of(&Blob::decode(&plain).unwrap(), plain.len());
        assert!(i
            .text(Path::new("p.blob"))
            .ends_with("discovered terms: none"));
    }

    /// What cannot be flashed is refused with the term named: a rig term, a table of
    /// more than 8, a term twice on one axis.
    #[test]
    fn terms_that_cannot_be_flashed_are_refused_by_name() {
        let cal: Calibration<f64> = example_blob().calibration.convert();
        let err = |terms: &[AxisTerm]| {
            build_blob_with_terms("U-1", "V", &cal, terms)
                .unwrap_err()
                .to_string()
        };
        let rig = err(&[t("a_x*t", Axis::Y, 1e-4)]);
        assert!(rig.contains("term `a_x*t` is a term of the rig"), "{rig}");
        let twice = err(&[t("a_x*a_y", Axis::Y, 1e-4), t("a_y*a_x", Axis::Y, 2e-4)]);
        assert!(twice.contains("term `a_x*a_y`: twice on axis y"), "{twice}");
        let nine: Vec<AxisTerm> = [
            "a_x", "a_y", "a_z", "dT", "dTdt", "a_x^2", "a_y^2", "a_z^2", "a_x*a_y",
        ]
        .iter()
        .map(|s| t(s, Axis::X, 1e-5))
        .collect();
        assert!(err(&nine).contains("at most 8"));
    }
}
