//! The recording reader, exactly per recording-format.md (version 1), and its dwells.
use crate::data::fields::{self, number as parse_num, temperature as parse_temp};
use crate::data::output_unit::OutputUnit;
use crate::data::positions::Positions;
use crate::error::{ErrorKind, HostError, Result};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// One sample row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Time, s.
    pub t_s: f64,
    /// Index into [`Positions`], `None` for `-` (moving / unknown).
    pub position: Option<usize>,
    /// Unit temperature sensor, C.
    pub temp_c: f64,
    /// Chamber air / set point, C, when the column exists.
    pub chamber_c: Option<f64>,
    /// The three outputs (V, or the recording's `output_unit`).
    pub u: [f64; 3],
    /// 1-based line number in the file.
    pub line: usize,
}

/// One row on the in-flight terms' clock ([`Recording::clock`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowClock {
    /// Seconds since the previous row (the first row: since the power-on before it).
    pub dt_s: f64,
    /// The unit was powered on again this many seconds before this row (a stated
    /// power-off ended since the previous row).
    pub power_on_s: Option<f64>,
}

/// `power_off_s`: comma-separated `start-end` spans (s), each with start <= end.
fn power_off_spans(path: &Path, line: usize, v: &str) -> Result<Vec<[f64; 2]>> {
    let mut out = Vec::new();
    for span in v.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        // a span's '-' is the one after its first character (a start may be negative)
        let cut = span
            .char_indices()
            .skip(1)
            .find(|(_, c)| *c == '-')
            .map(|(i, _)| i);
        let Some(cut) = cut else {
            return Err(HostError::at_field(
                ErrorKind::Malformed,
                path,
                line,
                "power_off_s",
                format!("`{span}` is not a span `start-end` in seconds"),
            ));
        };
        let start = parse_num(path, line, "power_off_s", span[..cut].trim())?;
        let end = parse_num(path, line, "power_off_s", span[cut + 1..].trim())?;
        if end < start {
            return Err(HostError::at_field(
                ErrorKind::Malformed,
                path,
                line,
                "power_off_s",
                format!("span `{span}` ends before it starts"),
            ));
        }
        out.push([start, end]);
    }
    Ok(out)
}

/// A maximal run of consecutive rows with the same (known) position.
#[derive(Debug, Clone, PartialEq)]
pub struct Dwell {
    /// Position index.
    pub position: usize,
    /// Row range `[start, end)` in [`Recording::rows`].
    pub start: usize,
    /// End (exclusive).
    pub end: usize,
    /// Mean temperature, C.
    pub temp_c: f64,
    /// Temperature span (max - min), C.
    pub temp_span_c: f64,
    /// Mean outputs.
    pub u_mean: [f64; 3],
}

impl Dwell {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.end.saturating_sub(self.start)
    }
    /// True when the dwell has no samples (never for a dwell built by the reader).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A parsed recording.
#[derive(Debug, Clone)]
pub struct Recording {
    /// Where it was read from.
    pub path: PathBuf,
    /// All metadata (`# key=value`), known and unknown.
    pub metadata: BTreeMap<String, String>,
    /// Unit serial (`unit`), empty if absent (see [`Recording::serial`]).
    pub unit: String,
    /// Reference temperature (`t0_c`, default 20).
    pub t0_c: f64,
    /// Output unit (`output_unit`, default `V`; any other label kept as it is).
    pub output_unit: OutputUnit,
    /// Spans `[start, end]` (s, on `t_s`) the unit was powered off (`power_off_s`): each
    /// end is a power-on, where the in-flight terms' machines start again.
    pub power_off: Vec<[f64; 2]>,
    /// The positions in use (built-in + positions file).
    pub positions: Positions,
    /// Samples in time order.
    pub rows: Vec<Row>,
    /// Dwells in time order.
    pub dwells: Vec<Dwell>,
    /// Warnings (unknown columns/metadata, short dwells, drifting dwells).
    pub warnings: Vec<String>,
    /// Notes on expected features of the data (dwells resting through ramps).
    pub notes: Vec<String>,
}

