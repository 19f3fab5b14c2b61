//! The `host-fit` command line: every command prints text, or JSON with `--json`.
use crate::calib::{build_blob, F32_BOUND_G};
use crate::error::{HostError, Result};
use crate::identify::{identify_stop, noise, observations, stops, StopCoeffs};
use crate::io::{check_writable, write_atomic};
use crate::positions::Positions;
use crate::recording::Recording;
use crate::temperature::{self, fit_joint, fit_table, report_json, Basis, ModelFit, TableRow};
use crate::verify::verify;
use clap::{Parser, Subcommand, ValueEnum};
use firmware_core::blob::Blob;
use firmware_core::compensate::{ErrorModel, Method};
use firmware_core::model::COEFF_NAMES;
use firmware_core::temperature::TempModel;
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Calibration and temperature compensation of a triaxial accelerometer: the bench tool.
#[derive(Parser, Debug)]
#[command(name = "host-fit", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Temperature model kind.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelKind {
    /// Piecewise-linear through breakpoints.
    Pwl,
    /// Polynomial of dT.
    Poly,
}

/// Identification route.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// All dwells at once, each (window) at its own temperature.
    Joint,
    /// The paper's route: formula (10) per stop, then a fit across stops.
    PerStop,
}

/// Method-2 error model.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrModel {
    /// Formulas (6)/(7).
    Full,
    /// Formula (8).
    Simplified,
}

