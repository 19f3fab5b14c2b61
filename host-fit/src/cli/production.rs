//! `batch`, `simulate` and `demo`: many units, the twin, and the main job.
use super::args::{BatchArgs, DemoArgs, PlanArgs, SimulateArgs};
use super::common::w;
use super::common::Outcome;
use crate::acceptance::Verdict;
use crate::batch::{BatchOptions, UnitStatus};
use crate::diagnose::findings::Finding;
use crate::diagnose::parameters::Quantity;
use crate::diagnose::EffectId;
use crate::error::{ErrorKind, HostError, Result};
use crate::output::{check_writable, write_atomic, write_json};
use crate::simulate::SimConfig;
use serde::{Deserialize, Serialize};
use std::io::Write;

pub(super) fn batch(a: BatchArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let t = std::time::Instant::now();
    let (positions, warns) = super::common::positions(&a.positions)?;
    for wn in &warns {
        let _ = writeln!(err, "warning: {wn}");
    }
    let o = BatchOptions {
        jobs: a.jobs,
        model: a.model.map(Into::into),
        spec: a.accept.spec()?,
        diagnose: a.diagnose,
        force: a.force,
        positions,
        store: super::records::batch_store(&a.dir, &a.out, &a.record, a.no_db)?,
        allow: a.allow.iter().map(|x| (*x).into()).collect(),
    };
    let res = crate::batch::run(&a.dir, &a.out, &o)?;
    let count = |s: UnitStatus| res.units.iter().filter(|r| r.acceptance == s).count();
    for r in res
        .units
        .iter()
        .filter(|r| r.acceptance != UnitStatus::Pass)
    {
        let _ = writeln!(err, "{}: {}: {}", r.file.display(), r.acceptance, r.reason);
    }
    w(
        out,
        format!(
            "{} units in {:.1} s: {} pass, {} fail, {} error, {} not judged ({}); summary {}",
            res.units.len(),
            t.elapsed().as_secs_f64(),
            count(UnitStatus::Pass),
            count(UnitStatus::Fail),
            count(UnitStatus::Error),
            count(UnitStatus::NotJudged),
            o.spec.text(),
            a.out.join("summary.csv").display()
        ),
    )?;
    let far: Vec<String> = res
        .units
        .iter()
        .filter(|u| !u.outlier.is_empty())
        .map(|u| {
            let (c, z) =
                u.outlier.iter().fold(
                    ("", 0.0f64),
                    |m, x| if x.1.abs() > m.1.abs() { *x } else { m },
                );
            format!(
                "{} of {} ({c} z={z:.1})",
                u.unit,
                u.file
                    .file_name()
                    .map(|f| f.to_string_lossy().into_owned())
                    .unwrap_or_default()
            )
        })
        .collect();
    w(
        out,
        format!(
            "lot: {} coefficients over {} fitted units in {}; units far from the lot (robust z > {}): {}",
            res.lot.len(),
            res.lot.first().map_or(0, |l| l.units),
            a.out.join("lot.csv").display(),
            crate::batch::OUTLIER_Z,
            if far.is_empty() { "none".to_string() } else { far.join(", ") }
        ),
    )?;
    if let (Some(t), Some(n)) = (&o.store, res.recorded) {
        if res.resumed > 0 {
            w(
                out,
                format!(
                    "resumed: {} units already recorded in {} were kept as recorded (not computed again)",
                    res.resumed, t.db
                ),
            )?;
        }
        w(
            out,
            format!(
                "records: {n} units recorded in {} (lot {}; host-fit history SERIAL --db {}, host-fit trend --db {} --out trend.html)",
                t.db,
                t.lot.as_deref().unwrap_or("-"),
                t.db,
                t.db
            ),
        )?;
    }
    Ok(match res.verdict() {
        Verdict::Pass => Outcome::Done,
        Verdict::Fail => Outcome::Rejected,
        Verdict::NotJudged => Outcome::NotJudged,
    })
}

/// `simulate --truth`.
#[derive(Serialize)]
struct Truth<'a> {
    config: &'a SimConfig,
}