/// Dwells shorter than this are warned about.
pub const MIN_DWELL_SAMPLES: usize = 3;
/// More short (or drifting) dwells than this are summarised in one warning.
pub const MAX_NAMED_SHORT_DWELLS: usize = 3;
/// A dwell whose temperature moves more than this (C) is warned about.
pub const MAX_DWELL_DRIFT_C: f64 = 0.5;
/// A dwell whose temperature moves this much (C) rests through a ramp: expected, noted
/// once for all such dwells.
pub const RAMP_SPAN_C: f64 = 2.0;
/// A recording in which at least this share of the dwells drift more than
/// [`MAX_DWELL_DRIFT_C`] is a sweep: `fit` takes it on the dynamic route, through its
/// moving dwells, so their drift is expected (a note, not a warning).
pub const SWEEP_MOVING_SHARE: f64 = 0.5;

const KNOWN_META: [&str; 6] = [
    "unit",
    "t0_c",
    "g_local",
    "format",
    "output_unit",
    "power_off_s",
];
const REQUIRED: [&str; 6] = ["t_s", "position", "temp_c", "ux_v", "uy_v", "uz_v"];

/// The serial of a unit whose recording names none (no `# unit=`): what its blob and
/// its records carry.
pub const UNKNOWN_SERIAL: &str = "UNKNOWN";

impl Recording {
    /// The unit's serial: `unit`, or [`UNKNOWN_SERIAL`] when the recording has none.
    pub fn serial(&self) -> &str {
        if self.unit.is_empty() {
            UNKNOWN_SERIAL
        } else {
            &self.unit
        }
    }

    /// Read a recording file.
    pub fn read(path: &Path, positions: Positions) -> Result<Recording> {
        let f = std::fs::File::open(path).map_err(|e| HostError::io(path, &e))?;
        Self::from_reader(path, f, positions)
    }

    /// Read a recording from any reader (`path` is used in messages).
    pub fn from_reader(path: &Path, reader: impl Read, positions: Positions) -> Result<Recording> {
        let mut rec = Recording {
            path: path.to_path_buf(),
            metadata: BTreeMap::new(),
            unit: String::new(),
            t0_c: 20.0,
            output_unit: OutputUnit::Volt,
            power_off: Vec::new(),
            positions,
            rows: Vec::new(),
            dwells: Vec::new(),
            warnings: Vec::new(),
            notes: Vec::new(),
        };
        let mut reader = BufReader::new(reader);
        let mut buf = Vec::new();
        let mut line_no = 0usize;
        let mut cols: Option<Columns> = None;
        let mut last_t = f64::NEG_INFINITY;
        loop {
            buf.clear();
            let n = reader
                .read_until(b'\n', &mut buf)
                .map_err(|e| HostError::io(path, &e))?;
            if n == 0 {
                break;
            }
            line_no += 1;
            let mut text = std::str::from_utf8(&buf).map_err(|_| {
                HostError::at(
                    ErrorKind::Malformed,
                    path,
                    line_no,
                    "is not valid UTF-8 text",
                )
            })?;
            if line_no == 1 {
                text = text.strip_prefix('\u{feff}').unwrap_or(text);
            }
            let line = text.trim_end_matches(['\n', '\r']);
            if line.trim().is_empty() {
                continue;
            }
            if let Some(comment) = line.strip_prefix('#') {
                rec.metadata_line(comment, line_no)?;
                continue;
            }
            match &cols {
                None => {
                    cols = Some(Columns::from_header(
                        path,
                        line_no,
                        line,
                        &mut rec.warnings,
                    )?)
                }
                Some(c) => {
                    let row = c.parse_row(path, line_no, line, &rec.positions)?;
                    if row.t_s < last_t {
                        return Err(HostError::at_field(
                            ErrorKind::Malformed,
                            path,
                            line_no,
                            "t_s",
                            format!("time goes backwards ({} after {})", row.t_s, last_t),
                        ));
                    }
                    last_t = row.t_s;
                    rec.rows.push(row);
                }
            }
        }
        if cols.is_none() {
            return Err(HostError::in_file(
                ErrorKind::Malformed,
                path,
                "no header row: the file is empty or holds only comments (need t_s,position,temp_c,ux_v,uy_v,uz_v)",
            ));
        }
        if rec.rows.is_empty() {
            return Err(HostError::at(
                ErrorKind::Insufficient,
                path,
                line_no,
                "no data rows after the header",
            ));
        }
        rec.build_dwells();
        Ok(rec)
    }