#[derive(clap::Args, Debug, Clone)]
struct ModelArgs {
    /// Temperature model.
    #[arg(long, value_enum, default_value = "pwl")]
    model: ModelKind,
    /// Polynomial order (default: 3, or less if fewer temperatures).
    #[arg(long)]
    order: Option<usize>,
    /// Breakpoints for pwl, C, comma-separated (default: the calibration temperatures).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    breakpoints: Option<Vec<f64>>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Fit temperature models to a coefficient table (format of paper-tables.csv).
    TempFit {
        /// The table: temp_c,kxx,kyy,kzz,kxy,kxz,kyx,kyz,kzx,kzy,u0x,u0y,u0z.
        coeffs: PathBuf,
        #[command(flatten)]
        model: ModelArgs,
        /// Reference temperature T0, C.
        #[arg(long, default_value_t = 20.0, allow_hyphen_values = true)]
        t0: f64,
        /// Report scale and cross terms as the paper's relative beta/gamma.
        #[arg(long)]
        relative: bool,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Identify the 12 coefficients at every calibration stop (the paper's formula (10)).
    Identify {
        /// The recording.
        recording: PathBuf,
        /// Positions file (name,fx,fy,fz).
        #[arg(long)]
        positions: Option<PathBuf>,
        /// Write the per-stop table in the format of paper-tables.csv.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Overwrite an existing output.
        #[arg(long)]
        force: bool,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Fit a recording and write the coefficient blob.
    Fit {
        /// The recording.
        recording: PathBuf,
        /// Positions file (name,fx,fy,fz).
        #[arg(long)]
        positions: Option<PathBuf>,
        #[command(flatten)]
        model: ModelArgs,
        /// Identification route.
        #[arg(long, value_enum, default_value = "joint")]
        route: Route,
        /// Positions kept out of the fit for verification (default PP1..PP6).
        #[arg(long, value_delimiter = ',', default_value = "PP1,PP2,PP3,PP4,PP5,PP6")]
        positions_for_check: Vec<String>,
        /// Recompute the firmware's cached matrices after this temperature change, C.
        #[arg(long, default_value_t = 0.1)]
        update_step: f64,
        /// Clamp the temperature to the valid range instead of extrapolating.
        #[arg(long)]
        clamp: bool,
        /// The blob to write.
        #[arg(long)]
        out: PathBuf,
        /// Overwrite an existing output.
        #[arg(long)]
        force: bool,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Formula (13) in the verification dwells, uncompensated and compensated.
    Verify {
        /// The recording.
        recording: PathBuf,
        /// Positions file (name,fx,fy,fz).
        #[arg(long)]
        positions: Option<PathBuf>,
        /// The coefficient blob.
        #[arg(long)]
        blob: PathBuf,
        /// 1: correct the constants; 2: correct the result.
        #[arg(long, value_parser = ["1", "2"], default_value = "1")]
        method: String,
        /// Error model of method 2.
        #[arg(long, value_enum, default_value = "full")]
        error_model: ErrModel,
        /// Positions to check.
        #[arg(long, value_delimiter = ',', default_value = "PP1,PP2,PP3,PP4,PP5,PP6")]
        positions_for_check: Vec<String>,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// The engineer's HTML report of a recording: the paper's and richer models,
    /// compensated through firmware-core, dg per verification position, the coefficients
    /// against temperature, residuals against time.
    Report {
        /// The recording.
        recording: PathBuf,
        /// Positions file (name,fx,fy,fz).
        #[arg(long)]
        positions: Option<PathBuf>,
        /// The HTML file to write.
        #[arg(long)]
        out: PathBuf,
        /// Overwrite an existing file.
        #[arg(long)]
        force: bool,
    },
    /// Locate where the model and a recording disagree, name the physics left out,
    /// model it and show the fit improve (JSON contract at-diagnosis/1).
    Diagnose {
        /// The recording.
        recording: PathBuf,
        /// Positions file (name,fx,fy,fz).
        #[arg(long)]
        positions: Option<PathBuf>,
        /// Write an HTML report with residual plots before and after.
        #[arg(long)]
        report: Option<PathBuf>,
        /// Write the extended model (tables and in-flight physics terms) as a blob.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Overwrite existing outputs.
        #[arg(long)]
        force: bool,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Fit (and optionally diagnose) every recording in a folder, in parallel.
    Batch {
        /// Folder of recordings (*.csv).
        dir: PathBuf,
        /// Output folder: one blob and one JSON per unit, and summary.csv.
        #[arg(long)]
        out: PathBuf,
        /// Parallel jobs (default: one per core).
        #[arg(long)]
        jobs: Option<usize>,
        /// Temperature model.
        #[arg(long, value_enum, default_value = "pwl")]
        model: ModelKind,
        /// Also run the diagnosis on every unit.
        #[arg(long)]
        diagnose: bool,
        /// Overwrite outputs of an earlier run.
        #[arg(long)]
        force: bool,
    },
    /// Blind tests of the diagnosis on simulated recordings with concealed effects.
    Blind {
        /// The long suite (more seeds, magnitudes down to the edge of detectability).
        #[arg(long)]
        long: bool,
    },
    /// Simulate a unit's production temperature test (the digital twin).
    Simulate {
        /// TOML configuration (default: the built-in paper unit and profile).
        config: Option<PathBuf>,
        /// The recording to write.
        #[arg(long)]
        out: PathBuf,
        /// Random seed (overrides the configuration's).
        #[arg(long)]
        seed: Option<u64>,
        /// Also write the truth (all parameters) as JSON here.
        #[arg(long)]
        truth: Option<PathBuf>,
        /// Overwrite existing outputs.
        #[arg(long)]
        force: bool,
    },
    /// The main job: simulate the paper's experiment, fit, compensate, summarise, report.
    Demo {
        /// Output folder.
        #[arg(long, default_value = "demo-out")]
        out: PathBuf,
        /// Random seed of the simulation.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Overwrite the outputs of an earlier run.
        #[arg(long)]
        force: bool,
    },
    /// Firmware test vectors: write an input table, or print the expected f32 results
    /// (as bits) of the firmware-core code on it (used by `cargo xtask embedded`).
    FwVectors {
        /// The blob.
        #[arg(long)]
        blob: PathBuf,
        /// Write a new input table here (else read --inputs).
        #[arg(long)]
        make_inputs: Option<PathBuf>,
        /// The input table to evaluate.
        #[arg(long)]
        inputs: Option<PathBuf>,
        /// Random samples in a new table (edge cases are appended).
        #[arg(long, default_value_t = 64)]
        n: usize,
        /// Seed of a new table.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Prefix of the method tags in the output (the harness prints `p` for the
        /// blob with physics terms).
        #[arg(long, default_value = "")]
        tag_prefix: String,
        /// Overwrite an existing table.
        #[arg(long)]
        force: bool,
    },
    /// Decode a blob and print it, or say why it is invalid.
    Inspect {
        /// The blob.
        blob: PathBuf,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
}

/// Run the tool with `args` (including the program name); returns the exit code.
pub fn run<I, T>(args: I, out: &mut dyn Write, err: &mut dyn Write) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) => {
            let code = e.exit_code();
            let _ = if code == 0 {
                write!(out, "{}", e.render())
            } else {
                write!(err, "{}", e.render())
            };
            return code;
        }
    };
    match dispatch(cli.command, out, err) {
        Ok(()) => 0,
        Err(e) => {
            let _ = writeln!(err, "error: {e}");
            1
        }
    }
}

fn w(out: &mut dyn Write, s: impl std::fmt::Display) -> Result<()> {
    writeln!(out, "{s}").map_err(|e| HostError::msg(format!("cannot write output: {e}")))
}

fn load(recording: &Path, positions: Option<&Path>, err: &mut dyn Write) -> Result<Recording> {
    let (pos, mut warns) = match positions {
        Some(p) => Positions::with_file(p)?,
        None => (Positions::default(), Vec::new()),
    };
    let rec = Recording::read(recording, pos)?;
    warns.extend(rec.warnings.iter().cloned());
    for wn in &warns {
        let _ = writeln!(err, "warning: {wn}");
    }
    Ok(rec)
}

fn selector(rec: &Recording, names: &[String]) -> Result<Vec<bool>> {
    let mut v = vec![false; rec.positions.list.len()];
    for n in names {
        match rec.positions.index(n) {
            Some(i) => v[i] = true,
            None => {
                return Err(HostError::msg(format!(
                    "unknown position `{n}` in --positions-for-check (not built in and not in a positions file)"
                )))
            }
        }
    }
    Ok(v)
}

/// Per-stop identification of the fit positions.
pub fn identify_stops(rec: &Recording, fit_sel: &dyn Fn(usize) -> bool) -> Result<Vec<StopCoeffs>> {
    let nz = noise(rec);
    let st = stops(rec, fit_sel, 3.0);
    if st.is_empty() {
        return Err(HostError::in_file(
            &rec.path,
            "no static calibration dwells (temperature steady within 0.5 C) in the fit positions",
        ));
    }
    st.iter().map(|s| identify_stop(rec, s, &nz)).collect()
}

/// What `fit` decided and measured.
pub struct FitOutcome {
    /// The fitted model.
    pub fit: ModelFit,
    /// Per-stop identification (for the report and the paper comparison).
    pub stops: Vec<StopCoeffs>,
}

/// Fit a recording: the joint route by default, the per-stop route on request.
pub fn fit_recording(
    rec: &Recording,
    fit_sel: &dyn Fn(usize) -> bool,
    kind: ModelKind,
    order: Option<usize>,
    breakpoints: Option<Vec<f64>>,
    route: Route,
) -> Result<FitOutcome> {
    let st = identify_stops(rec, fit_sel)?;
    let stop_temps: Vec<f64> = st.iter().map(|s| s.temp_c).collect();
    let basis = match kind {
        ModelKind::Poly => Basis::Poly {
            order: order.unwrap_or_else(|| 3.min(stop_temps.len().saturating_sub(1)).max(1)),
        },
        ModelKind::Pwl => Basis::Pwl {
            breakpoints: match breakpoints {
                Some(b) => b,
                None => {
                    let mut b: Vec<f64> = temperature::temperature_clusters(&stop_temps)
                        .iter()
                        .map(|t| (t * 100.0).round() / 100.0)
                        .collect();
                    b.dedup();
                    b
                }
            },
        },
    };
    let fit = match route {
        Route::Joint => {
            let obs = observations(rec, fit_sel, 0.25);
            fit_joint(&obs, &noise(rec), &basis, rec.t0_c, &rec.path)?
        }
        Route::PerStop => {
            let rows: Vec<TableRow> = st
                .iter()
                .map(|s| TableRow {
                    temp_c: s.temp_c,
                    coeffs: s.coeffs,
                    stderr: Some(s.stderr),
                })
                .collect();
            fit_table(&rows, &basis, rec.t0_c)
                .map_err(|e| HostError::in_file(&rec.path, e.message))?
        }
    };
    Ok(FitOutcome { fit, stops: st })
}

fn coeff_csv(stops: &[StopCoeffs]) -> String {
    let mut s = format!("temp_c,{}\n", COEFF_NAMES.join(","));
    for st in stops {
        let v: Vec<String> = st.coeffs.iter().map(|c| format!("{c:.10}")).collect();
        s.push_str(&format!("{:.3},{}\n", st.temp_c, v.join(",")));
    }
    s
}

fn dispatch(cmd: Command, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    match cmd {
        Command::TempFit {
            coeffs,
            model,
            t0,
            relative,
            json,
        } => {
            let rows = temperature::read_table(&coeffs)?;
            let basis = match model.model {
                ModelKind::Poly => Basis::Poly {
                    order: model
                        .order
                        .unwrap_or_else(|| 3.min(rows.len().saturating_sub(1)).max(1)),
                },
                ModelKind::Pwl => Basis::Pwl {
                    breakpoints: model
                        .breakpoints
                        .unwrap_or_else(|| rows.iter().map(|r| r.temp_c).collect()),
                },
            };
            let fit =
                fit_table(&rows, &basis, t0).map_err(|e| HostError::in_file(&coeffs, e.message))?;
            let rep = report_json(&fit, relative);
            if json {
                w(out, serde_json::to_string_pretty(&rep).unwrap_or_default())
            } else {
                print_temp_fit(out, &fit, &rep)
            }
        }
        Command::Identify {
            recording,
            positions,
            csv,
            force,
            json,
        } => {
            if let Some(c) = &csv {
                check_writable(c, force)?;
            }
            let rec = load(&recording, positions.as_deref(), err)?;
            let nz = noise(&rec);
            let tp: Vec<bool> = (0..rec.positions.list.len())
                .map(|i| !rec.positions.name(i).starts_with("PP"))
                .collect();
            let st = identify_stops(&rec, &|p| tp.get(p).copied().unwrap_or(false))?;
            if let Some(c) = &csv {
                write_atomic(c, coeff_csv(&st).as_bytes(), force)?;
            }
            if json {
                let stops: Vec<_> = st.iter().map(|s| {
                    let c: serde_json::Map<_, _> = COEFF_NAMES.iter().zip(s.coeffs).map(|(n, v)| (n.to_string(), json!(v))).collect();
                    let e: serde_json::Map<_, _> = COEFF_NAMES.iter().zip(s.stderr).map(|(n, v)| (n.to_string(), json!(v))).collect();
                    json!({"temp_c": s.temp_c, "positions": s.positions, "coefficients": c, "stderr": e, "k2": s.k2})
                }).collect();
                w(
                    out,
                    serde_json::to_string_pretty(
                        &json!({"unit": rec.unit, "noise_sigma": nz.sigma, "stops": stops}),
                    )
                    .unwrap_or_default(),
                )
            } else {
                w(
                    out,
                    format!(
                        "unit {}  noise sigma (per sample) x {:.3e} y {:.3e} z {:.3e} {}",
                        rec.unit, nz.sigma[0], nz.sigma[1], nz.sigma[2], rec.output_unit
                    ),
                )?;
                w(out, coeff_csv(&st).trim_end())
            }
        }
        Command::Fit {
            recording,
            positions,
            model,
            route,
            positions_for_check,
            update_step,
            clamp,
            out: out_path,
            force,
            json,
        } => {
            check_writable(&out_path, force)?;
            let rec = load(&recording, positions.as_deref(), err)?;
            let check = selector(&rec, &positions_for_check)?;
            let fit_sel = |p: usize| !check.get(p).copied().unwrap_or(false);
            let oc = fit_recording(
                &rec,
                &fit_sel,
                model.model,
                model.order,
                model.breakpoints,
                route,
            )?;
            let cal = oc.fit.calibration(update_step, clamp);
            let serial = if rec.unit.is_empty() {
                "UNKNOWN"
            } else {
                rec.unit.as_str()
            };
            let (blob, bytes, dep) = build_blob(serial, &cal)?;
            write_atomic(&out_path, &bytes, force)?;
            let nz = noise(&rec);
            if json {
                let j = json!({
                    "unit": serial, "route": format!("{route:?}").to_lowercase(), "model": oc.fit.basis.describe(),
                    "t0_c": cal.t0_c, "t_min_c": cal.t_min_c, "t_max_c": cal.t_max_c,
                    "noise_sigma": nz.sigma, "k2": oc.fit.k2,
                    "stops": oc.stops.iter().map(|s| json!({"temp_c": s.temp_c, "positions": s.positions})).collect::<Vec<_>>(),
                    "f32_departure_g": dep, "f32_bound_g": F32_BOUND_G,
                    "blob": out_path.display().to_string(), "blob_bytes": bytes.len(),
                    "temperature_model": report_json(&oc.fit, false),
                    "warnings": rec.warnings,
                });
                w(out, serde_json::to_string_pretty(&j).unwrap_or_default())
            } else {
                w(
                    out,
                    format!(
                        "unit {}: {} route, model {}, T0 {} C, valid {:.2}..{:.2} C",
                        serial,
                        format!("{route:?}").to_lowercase(),
                        oc.fit.basis.describe(),
                        cal.t0_c,
                        cal.t_min_c,
                        cal.t_max_c
                    ),
                )?;
                w(
                    out,
                    format!(
                        "stops: {}",
                        oc.stops
                            .iter()
                            .map(|s| format!("{:.2} C ({} positions)", s.temp_c, s.positions.len()))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )?;
                w(out, format!("f32 firmware path vs f64 model: max {dep:.2e} g (bound {F32_BOUND_G:.0e} g)"))?;
                w(
                    out,
                    format!(
                        "wrote {} ({} bytes, serial {})",
                        out_path.display(),
                        bytes.len(),
                        blob.serial
                    ),
                )
            }
        }
        Command::Verify {
            recording,
            positions,
            blob,
            method,
            error_model,
            positions_for_check,
            json,
        } => {
            let bytes = std::fs::read(&blob).map_err(|e| HostError::io(&blob, &e))?;
            let b = Blob::decode(&bytes)
                .map_err(|e| HostError::in_file(&blob, format!("invalid blob: {e}")))?;
            let rec = load(&recording, positions.as_deref(), err)?;
            let sel = selector(&rec, &positions_for_check)?;
            let m = match (method.as_str(), error_model) {
                ("1", _) => Method::CorrectConstants,
                (_, ErrModel::Full) => Method::CorrectResult(ErrorModel::Full),
                (_, ErrModel::Simplified) => Method::CorrectResult(ErrorModel::Simplified),
            };
            let v = verify(&rec, &b, m, &|p| sel.get(p).copied().unwrap_or(false))
                .ok_or_else(|| HostError::in_file(&blob, "K(T0) of the blob is singular"))?;
            if v.dwells.is_empty() {
                return Err(HostError::in_file(
                    &recording,
                    format!(
                        "no dwells in the verification positions ({})",
                        positions_for_check.join(",")
                    ),
                ));
            }
            if json {
                w(out, serde_json::to_string_pretty(&json!({"unit": b.serial.as_str(), "method": method, "dwells": v.dwells, "max_by_temperature": v.max_by_temperature})).unwrap_or_default())
            } else {
                w(
                    out,
                    format!(
                        "{:<8} {:>8} {:>16} {:>12}",
                        "position", "temp_c", "dg_uncomp_mg", "dg_mg"
                    ),
                )?;
                for d in &v.dwells {
                    w(
                        out,
                        format!(
                            "{:<8} {:>8.2} {:>16.4} {:>12.4}",
                            d.position, d.temp_c, d.dg_mg_uncompensated, d.dg_mg
                        ),
                    )?;
                }
                for t in &v.max_by_temperature {
                    w(
                        out,
                        format!(
                            "max |dg| at {:>7.2} C: uncompensated {:.4} mg, method {} {:.4} mg",
                            t.temp_c, t.max_abs_dg_mg_uncompensated, method, t.max_abs_dg_mg
                        ),
                    )?;
                }
                Ok(())
            }
        }
        Command::Batch {
            dir,
            out: out_dir,
            jobs,
            model,
            diagnose,
            force,
        } => {
            let t = std::time::Instant::now();
            let res = crate::batch::run(&dir, &out_dir, jobs, model, diagnose, force)?;
            let bad = res.iter().filter(|r| r.status != "ok").count();
            for r in res.iter().filter(|r| r.status != "ok") {
                let _ = writeln!(err, "{}: {}", r.file.display(), r.status);
            }
            w(
                out,
                format!(
                    "{} units in {:.1} s: {} ok, {} failed; summary {}",
                    res.len(),
                    t.elapsed().as_secs_f64(),
                    res.len() - bad,
                    bad,
                    out_dir.join("summary.csv").display()
                ),
            )
        }
        Command::Report {
            recording,
            positions,
            out: html_out,
            force,
        } => {
            check_writable(&html_out, force)?;
            let rec = load(&recording, positions.as_deref(), err)?;
            let oc = crate::demo::analyse(rec, None, None)?;
            let table = crate::demo::table(&oc.rows);
            let html = crate::report::demo_report(&oc, &table)?;
            write_atomic(&html_out, html.as_bytes(), force)?;
            w(out, table)?;
            w(out, format!("report: {}", html_out.display()))
        }
        Command::Blind { long } => {
            let cases = crate::blind::suite(long);
            let outcomes: Vec<_> = cases.iter().map(crate::blind::run).collect();
            w(out, crate::blind::report(&outcomes))
        }
        Command::Diagnose {
            recording,
            positions,
            report,
            out: blob_out,
            force,
            json,
        } => {
            for p in report.iter().chain(blob_out.iter()) {
                check_writable(p, force)?;
            }
            let rec = load(&recording, positions.as_deref(), err)?;
            let d = crate::diagnose::diagnose(&rec)?;
            let mut j = d.json(&rec);
            if let Some(b) = &blob_out {
                let cal = d.calibration(rec.t0_c);
                let serial = if rec.unit.is_empty() {
                    "UNKNOWN"
                } else {
                    rec.unit.as_str()
                };
                let (blob, bytes, dep) = build_blob(serial, &cal)?;
                write_atomic(b, &bytes, force)?;
                j["blob"] = json!({"path": b.display().to_string(), "bytes": bytes.len(), "physics": blob.calibration.physics.is_some(), "f32_departure_g": dep});
            }
            if let Some(r) = &report {
                let html = crate::report::diagnosis_report(&rec, &d)?;
                write_atomic(r, html.as_bytes(), force)?;
            }
            if json {
                w(out, serde_json::to_string_pretty(&j).unwrap_or_default())
            } else {
                w(out, crate::diagnose::text(&j))
            }
        }
        Command::Simulate {
            config,
            out: out_path,
            seed,
            truth,
            force,
        } => {
            check_writable(&out_path, force)?;
            if let Some(t) = &truth {
                check_writable(t, force)?;
            }
            let mut cfg = match &config {
                Some(p) => {
                    let text = std::fs::read_to_string(p).map_err(|e| HostError::io(p, &e))?;
                    crate::simulate::parse_config(p, &text)?
                }
                None => crate::simulate::SimConfig::default(),
            };
            if let Some(s) = seed {
                cfg.seed = s;
            }
            let sim = crate::simulate::simulate(&cfg, |_| {})?;
            write_atomic(&out_path, sim.csv.as_bytes(), force)?;
            if let Some(t) = &truth {
                let j = serde_json::to_string_pretty(&json!({"config": cfg})).unwrap_or_default();
                write_atomic(t, j.as_bytes(), force)?;
            }
            w(
                out,
                format!(
                    "wrote {} ({} rows, seed {})",
                    out_path.display(),
                    sim.rows,
                    cfg.seed
                ),
            )
        }
        Command::Demo {
            out: dir,
            seed,
            force,
        } => {
            let oc = crate::demo::run(&dir, seed, force)?;
            w(out, crate::demo::table(&oc.rows))?;
            w(
                out,
                format!("summary: {}", dir.join("summary.json").display()),
            )?;
            w(
                out,
                format!("report:  {}", dir.join("report.html").display()),
            )
        }
        Command::FwVectors {
            blob,
            make_inputs,
            inputs,
            n,
            seed,
            tag_prefix,
            force,
        } => {
            let bytes = std::fs::read(&blob).map_err(|e| HostError::io(&blob, &e))?;
            let b = Blob::decode(&bytes)
                .map_err(|e| HostError::in_file(&blob, format!("invalid blob: {e}")))?;
            if let Some(p) = make_inputs {
                let table = crate::fwcheck::make_inputs(&b, n, seed);
                write_atomic(&p, &table, force)?;
                return w(
                    out,
                    format!("wrote {} ({} inputs)", p.display(), table.len() / 16),
                );
            }
            let p =
                inputs.ok_or_else(|| HostError::msg("give --inputs FILE or --make-inputs FILE"))?;
            let table = std::fs::read(&p).map_err(|e| HostError::io(&p, &e))?;
            if table.len() % 16 != 0 {
                return Err(HostError::in_file(
                    &p,
                    "length is not a multiple of 16 bytes (ux uy uz temp, f32)",
                ));
            }
            let (lines, worst) = crate::fwcheck::expected(&b, &table, &tag_prefix);
            for l in lines {
                w(out, l)?;
            }
            w(
                out,
                format!("f64-departure {worst:e} bound {F32_BOUND_G:e}"),
            )?;
            if !crate::fwcheck::within_bound(worst) {
                return Err(HostError::msg(format!(
                    "f32 departs from f64 by {worst:e} g, over the bound {F32_BOUND_G:e}"
                )));
            }
            Ok(())
        }
        Command::Inspect { blob, json } => {
            let bytes = std::fs::read(&blob).map_err(|e| HostError::io(&blob, &e))?;
            let b = Blob::decode(&bytes)
                .map_err(|e| HostError::in_file(&blob, format!("invalid blob: {e}")))?;
            let c = &b.calibration;
            let (kind, table) = match &c.model {
                TempModel::Poly { terms } => (
                    format!("poly{}", terms.len() - 1),
                    terms
                        .iter()
                        .enumerate()
                        .map(|(k, r)| (format!("dT^{k}"), r.to_vec()))
                        .collect::<Vec<_>>(),
                ),
                TempModel::Pwl {
                    breakpoints,
                    values,
                } => (
                    "pwl".to_string(),
                    breakpoints
                        .iter()
                        .zip(values)
                        .map(|(t, r)| (format!("{t} C"), r.to_vec()))
                        .collect(),
                ),
            };
            if json {
                w(out, serde_json::to_string_pretty(&json!({
                    "format_version": firmware_core::blob::FORMAT_VERSION, "bytes": bytes.len(), "serial": b.serial.as_str(),
                    "t0_c": c.t0_c, "t_min_c": c.t_min_c, "t_max_c": c.t_max_c, "clamp": c.clamp, "update_step_c": c.update_step_c,
                    "model": kind, "columns": COEFF_NAMES,
                    "rows": table.iter().map(|(k, r)| json!({"at": k, "values": r})).collect::<Vec<_>>(),
                })).unwrap_or_default())
            } else {
                w(
                    out,
                    format!(
                        "blob {} ({} bytes, format {}): serial {}",
                        blob.display(),
                        bytes.len(),
                        firmware_core::blob::FORMAT_VERSION,
                        b.serial
                    ),
                )?;
                w(
                    out,
                    format!(
                        "T0 {} C, valid {}..{} C, {}, update step {} C, model {kind}",
                        c.t0_c,
                        c.t_min_c,
                        c.t_max_c,
                        if c.clamp { "clamped" } else { "extrapolated" },
                        c.update_step_c
                    ),
                )?;
                w(
                    out,
                    format!(
                        "{:>10} {}",
                        "",
                        COEFF_NAMES.map(|n| format!("{n:>12}")).join("")
                    ),
                )?;
                for (k, r) in table {
                    w(
                        out,
                        format!(
                            "{k:>10} {}",
                            r.iter().map(|v| format!("{v:>12.4e}")).collect::<String>()
                        ),
                    )?;
                }
                Ok(())
            }
        }
    }
}

fn print_temp_fit(out: &mut dyn Write, fit: &ModelFit, rep: &serde_json::Value) -> Result<()> {
    w(
        out,
        format!("model {}  T0 {} C", fit.basis.describe(), fit.t0_c),
    )?;
    if let Some(iv) = rep.get("intervals").and_then(|v| v.as_array()) {
        for i in iv {
            w(out, format!("interval {} .. {} C:", i["from_c"], i["to_c"]))?;
            if let Some(m) = i["coefficients"].as_object() {
                for (k, v) in m {
                    w(
                        out,
                        format!("  {k:<10} {:>14.6e}", v.as_f64().unwrap_or(f64::NAN)),
                    )?;
                }
            }
        }
    }
    if let Some(m) = rep.get("coefficients").and_then(|v| v.as_object()) {
        for (k, v) in m {
            w(out, format!("  {k:<10} {}", v))?;
        }
    }
    Ok(())
}
