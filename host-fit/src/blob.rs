//! From a fitted model to a flashed blob and back: f32 tables, the discovered terms'
//! table, the f32-vs-f64 check, encoding, reading a blob file, and what `inspect` shows
//! of it.
use crate::data::output_unit::OutputUnit;
use crate::error::{ErrorKind, HostError, Result};
use crate::model::precision::check_with_terms;
use crate::terms::{unit_table, AxisTerm};
use firmware_core::blob::{Blob, RunId, MAGIC, MAX_BLOB_LEN, MAX_SERIAL_LEN};
use firmware_core::model::COEFF_NAMES;
use firmware_core::temperature::{Calibration, Physics, TempModel};
use firmware_core::terms::{TermEntry, TermList};
use serde::Serialize;
use std::path::Path;

/// Build and encode the blob for `serial` from an f64 calibration whose K and U0 are in
/// `output_unit` (the recording's `output_unit`, recorded in the blob); checks the f32
/// path against [`crate::model::precision::F32_BOUND_G`]. Returns the blob, its bytes and the measured departure.
pub fn build_blob(
    serial: &str,
    output_unit: &OutputUnit,
    cal64: &Calibration<f64>,
) -> Result<(Blob, Vec<u8>, f64)> {
    let (blob, bytes, (inside, _)) = build_blob_checked(serial, output_unit, cal64)?;
    Ok((blob, bytes, inside))
}

/// [`build_blob`], returning the departure inside the range and beyond it.
pub fn build_blob_checked(
    serial: &str,
    output_unit: &OutputUnit,
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
    output_unit: &OutputUnit,
    cal64: &Calibration<f64>,
    terms: &[AxisTerm],
) -> Result<(Blob, Vec<u8>, (f64, f64))> {
    let s = blob_serial(serial)?;
    let terms64 = unit_table(terms)
        .map_err(|e| HostError::new(ErrorKind::Blob, format!("cannot build the blob: {e}")))?;
    let blob = Blob {
        serial: s,
        output_unit: output_unit.in_blob(),
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
        .map_err(|e| HostError::new(ErrorKind::Blob, format!("cannot build the blob: {e}")))?;
    let (dep, beyond) = check_with_terms(cal64, &terms64, &blob.calibration, &blob.terms)?;
    Ok((blob, buf[..n].to_vec(), (dep, beyond)))
}

/// The serial as the blob stores it: printable ASCII of at most the blob format's limit
/// (`firmware_core::blob::MAX_SERIAL_LEN` bytes), or an error that states which rule it
/// breaks.
pub fn blob_serial(serial: &str) -> Result<heapless::String<MAX_SERIAL_LEN>> {
    if let Some(c) = serial.chars().find(|c| !(' '..='~').contains(c)) {
        return Err(HostError::new(ErrorKind::Blob, format!(
            "unit serial `{serial}` has `{c}`: the blob stores printable ASCII only (the firmware checks it in place); give another (`fit --serial`, `diagnose --serial`)"
        )));
    }
    let mut s = heapless::String::<MAX_SERIAL_LEN>::new();
    s.push_str(serial).map_err(|_| {
        HostError::new(ErrorKind::Blob, format!(
            "unit serial `{serial}` is {} bytes; the blob format holds at most {MAX_SERIAL_LEN} bytes (firmware_core::blob::MAX_SERIAL_LEN): give a shorter one (`fit --serial`, `diagnose --serial`)",
            serial.len()
        ))
    })?;
    Ok(s)
}

/// The error of a blob (or the blob fitted from `path`) whose K(T0) cannot be inverted.
pub fn singular_k(path: &Path) -> HostError {
    HostError::in_file(ErrorKind::Numerical, path, "K(T0) of the blob is singular")
}

/// Read and decode a blob file; the error names the file and why it is invalid. A file
/// without the magic bytes is "not a blob" (a recording given by mistake, say), said
/// before any check that would call it a corrupted one.
pub fn read_blob(path: &Path) -> Result<(Blob, Vec<u8>)> {
    let bytes = std::fs::read(path).map_err(|e| HostError::io(path, &e))?;
    if !bytes.starts_with(&MAGIC) {
        return Err(HostError::in_file(
            ErrorKind::Blob,
            path,
            not_a_blob(&bytes),
        ));
    }
    let b = Blob::decode(&bytes)
        .map_err(|e| HostError::in_file(ErrorKind::Blob, path, format!("invalid blob: {e}")))?;
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
    /// The rate estimator's low-pass time constant, s (negative: the zero-lag estimator
    /// of time constant `|rate_tau_s|`).
    pub rate_tau_s: f32,
    /// `hysteresis`: the offset split, per axis.
    pub hysteresis: [f32; 3],
    /// The change that sets the direction, C (a relay); negative: a play operator of
    /// half-width `-hysteresis_threshold_c`, linear over twice that after a reversal.
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
                "  temp_rate        r {} per C/s, rate by the {}",
                v(self.rate),
                crate::model::effects::rate_estimator(f64::from(self.rate_tau_s))
            ),
            format!(
                "  hysteresis       h {}, {}, direction at power-on {}",
                v(self.hysteresis),
                if self.hysteresis_threshold_c < 0.0 {
                    format!(
                        "a play operator over {} C (threshold {} C)",
                        -2.0 * self.hysteresis_threshold_c,
                        self.hysteresis_threshold_c
                    )
                } else {
                    format!("threshold {} C", self.hysteresis_threshold_c)
                },
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
        let (blob, bytes, (dep, _)) =
            build_blob_with_terms("U-1", &OutputUnit::parse("V"), &cal, &terms).unwrap();
        assert_eq!(u16::from_le_bytes([bytes[4], bytes[5]]), 5);
        assert!(dep <= crate::model::precision::F32_BOUND_G, "{dep:e}");
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
        let (_, plain, _) = build_blob("U-1", &OutputUnit::parse("V"), &cal).unwrap();
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
            build_blob_with_terms("U-1", &OutputUnit::parse("V"), &cal, terms)
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
