//! Coefficient tables (the format of paper-tables.csv): one row of the 12 coefficients
//! per temperature, read by `temp-fit` and written by `identify --csv`.
use crate::data::fields;
use crate::error::{ErrorKind, HostError, Result};
use firmware_core::model::COEFF_NAMES;
use std::path::Path;

/// One row of a coefficient table (COEFFS.csv / per-stop identification).
#[derive(Debug, Clone, PartialEq)]
pub struct TableRow {
    /// Temperature, C.
    pub temp_c: f64,
    /// The 12 coefficients.
    pub coeffs: [f64; 12],
    /// Their standard errors, when known (weights of the fit).
    pub stderr: Option<[f64; 12]>,
}

/// Read a coefficient table in the format of paper-tables.csv.
pub fn read_table(path: &Path) -> Result<Vec<TableRow>> {
    let text = std::fs::read_to_string(path).map_err(|e| HostError::io(path, &e))?;
    let mut cols: Option<Vec<usize>> = None;
    let mut rows = Vec::new();
    let want: Vec<&str> = std::iter::once("temp_c").chain(COEFF_NAMES).collect();
    for (line_no, line) in fields::data_lines(&text) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        match &cols {
            None => {
                let idx = fields::header_columns(path, line_no, line, &want)?;
                cols = Some(idx);
            }
            Some(idx) => {
                let mut v = [0.0; 13];
                for (slot, (k, name)) in v.iter_mut().zip(idx.iter().zip(&want)) {
                    let s = f.get(*k).copied().unwrap_or("");
                    *slot = if *name == "temp_c" {
                        fields::temperature(path, line_no, name, s)?
                    } else {
                        fields::number(path, line_no, name, s)?
                    };
                }
                rows.push(TableRow {
                    temp_c: v[0],
                    coeffs: std::array::from_fn(|c| v[c + 1]),
                    stderr: None,
                });
            }
        }
    }
    if rows.is_empty() {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            path,
            "no coefficient rows",
        ));
    }
    rows.sort_by(|a, b| a.temp_c.total_cmp(&b.temp_c));
    Ok(rows)
}

/// The table as CSV text (temperatures to 0.001 C, coefficients to 1e-10).
pub fn to_csv(rows: &[TableRow]) -> Result<String> {
    let header: Vec<&str> = std::iter::once("temp_c").chain(COEFF_NAMES).collect();
    crate::output::csv(
        &header,
        rows.iter().map(|r| {
            std::iter::once(format!("{:.3}", r.temp_c))
                .chain(r.coeffs.iter().map(|c| format!("{c:.10}")))
                .collect::<Vec<_>>()
        }),
    )
}