    fn metadata_line(&mut self, comment: &str, line: usize) -> Result<()> {
        let Some((k, v)) = comment.split_once('=') else {
            return Ok(());
        };
        let (k, v) = (k.trim().to_string(), v.trim().to_string());
        if k.is_empty() || k.contains(' ') {
            return Ok(()); // prose that happens to contain '='
        }
        match k.as_str() {
            "format" if v != "at-recording/1" => {
                return Err(HostError::at_field(
                    ErrorKind::Unsupported,
                    &self.path,
                    line,
                    "format",
                    format!("`{v}` is not a supported format (expected at-recording/1)"),
                ))
            }
            "t0_c" => self.t0_c = parse_temp(&self.path, line, "t0_c", &v)?,
            "unit" => self.unit = v.clone(),
            "output_unit" => {
                let u = OutputUnit::parse(&v);
                if !u.is_known() {
                    self.warnings.push(format!(
                        "{}:{line}: output_unit `{v}` is not one of the format's (V, mV, m/s2, g, mg, counts): kept as the label of the outputs",
                        self.path.display()
                    ));
                }
                self.output_unit = u;
            }
            "power_off_s" => self.power_off = power_off_spans(&self.path, line, &v)?,
            _ => {}
        }
        if !KNOWN_META.contains(&k.as_str()) {
            self.warnings.push(format!(
                "{}:{line}: unknown metadata key `{k}` kept ({k}={v})",
                self.path.display()
            ));
        }
        self.metadata.insert(k, v);
        Ok(())
    }

    /// The clock the in-flight terms run on, per row: the time step before it (from the
    /// previous row; for the first row from the power-on before it, 0 when none is
    /// stated), and when a stated `power_off_s` span ended between the previous row and
    /// this one, how long before this row the unit was powered on again. The firmware's
    /// `compensate_dt` and `power_on` take exactly these, in `verify` as in the
    /// diagnosis's regressors.
    pub fn clock(&self) -> Vec<RowClock> {
        let mut ends: Vec<f64> = self.power_off.iter().map(|s| s[1]).collect();
        ends.sort_by(f64::total_cmp);
        let mut next = ends.iter().copied().peekable();
        let mut prev: Option<f64> = None;
        self.rows
            .iter()
            .map(|r| {
                let mut on = None;
                while let Some(e) = next.peek().copied() {
                    if e > r.t_s {
                        break;
                    }
                    if prev.is_none_or(|p| e > p) {
                        on = Some(e);
                    }
                    next.next();
                }
                let c = match prev {
                    Some(p) => RowClock {
                        dt_s: r.t_s - p,
                        power_on_s: on.map(|e| r.t_s - e),
                    },
                    None => RowClock {
                        dt_s: on.map_or(0.0, |e| r.t_s - e),
                        power_on_s: None,
                    },
                };
                prev = Some(r.t_s);
                c
            })
            .collect()
    }

    /// The median time between successive rows, s (1 when there are fewer than two).
    pub fn median_step_s(&self) -> f64 {
        let mut d: Vec<f64> = self
            .rows
            .windows(2)
            .map(|w| w[1].t_s - w[0].t_s)
            .filter(|d| *d > 0.0)
            .collect();
        d.sort_by(f64::total_cmp);
        d.get(d.len() / 2).copied().unwrap_or(1.0)
    }