pub(super) fn simulate(a: SimulateArgs, out: &mut dyn Write) -> Result<()> {
    check_writable(&a.out, a.force)?;
    if let Some(t) = &a.truth {
        check_writable(t, a.force)?;
    }
    let mut cfg = match &a.config {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| HostError::io(p, &e))?;
            crate::simulate::parse_config(p, &text)?
        }
        None => SimConfig::default(),
    };
    if let Some(s) = a.seed {
        cfg.seed = s;
    }
    if let Some(p) = &a.plan {
        let text = std::fs::read_to_string(p).map_err(|e| HostError::io(p, &e))?;
        let steps = crate::simulate::program::parse_program(p, &text)?;
        if cfg.flight.is_some() {
            return Err(HostError::new(
                ErrorKind::Invalid,
                "--plan runs a chamber program; the configuration is a [flight]",
            ));
        }
        // the unit starts soaked at the program's first set point
        cfg.chamber.start_c = steps[0].setpoint_c;
        cfg.schedule.sweep = None;
        cfg.schedule.program = steps;
    }
    if let Some(p) = &a.positions_out {
        check_writable(p, a.force)?;
    }
    if cfg.flight.is_some() && a.positions_out.is_none() {
        return Err(HostError::new(
            ErrorKind::Invalid,
            "a [flight] configuration names its attitudes in a positions file: give --positions-out FILE",
        ));
    }
    let sim = crate::simulate::simulate(&cfg, |_| {})?;
    write_atomic(&a.out, sim.csv.as_bytes(), a.force)?;
    if let (Some(p), Some(text)) = (&a.positions_out, &sim.positions_csv) {
        write_atomic(p, text.as_bytes(), a.force)?;
    }
    if let Some(t) = &a.truth {
        write_json(t, &Truth { config: &cfg }, a.force)?;
    }
    w(
        out,
        format!(
            "wrote {} ({} rows, seed {})",
            a.out.display(),
            sim.rows,
            cfg.seed
        ),
    )
}

/// `plan --json`.
#[derive(Serialize)]
struct Planned<'a> {
    limits: &'a crate::plan::Limits,
    verification_temps_c: [f64; 3],
    candidates: &'a [crate::plan::Candidate],
    chosen: &'a crate::plan::Candidate,
    program: String,
    program_rows: usize,
    /// How the program separates the diagnosis's coupled effects (none asked: absent).
    #[serde(skip_serializing_if = "Option::is_none")]
    separation: Option<&'a str>,
}

/// The plan's options checked one by one, so the error names the option at fault.
fn check_plan_options(a: &PlanArgs) -> Result<()> {
    let bad = |opt: &str, why: String| {
        Err(HostError::new(
            ErrorKind::Invalid,
            format!("plan: {opt} {why}"),
        ))
    };
    match a.range_c.as_slice() {
        [lo, hi] if lo.is_finite() && hi.is_finite() && lo < hi => {}
        r => {
            return bad(
                "--range-c",
                format!("must be LO,HI with LO < HI (got {r:?})"),
            )
        }
    }
    for (opt, v, strict) in [
        ("--max-ramp-c-per-min", a.max_ramp_c_per_min, true),
        ("--rate-hz", a.rate_hz, true),
        ("--noise", a.noise.unwrap_or(1.0), true),
        ("--dwell-s", a.dwell_s, true),
        ("--move-s", a.move_s, false),
        ("--tau-s", a.tau_s.unwrap_or(0.0), false),
    ] {
        if !v.is_finite() || v < 0.0 || (strict && v == 0.0) {
            let need = if strict { "> 0" } else { ">= 0" };
            return bad(opt, format!("must be a finite number {need} (got {v})"));
        }
    }
    if a.positions.len() < 6 {
        return bad(
            "--positions",
            format!("needs at least 6 positions (got {})", a.positions.len()),
        );
    }
    match (a.target_mg, a.hours) {
        (Some(v), None) | (None, Some(v)) if !(v.is_finite() && v > 0.0) => bad(
            if a.target_mg.is_some() {
                "--target-mg"
            } else {
                "--hours"
            },
            format!("must be a finite number > 0 (got {v})"),
        ),
        _ => Ok(()),
    }
}

/// What `plan --from-diagnosis` reads of a `diagnose --json` output, typed.
#[derive(Deserialize)]
struct UnitType {
    /// Per axis (null where not a number).
    #[serde(default)]
    noise_sigma_per_sample: Option<Vec<Option<f64>>>,
    #[serde(default)]
    findings: Vec<Finding>,
    #[serde(default)]
    ambiguous: Vec<Ambiguous>,
}

