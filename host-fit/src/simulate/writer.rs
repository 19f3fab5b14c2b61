//! The recording as text (recording-format v1): metadata, then rows through a CSV writer.
use crate::data::output_unit::OutputUnit;
use crate::error::{ErrorKind, HostError, Result};
use crate::simulate::config::SimConfig;

/// The simulated recording as text, with the positions used.
pub struct Simulation {
    /// The recording (recording-format v1).
    pub csv: String,
    /// Number of sample rows.
    pub rows: usize,
    /// The positions file the recording needs (a flight's attitudes, all of role
    /// verification); None when the built-in and configured positions suffice.
    pub positions_csv: Option<String>,
}

/// The recording's metadata lines, then its rows through a CSV writer; with
/// `dwell_means`, one row per tilter dwell (its mean) and nothing else.
pub(super) struct RecordingWriter {
    head: String,
    /// Decimals of `t_s` (more for jittered or fast clocks).
    decimals: usize,
    csv: csv::Writer<Vec<u8>>,
    rows: usize,
    dwell_means: bool,
    /// The open dwell: its name, and the sums of t, temperature, air and outputs.
    acc: Option<(String, usize, [f64; 6])>,
    /// Written output units per volt, and the step of the written values (0: none).
    per_v: f64,
    step: f64,
    /// The outputs are counts: written as integers (unless averaged over a dwell).
    counts: bool,
}

impl RecordingWriter {
    /// `power_offs` (`[start, duration]`) are written as `power_off_s` when the logger
    /// says so; `fine`: `t_s` with 6 decimals (jitter, or a clock faster than 100 Hz).
    pub(super) fn new(cfg: &SimConfig, power_offs: &[[f64; 2]], fine: bool) -> Result<Self> {
        let mut head = format!(
            "# format=at-recording/1\n# unit={}\n# t0_c={}\n# g_local=9.80665\n# simulated by host-fit simulate, seed {}\n",
            cfg.unit.serial, cfg.t0_c, cfg.seed
        );
        let (per_v, step) = cfg.output.scale_and_step()?;
        // V is the format's default: a twin recording in volts stays as it always was
        if cfg.output.unit != OutputUnit::Volt {
            head.push_str(&format!("# output_unit={}\n", cfg.output.unit));
        }
        if cfg.logger.power_off_metadata && !power_offs.is_empty() {
            let spans: Vec<String> = power_offs
                .iter()
                .map(|[s, d]| format!("{s}-{}", s + d))
                .collect();
            head.push_str(&format!("# power_off_s={}\n", spans.join(",")));
        }
        let mut csv = csv::Writer::from_writer(Vec::new());
        csv.write_record([
            "t_s",
            "position",
            "temp_c",
            "chamber_c",
            "ux_v",
            "uy_v",
            "uz_v",
        ])
        .map_err(Self::err)?;
        Ok(RecordingWriter {
            head,
            decimals: if fine { 6 } else { 2 },
            csv,
            rows: 0,
            dwell_means: cfg.schedule.dwell_means,
            acc: None,
            per_v,
            step,
            counts: cfg.output.unit == OutputUnit::Counts,
        })
    }

    fn err(e: csv::Error) -> HostError {
        HostError::new(
            ErrorKind::Internal,
            format!("cannot write the recording: {e}"),
        )
    }

    fn write(&mut self, t: f64, name: &str, ts: f64, air: f64, u: [f64; 3]) -> Result<()> {
        self.rows += 1;
        // counts as read are integers; a dwell's mean of them is not
        let out = |v: f64| {
            if self.counts && !self.dwell_means {
                // + 0.0: a rounded -0.4 is the count 0, not "-0"
                format!("{:.0}", v.round() + 0.0)
            } else {
                format!("{v:.8}")
            }
        };
        self.csv
            .write_record([
                format!("{t:.*}", self.decimals),
                name.to_string(),
                format!("{ts:.4}"),
                format!("{air:.3}"),
                out(u[0]),
                out(u[1]),
                out(u[2]),
            ])
            .map_err(Self::err)
    }

    /// The outputs in the written unit: scaled, and rounded to its step.
    fn convert(&self, u: [f64; 3]) -> [f64; 3] {
        u.map(|v| {
            let w = v * self.per_v;
            if self.step > 0.0 {
                (w / self.step).round() * self.step
            } else {
                w
            }
        })
    }

    /// Write the open dwell's mean.
    fn flush(&mut self) -> Result<()> {
        if let Some((name, n, s)) = self.acc.take() {
            let m = s.map(|v| v / n as f64);
            self.write(m[0], &name, m[1], m[2], [m[3], m[4], m[5]])?;
        }
        Ok(())
    }

    pub(super) fn row(
        &mut self,
        t: f64,
        name: &str,
        ts: f64,
        air: f64,
        u: [f64; 3],
        measuring: bool,
    ) -> Result<()> {
        let u = self.convert(u);
        if !self.dwell_means {
            return self.write(t, name, ts, air, u);
        }
        let same = self.acc.as_ref().is_some_and(|(n, _, _)| n == name) && measuring;
        if !same {
            self.flush()?;
        }
        if measuring {
            let (_, n, s) = self
                .acc
                .get_or_insert_with(|| (name.to_string(), 0, [0.0; 6]));
            *n += 1;
            for (a, v) in s.iter_mut().zip([t, ts, air, u[0], u[1], u[2]]) {
                *a += v;
            }
        }
        Ok(())
    }

    pub(super) fn finish(mut self) -> Result<Simulation> {
        self.flush()?;
        let body = self.csv.into_inner().map_err(|e| {
            HostError::new(
                ErrorKind::Internal,
                format!("cannot write the recording: {e}"),
            )
        })?;
        let body = String::from_utf8(body)
            .map_err(|e| HostError::new(ErrorKind::Internal, e.to_string()))?;
        Ok(Simulation {
            csv: self.head + &body,
            rows: self.rows,
            positions_csv: None,
        })
    }
}
