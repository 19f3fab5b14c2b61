//! A chamber and tilter program (`simulate --plan PLAN.csv`, written by `host-fit plan`):
//! rows of `time_s,setpoint_c,position`, documented in docs/chamber-program.md. The set
//! point runs linearly from each row's value to the next row's; the tilter holds the
//! row's position until the next row (`-`: it moves from the last named position to the
//! next one); the last row ends the program. The unit starts soaked at the first set
//! point.
use crate::error::{ErrorKind, HostError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One row of a program.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Step {
    /// When the row starts, s from the start.
    pub time_s: f64,
    /// The chamber's set point at that time, C.
    pub setpoint_c: f64,
    /// The tilter's position from then on (`-`: moving to the next named one).
    pub position: String,
}

/// The header a program starts with.
pub const HEADER: [&str; 3] = ["time_s", "setpoint_c", "position"];

/// Parse a program; every error names the file, the line and the field.
pub fn parse_program(path: &Path, text: &str) -> Result<Vec<Step>> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let head = r
        .headers()
        .map_err(|e| {
            HostError::in_file(
                ErrorKind::Malformed,
                path,
                format!("cannot read the header: {e}"),
            )
        })?
        .clone();
    if head.iter().collect::<Vec<_>>() != HEADER {
        return Err(HostError::at(
            ErrorKind::Malformed,
            path,
            1,
            format!(
                "the header must be `{}` (found `{}`)",
                HEADER.join(","),
                head.iter().collect::<Vec<_>>().join(",")
            ),
        ));
    }
    let mut out: Vec<Step> = Vec::new();
    for rec in r.records() {
        let rec =
            rec.map_err(|e| HostError::in_file(ErrorKind::Malformed, path, format!("{e}")))?;
        let line = rec.position().map(|p| p.line() as usize).unwrap_or(0);
        let num = |i: usize| -> Result<f64> {
            let f = rec.get(i).unwrap_or("");
            f.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    HostError::at(
                        ErrorKind::Malformed,
                        path,
                        line,
                        format!("{}: `{f}` is not a finite number", HEADER[i]),
                    )
                })
        };
        let (t, sp) = (num(0)?, num(1)?);
        let position = rec.get(2).unwrap_or("").to_string();
        if position.is_empty() {
            return Err(HostError::at(
                ErrorKind::Malformed,
                path,
                line,
                "position: empty (a name, or `-` while moving)",
            ));
        }
        match out.last() {
            None if t < 0.0 => {
                return Err(HostError::at(
                    ErrorKind::Malformed,
                    path,
                    line,
                    "time_s: the first row must be at t >= 0",
                ))
            }
            Some(p) if t <= p.time_s => {
                return Err(HostError::at(
                    ErrorKind::Malformed,
                    path,
                    line,
                    format!(
                        "time_s: {t} does not follow {} (rows in increasing time)",
                        p.time_s
                    ),
                ))
            }
            _ => {}
        }
        out.push(Step {
            time_s: t,
            setpoint_c: sp,
            position,
        });
    }
    if out.len() < 2 {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            path,
            "a program needs at least two rows (the last one ends it)",
        ));
    }
    Ok(out)
}

/// A program as CSV text (the header, then one row per step).
pub fn to_csv(steps: &[Step]) -> String {
    let mut s = format!("{}\n", HEADER.join(","));
    for st in steps {
        s.push_str(&format!(
            "{},{},{}\n",
            st.time_s, st.setpoint_c, st.position
        ));
    }
    s
}

/// The set point at `t` on a profile of `(time_s, setpoint_c)` knots in time order: linear
/// between knots, a step where two share a time, the last knot's value after the end
/// (0 for no knots). The sweep of the twin and `plan`'s sweeps share it, so a planned
/// sweep is the one the twin runs.
pub fn set_point_at(knots: &[(f64, f64)], t: f64) -> f64 {
    knots
        .windows(2)
        .find(|w| t <= w[1].0)
        .map(|w| {
            let span = w[1].0 - w[0].0;
            if span > 0.0 {
                w[0].1 + (w[1].1 - w[0].1) * (t - w[0].0) / span
            } else {
                w[1].1
            }
        })
        .unwrap_or_else(|| knots.last().map_or(0.0, |k| k.1))
}

#[cfg(test)]
mod tests {
    use super::set_point_at;

    #[test]
    fn the_set_point_runs_linearly_steps_at_shared_times_and_holds_after_the_end() {
        let knots = [(0.0, -40.0), (600.0, 20.0), (900.0, 20.0), (900.0, 70.0)];
        assert_eq!(set_point_at(&knots, 0.0), -40.0);
        assert!((set_point_at(&knots, 150.0) - -25.0).abs() < 1e-12);
        assert_eq!(set_point_at(&knots, 700.0), 20.0);
        // two knots at one time: the later value from that time on
        assert_eq!(set_point_at(&knots, 900.0), 20.0);
        assert_eq!(set_point_at(&knots, 901.0), 70.0);
        assert_eq!(set_point_at(&knots, 1e6), 70.0);
        assert_eq!(set_point_at(&[], 5.0), 0.0);
    }
}