/// An ambiguity of the diagnosis: the candidates it could not tell apart.
#[derive(Deserialize)]
struct Ambiguous {
    candidates: Vec<EffectId>,
}

/// What `plan` takes of a unit type's diagnosis.
pub(super) struct TypeFacts {
    /// The thermal lag's time constant (the slowest axis), s.
    pub tau_s: Option<f64>,
    /// The noise per sample (the noisiest axis), output units.
    pub noise: Option<f64>,
    /// The coupled effects a stop-and-soak program must separate
    /// ([`crate::plan::to_separate`]).
    pub separate: Vec<EffectId>,
}

/// The unit type's time constant, noise per sample and coupled effects from a
/// `diagnose --json` output: the thermal_lag finding's slowest axis, the noisiest axis,
/// the findings and ambiguities a program must separate; an error names the file and
/// what it lacks.
pub(super) fn from_diagnosis(path: &std::path::Path, text: &str) -> Result<TypeFacts> {
    let bad = |why: &str| HostError::in_file(ErrorKind::Malformed, path, why);
    let j: UnitType =
        serde_json::from_str(text).map_err(|e| bad(&format!("not a diagnosis JSON ({e})")))?;
    let noise = j.noise_sigma_per_sample.and_then(|v| {
        let v: Vec<f64> = v.into_iter().flatten().collect();
        (v.len() == 3 && v.iter().all(|x| x.is_finite() && *x > 0.0))
            .then(|| v.iter().copied().fold(0.0, f64::max))
    });
    let tau = j
        .findings
        .iter()
        .find(|f| f.effect == EffectId::ThermalLag)
        .map(|f| {
            // the lag's first pole, for all axes or per axis (the slowest)
            f.parameters
                .list
                .iter()
                .filter(|p| matches!(p.quantity, Quantity::Tau { pole: 1, .. }))
                .map(|p| p.value)
                .filter(|t| t.is_finite() && *t >= 0.0)
                .fold(f64::NAN, f64::max)
        })
        .filter(|t| t.is_finite());
    let found: Vec<EffectId> = j.findings.iter().map(|f| f.effect).collect();
    let groups: Vec<Vec<EffectId>> = j.ambiguous.into_iter().map(|g| g.candidates).collect();
    Ok(TypeFacts {
        tau_s: tau,
        noise,
        separate: crate::plan::to_separate(&found, &groups),
    })
}

/// The unit type `plan` plans for: `--tau-s` and `--noise`, else the diagnosis's
/// (`--from-diagnosis`; an error names what it lacks), and the diagnosis's coupled
/// effects to separate.
fn unit_type(a: &PlanArgs) -> Result<TypeFacts> {
    let (mut tau_s, mut noise) = (a.tau_s, a.noise);
    let mut separate = Vec::new();
    if let Some(d) = &a.from_diagnosis {
        let text = std::fs::read_to_string(d)
            .map_err(|e| HostError::new(ErrorKind::Io, format!("{}: {e}", d.display())))?;
        let TypeFacts {
            tau_s: t,
            noise: n,
            separate: s,
        } = from_diagnosis(d, &text)?;
        separate = s;
        let missing = |what: &str, opt: &str| {
            HostError::new(
                ErrorKind::Insufficient,
                format!(
                    "{}: {what} missing (give {opt}{})",
                    d.display(),
                    if opt == "--tau-s" {
                        ", --tau-s 0 for a unit found without lag"
                    } else {
                        ""
                    }
                ),
            )
        };
        if tau_s.is_none() {
            tau_s = Some(t.ok_or_else(|| {
                missing(
                    "the thermal_lag finding's time constant (tau_*_s)",
                    "--tau-s",
                )
            })?);
        }
        if noise.is_none() {
            noise =
                Some(n.ok_or_else(|| {
                    missing("noise_sigma_per_sample (three values > 0)", "--noise")
                })?);
        }
    }
    Ok(TypeFacts {
        tau_s,
        noise,
        separate,
    })
}