    fn build_dwells(&mut self) {
        let mut short: Vec<String> = Vec::new();
        let mut ramps: Vec<(String, f64)> = Vec::new();
        let mut drifts: Vec<(String, String, f64)> = Vec::new();
        let mut i = 0;
        while i < self.rows.len() {
            let Some(pos) = self.rows.get(i).and_then(|r| r.position) else {
                i += 1;
                continue;
            };
            let start = i;
            while self.rows.get(i).is_some_and(|r| r.position == Some(pos)) {
                i += 1;
            }
            let slice = self.rows.get(start..i).unwrap_or(&[]);
            let n = slice.len() as f64;
            let mut u = [0.0; 3];
            let (mut lo, mut hi, mut tsum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
            for r in slice {
                for (a, b) in u.iter_mut().zip(r.u) {
                    *a += b;
                }
                lo = lo.min(r.temp_c);
                hi = hi.max(r.temp_c);
                tsum += r.temp_c;
            }
            let d = Dwell {
                position: pos,
                start,
                end: i,
                temp_c: tsum / n,
                temp_span_c: hi - lo,
                u_mean: u.map(|x| x / n),
            };
            let first = slice.first().map(|r| r.line).unwrap_or(0);
            let last = slice.last().map(|r| r.line).unwrap_or(0);
            let name = self.positions.name(pos).to_string();
            if d.len() < MIN_DWELL_SAMPLES {
                short.push(format!(
                    "{}:{first}-{last}: dwell in {name} has {} samples (< {MIN_DWELL_SAMPLES}); used anyway",
                    self.path.display(),
                    d.len()
                ));
            }
            if d.temp_span_c >= RAMP_SPAN_C {
                ramps.push((name.clone(), d.temp_span_c));
            } else if d.temp_span_c > MAX_DWELL_DRIFT_C {
                drifts.push((
                    format!(
                        "{}:{first}-{last}: temperature drifts {:.2} C within the dwell in {name} (> {MAX_DWELL_DRIFT_C} C): not in thermal equilibrium, left out of static fits",
                        self.path.display(),
                        d.temp_span_c
                    ),
                    format!("{name} at lines {first}-{last}: {:.2} C", d.temp_span_c),
                    d.temp_span_c,
                ));
            }
            self.dwells.push(d);
        }
        self.summarise_short(short);
        self.summarise_drifts(drifts);
        self.summarise_ramps(&ramps);
    }

    /// The share of the dwells that drift more than [`MAX_DWELL_DRIFT_C`] (0 without
    /// dwells).
    pub fn moving_share(&self) -> f64 {
        let moving = self
            .dwells
            .iter()
            .filter(|d| d.temp_span_c > MAX_DWELL_DRIFT_C)
            .count();
        moving as f64 / self.dwells.len().max(1) as f64
    }

    /// A few drifting dwells are named one by one; many are one warning naming the worst
    /// (each is still left out of the static fits). In a sweep ([`SWEEP_MOVING_SHARE`])
    /// they are one note: the dynamic route fits through them.
    fn summarise_drifts(&mut self, mut drifts: Vec<(String, String, f64)>) {
        if !drifts.is_empty() && self.moving_share() >= SWEEP_MOVING_SHARE {
            self.notes.push(format!(
                "{}: {} dwells drift {MAX_DWELL_DRIFT_C} to {RAMP_SPAN_C} C in temperature: \
                 expected in a sweep ({:.0}% of the dwells move), fitted through on the dynamic \
                 route (a static fit leaves them out)",
                self.path.display(),
                drifts.len(),
                100.0 * self.moving_share()
            ));
            return;
        }
        if drifts.len() <= MAX_NAMED_SHORT_DWELLS {
            self.warnings.extend(drifts.into_iter().map(|d| d.0));
            return;
        }
        drifts.sort_by(|a, b| b.2.total_cmp(&a.2));
        let worst: Vec<&str> = drifts.iter().take(3).map(|d| d.1.as_str()).collect();
        self.warnings.push(format!(
            "{}: {} dwells drift more than {MAX_DWELL_DRIFT_C} C in temperature (worst: {}): not in \
             thermal equilibrium, left out of static fits",
            self.path.display(),
            drifts.len(),
            worst.join("; ")
        ));
    }

    /// Dwells that rest through a temperature ramp are expected data (a unit resting on
    /// the tilter while the chamber moves): one note for all of them, not a warning each.
    fn summarise_ramps(&mut self, ramps: &[(String, f64)]) {
        if ramps.is_empty() {
            return;
        }
        let mut names: Vec<String> = Vec::new();
        for (n, _) in ramps {
            let count = ramps.iter().filter(|(m, _)| m == n).count();
            let label = if count > 1 {
                format!("{n} x{count}")
            } else {
                n.clone()
            };
            if !names.contains(&label) {
                names.push(label);
            }
        }
        let (lo, hi) = ramps
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), (_, s)| {
                (l.min(*s), h.max(*s))
            });
        self.notes.push(format!(
            "{}: {} dwells rest through temperature ramps ({}; {lo:.1} to {hi:.1} C each): expected; \
             used as windows at their own temperatures, and left out of static fits where the \
             temperature moves",
            self.path.display(),
            ramps.len(),
            names.join(", ")
        ));
    }

    /// A few short dwells are named one by one; many (a dwell-averaged recording, one row
    /// per position and temperature) are one warning, not one per dwell.
    fn summarise_short(&mut self, short: Vec<String>) {
        if short.len() <= MAX_NAMED_SHORT_DWELLS {
            self.warnings.extend(short);
            return;
        }
        let single = self.dwells.iter().filter(|d| d.len() == 1).count();
        self.warnings.push(format!(
            "{}: {} of {} dwells have fewer than {MIN_DWELL_SAMPLES} samples ({single} have one: \
             a dwell-averaged recording?); used anyway, and where no dwell has two samples the \
             noise is taken from the fit's residual scatter, not from successive samples",
            self.path.display(),
            short.len(),
            self.dwells.len()
        ));
    }

    /// Rows of a dwell.
    pub fn dwell_rows(&self, d: &Dwell) -> &[Row] {
        self.rows.get(d.start..d.end).unwrap_or(&[])
    }
}