pub(super) fn plan(a: PlanArgs, out: &mut dyn Write) -> Result<()> {
    use crate::plan::{
        candidates, choose, program, table, verification, verification_temps, Limits, Target,
    };
    check_writable(&a.out, a.force)?;
    if let Some(r) = &a.report {
        check_writable(r, a.force)?;
    }
    let target = match (a.target_mg, a.hours) {
        (Some(mg), None) => Target::AccuracyMg(mg),
        (None, Some(h)) => Target::Hours(h),
        _ => {
            return Err(HostError::new(
                ErrorKind::Invalid,
                "give a target: --target-mg MG or --hours H",
            ))
        }
    };
    check_plan_options(&a)?;
    let TypeFacts {
        tau_s,
        noise,
        separate,
    } = unit_type(&a)?;
    let l = Limits {
        lo_c: a.range_c.first().copied().unwrap_or(f64::NAN),
        hi_c: a.range_c.get(1).copied().unwrap_or(f64::NAN),
        max_ramp_c_per_min: a.max_ramp_c_per_min,
        positions: a.positions.clone(),
        dwell_s: a.dwell_s,
        move_s: a.move_s,
        rate_hz: a.rate_hz,
        noise_v: noise.unwrap_or(crate::simulate::config::UNIT_NOISE_V),
        tau_s: tau_s.unwrap_or(0.0),
        separate,
    };
    let c = candidates(&l, a.seed)?;
    let chosen = choose(&c, target);
    let text = table(&c, chosen);
    let Some(i) = chosen else {
        return Err(HostError::new(
            ErrorKind::Unmet,
            format!(
                "{}:
{text}",
                crate::plan::why_none(&c, target, &l)
            ),
        ));
    };
    // what separates the diagnosis's coupled effects: the chosen program's return (only
    // a stop-and-soak program that has one is chosen then)
    let separation =
        crate::plan::separation(&l).map(|r| format!("the program ends with {}", r.describe()));
    let (mut steps, end) = program(c[i].kind, &l);
    let last = steps.pop().map(|s| s.setpoint_c).unwrap_or(l.lo_c);
    steps.extend(verification(&l, end, last));
    let csv = crate::simulate::program::to_csv(&steps);
    let page = match &a.report {
        Some(_) => Some(crate::report::plan::html(&c, i, target, &l)?),
        None => None,
    };
    write_atomic(&a.out, csv.as_bytes(), a.force)?;
    if let (Some(r), Some(p)) = (&a.report, &page) {
        write_atomic(r, p.as_bytes(), a.force)?;
    }
    if a.json {
        return w(
            out,
            crate::output::json(&Planned {
                limits: &l,
                verification_temps_c: verification_temps(&l),
                candidates: &c,
                chosen: &c[i],
                program: a.out.display().to_string(),
                program_rows: steps.len(),
                separation: separation.as_deref(),
            })?,
        );
    }
    w(
        out,
        format!(
            "{text}chosen: {} {} ({:.2} chamber hours, predicted worst |dg| {:.4} mg, its blob valid over {} C of the {}..{} C asked); verification block at {:?} C\nwrote {} ({} rows; run it on the twin with `host-fit simulate --plan {}`)",
            crate::plan::Candidate::label(i),
            c[i].kind.describe(),
            c[i].hours,
            c[i].predicted_mg,
            c[i].valid_text(),
            l.lo_c,
            l.hi_c,
            verification_temps(&l),
            a.out.display(),
            steps.len(),
            a.out.display()
        ) + &separation.map_or(String::new(), |s| format!("\nseparating: {s}")),
    )
}

pub(super) fn demo(a: DemoArgs, out: &mut dyn Write) -> Result<()> {
    let (oc, plan) = crate::demo::run(&a.out, a.seed, a.force)?;
    w(
        out,
        format!(
            "{}{}",
            crate::analysis::table(
                &oc.rows,
                &crate::analysis::verification_names(&oc.recording)
            ),
            crate::analysis::verdicts(&oc)
        ),
    )?;
    w(out, crate::demo_plan::text(&plan))?;
    w(
        out,
        format!(
            "plan:    {} (its program), {} (its blob)",
            a.out.join(crate::demo::PLAN_PROGRAM).display(),
            a.out.join(crate::demo::PLAN_BLOB).display()
        ),
    )?;
    w(
        out,
        format!("summary: {}", a.out.join("summary.json").display()),
    )?;
    w(
        out,
        format!("report:  {}", a.out.join("report.html").display()),
    )?;
    // the line's memory: what the store now holds of this unit
    let db = a.out.join(crate::demo::STORE);
    let mut store = crate::store::Store::open_existing(&db)?;
    let h = crate::store::history::history(&mut store, &oc.recording.unit)?;
    w(
        out,
        format!(
            "records: {}
{}",
            db.display(),
            h.text()
        ),
    )
}