struct Columns {
    n: usize,
    t: usize,
    pos: usize,
    temp: usize,
    u: [usize; 3],
    chamber: Option<usize>,
}

impl Columns {
    fn from_header(
        path: &Path,
        line: usize,
        text: &str,
        warnings: &mut Vec<String>,
    ) -> Result<Columns> {
        let idx = fields::header_columns(path, line, text, &REQUIRED)?;
        let names: Vec<String> = text
            .split(',')
            .map(|s| s.trim().to_ascii_lowercase())
            .collect();
        for (i, n) in names.iter().enumerate() {
            if names.iter().take(i).any(|m| m == n) {
                return Err(HostError::at_field(
                    ErrorKind::Malformed,
                    path,
                    line,
                    n,
                    "column appears twice in the header",
                ));
            }
        }
        let chamber = names.iter().position(|n| n == "chamber_c");
        for n in &names {
            if !REQUIRED.contains(&n.as_str()) && n != "chamber_c" {
                warnings.push(format!(
                    "{}:{line}: unknown column `{n}` ignored",
                    path.display()
                ));
            }
        }
        let g = |k: usize| idx.get(k).copied().unwrap_or(0);
        Ok(Columns {
            n: names.len(),
            t: g(0),
            pos: g(1),
            temp: g(2),
            u: [g(3), g(4), g(5)],
            chamber,
        })
    }

    fn parse_row(
        &self,
        path: &Path,
        line: usize,
        text: &str,
        positions: &Positions,
    ) -> Result<Row> {
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != self.n {
            let hint = if fields.len() > self.n {
                " (a comma used as decimal separator? use a point: 0.5, not 0,5)"
            } else {
                ""
            };
            return Err(HostError::at(
                ErrorKind::Malformed,
                path,
                line,
                format!(
                    "has {} fields, the header has {}{hint}",
                    fields.len(),
                    self.n
                ),
            ));
        }
        let get = |k: usize| fields.get(k).copied().unwrap_or("");
        let num = |k: usize, name: &str| parse_num(path, line, name, get(k));
        let temp = |k: usize, name: &str| parse_temp(path, line, name, get(k));
        let pname = get(self.pos);
        let position = if pname == "-" {
            None
        } else {
            Some(positions.index(pname).ok_or_else(|| {
                HostError::at_field(
                    ErrorKind::Malformed,
                    path,
                    line,
                    "position",
                    format!("unknown position name `{pname}` (not built in and not in a positions file)"),
                )
            })?)
        };
        Ok(Row {
            t_s: num(self.t, "t_s")?,
            position,
            temp_c: temp(self.temp, "temp_c")?,
            chamber_c: match self.chamber {
                Some(k) => Some(temp(k, "chamber_c")?),
                None => None,
            },
            u: [
                num(self.u[0], "ux_v")?,
                num(self.u[1], "uy_v")?,
                num(self.u[2], "uz_v")?,
            ],
            line,
        })
    }
}
