//! The demo's second half (issue 19): `host-fit plan` for the demo's unit with the
//! paper test's predicted accuracy as the target, the chosen program run on the same unit
//! of the twin (same seed, same truth), fitted as `fit` would (the dynamic route when it
//! is a sweep), and both blobs, the paper test's data-chosen one and the plan's, verified
//! through firmware-core on one equilibrium verification block recorded apart.
use crate::acceptance::{judge, Acceptance, Spec};
use crate::blob::build_blob;
use crate::data::positions::Role;
use crate::data::recording::Recording;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::pipeline::ModelRequest;
use crate::fit::route::{fit_on, Flash, Routed};
use crate::plan::{
    candidates, choose, predict, program, run, verification, verification_temps, Candidate, Limits,
    Target,
};
use crate::simulate::program::{to_csv, Step};
use crate::simulate::SimConfig;
use crate::verify::verify;
use firmware_core::blob::Blob;
use firmware_core::compensate::Method;
use firmware_core::temperature::Calibration;
use serde::Serialize;

/// How the plan's target was set.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str")]
#[strum(serialize_all = "snake_case")]
pub enum TargetFrom {
    /// The paper test's own predicted worst |dg| (the same prediction as the
    /// candidates', on the same verification block): the shortest plan at least as
    /// accurate.
    PaperPrediction,
    /// No candidate is predicted that accurate: the most accurate within the paper
    /// test's chamber hours.
    PaperHours,
}

/// One test of the comparison, judged on the verification block.
#[derive(Debug, Clone, Serialize)]
pub struct Judged {
    /// `paper test` or the chosen plan's description.
    pub test: String,
    /// Chamber hours of the calibration recording (the verification block apart).
    pub hours: f64,
    /// What was fitted (route and model).
    pub fitted: String,
    /// The blob's valid range, C.
    pub valid_c: (f64, f64),
    /// The worst verification |dg| (method 1), mg.
    pub worst_mg: f64,
    /// The acceptance of its blob on the block.
    pub acceptance: Acceptance,
}

/// The plan beside the paper's test.
pub struct Beside {
    /// The chamber, tilter and unit type the plan was made for.
    pub limits: Limits,
    /// Every candidate, predicted.
    pub candidates: Vec<Candidate>,
    /// The chosen candidate (an index of `candidates`).
    pub chosen: usize,
    /// The paper test's predicted worst |dg| on the verification block, mg.
    pub paper_predicted_mg: f64,
    /// How the target was set.
    pub target_from: TargetFrom,
    /// The target.
    pub target: Target,
    /// The chosen program followed by its verification block, as `plan` writes it.
    pub program_csv: String,
    /// The twin's recording of the chosen calibration program.
    pub recording_csv: String,
    /// Its recording, parsed.
    pub recording: Recording,
    /// The twin's recording of the verification block (the same unit).
    pub verification_csv: String,
    /// The plan's blob.
    pub blob: Vec<u8>,
    /// Its calibration (for the record).
    pub calibration: Calibration<f64>,
    /// The paper test's data-chosen blob and the plan's blob, judged on the block.
    pub judged: [Judged; 2],
}

/// The demo unit's chamber, tilter and type: the paper test's range, positions, dwells,
/// moves, sample rate, noise and lag; the chamber's fastest ramp is `plan`'s default.
pub fn limits(cfg: &SimConfig) -> Limits {
    let stops = cfg.schedule.stops.iter().map(|s| s.temp_c);
    Limits {
        lo_c: stops.clone().fold(f64::INFINITY, f64::min),
        hi_c: stops.fold(f64::NEG_INFINITY, f64::max),
        max_ramp_c_per_min: crate::plan::DEFAULT_MAX_RAMP_C_PER_MIN,
        positions: cfg.schedule.positions.clone(),
        dwell_s: cfg.schedule.dwell_s,
        move_s: cfg.schedule.move_s,
        rate_hz: cfg.schedule.rate_hz,
        noise_v: cfg.unit.noise_v,
        tau_s: cfg
            .effects
            .thermal_lag
            .as_ref()
            .map_or(0.0, |l| l.value.iter().copied().fold(0.0, f64::max)),
        // the demo plans from its twin, not from a diagnosis
        separate: Vec::new(),
    }
}

/// A recording fitted as `fit` fits it by default (`--route auto`: the dynamic route for
/// a sweep or a stop-and-soak test still settling behind a lag, else the static route
/// with the model the data choose); its calibration (the cache chosen as `fit` chooses
/// it) and a description.
pub fn fit_as_fit_does(rec: &Recording) -> Result<(Calibration<f64>, String)> {
    let routed = fit_on(rec, None, &ModelRequest::default(), &mut Vec::new())?;
    let cal = routed.calibration(rec, Flash::default())?.cal;
    let fitted = match &routed {
        Routed::Dynamic { .. } => format!("dynamic route, {}", routed.describe()),
        Routed::Identified { outcome, .. } => {
            let model = crate::analysis::Compared::Chosen(outcome.fit.basis.clone());
            format!("static route, {}", model.family())
        }
    };
    Ok((cal, fitted))
}

/// A test of the comparison, before it is judged.
struct Tested {
    /// `paper test` or the chosen plan's description.
    test: String,
    /// Chamber hours of its calibration recording.
    hours: f64,
    /// What was fitted (route and model).
    fitted: String,
}

/// Verify `blob` on the block `ver` with method 1 and judge it.
fn judged(ver: &Recording, blob: &Blob, what: Tested) -> Result<Judged> {
    let check = |p: usize| ver.positions.has_role(p, Role::Verification);
    let v = verify(ver, blob, Method::CorrectConstants, &check)
        .ok_or_else(|| HostError::new(ErrorKind::Numerical, "singular K(T0)"))?;
    if v.dwells.is_empty() {
        return Err(HostError::new(
            ErrorKind::Internal,
            "internal: the verification block has no verification dwells",
        ));
    }
    let worst_mg = v
        .max_by_temperature
        .iter()
        .map(|t| t.max_abs_dg_mg)
        .fold(0.0, f64::max);
    let cal = &blob.calibration;
    let acceptance = judge(
        &v,
        &Spec::default(),
        f64::from(cal.t0_c),
        (f64::from(cal.t_min_c), f64::from(cal.t_max_c)),
    );
    Ok(Judged {
        test: what.test,
        hours: what.hours,
        fitted: what.fitted,
        valid_c: (f64::from(cal.t_min_c), f64::from(cal.t_max_c)),
        worst_mg,
        acceptance,
    })
}

/// The plan beside the paper test `paper` (its recording, its data-chosen blob's bytes
/// and model name) of the unit `cfg`.
pub fn beside(
    cfg: &SimConfig,
    paper: &Recording,
    paper_blob: (&[u8], &crate::analysis::Compared),
) -> Result<Beside> {
    let l = limits(cfg);
    let temps = verification_temps(&l);
    let dwell_samples = l.dwell_s * l.rate_hz;
    // the paper test predicted as the candidates are, so the target is like for like
    let paper_predicted_mg =
        predict(paper, &temps, &l.positions, l.noise_v, dwell_samples)?.worst_mg;
    let paper_hours = paper.rows.last().map_or(0.0, |r| r.t_s) / 3600.0;
    let c = candidates(&l, cfg.seed)?;
    let (target_from, target, chosen) = match choose(&c, Target::AccuracyMg(paper_predicted_mg)) {
        Some(i) => (
            TargetFrom::PaperPrediction,
            Target::AccuracyMg(paper_predicted_mg),
            i,
        ),
        None => {
            let t = Target::Hours(paper_hours);
            let i = choose(&c, t).ok_or_else(|| {
                HostError::new(
                    ErrorKind::Unmet,
                    format!(
                        "{}:
{}",
                        crate::plan::why_none(&c, t, &l),
                        crate::plan::table(&c, None)
                    ),
                )
            })?;
            (TargetFrom::PaperHours, t, i)
        }
    };
    let (mut steps, end) = program(c[chosen].kind, &l);
    let cal_steps: Vec<Step> = steps.clone();
    let last = steps.pop().map_or(l.lo_c, |s| s.setpoint_c);
    steps.extend(verification(&l, end, last));
    let program_csv = to_csv(&steps);
    // the same unit through the chosen calibration program, and through the block
    // recorded apart (starting soaked where the program ended), so no verification
    // dwell is fitted
    let (recording_csv, rec) = run(cfg, &cal_steps, "plan-recording.csv")?;
    let (verification_csv, ver) = run(cfg, &verification(&l, 0.0, last), "verification.csv")?;
    let (cal, fitted) = fit_as_fit_does(&rec)?;
    let (blob, bytes, _) = build_blob(rec.serial(), &rec.output_unit, &cal)?;
    let paper_b = Blob::decode(paper_blob.0).map_err(|e| {
        HostError::new(
            ErrorKind::Internal,
            format!("internal: the paper test's blob: {e}"),
        )
    })?;
    let judged = [
        judged(
            &ver,
            &paper_b,
            Tested {
                test: "paper test".to_string(),
                hours: paper_hours,
                fitted: format!("static route, {}", paper_blob.1.family()),
            },
        )?,
        judged(
            &ver,
            &blob,
            Tested {
                test: format!("plan: {}", c[chosen].kind.describe()),
                hours: c[chosen].hours,
                fitted,
            },
        )?,
    ];
    Ok(Beside {
        limits: l,
        candidates: c,
        chosen,
        paper_predicted_mg,
        target_from,
        target,
        program_csv,
        recording_csv,
        recording: rec,
        verification_csv,
        blob: bytes,
        calibration: cal,
        judged,
    })
}

/// The comparison as text: the candidates, the choice and the table of the two tests.
pub fn text(b: &Beside) -> String {
    let temps = verification_temps(&b.limits);
    let why = match (b.target_from, b.target) {
        (TargetFrom::PaperPrediction, Target::AccuracyMg(mg)) => format!(
            "the shortest plan predicted within the paper test's own predicted {mg:.4} mg"
        ),
        (TargetFrom::PaperHours, Target::Hours(h)) => format!(
            "none predicted within the paper test's {:.4} mg: the most accurate within its {h:.2} h",
            b.paper_predicted_mg
        ),
        (_, Target::AccuracyMg(mg)) => format!("the shortest within {mg:.4} mg"),
        (_, Target::Hours(h)) => format!("the most accurate within {h:.2} h"),
    };
    let mut s = format!(
        "host-fit plan for this unit (range {:.0}..{:.0} C, fastest ramp {:.0} C/min, {} positions, {:.0}-s dwells; candidates on the twin, predicted worst verification |dg|):\n{}chosen: {why}\n",
        b.limits.lo_c,
        b.limits.hi_c,
        b.limits.max_ramp_c_per_min,
        b.limits.positions.len(),
        b.limits.dwell_s,
        crate::plan::table(&b.candidates, Some(b.chosen)),
    );
    s.push_str(&format!(
        "the paper test and the plan on the same unit, verified through firmware-core (method 1) on one equilibrium block at {:?} C:\n",
        temps
    ));
    let w = b
        .judged
        .iter()
        .map(|j| j.test.len())
        .chain([4])
        .max()
        .unwrap_or(4);
    let wf = b
        .judged
        .iter()
        .map(|j| j.fitted.len())
        .chain([6])
        .max()
        .unwrap_or(6);
    s.push_str(&format!(
        "  {:<w$}   chamber h   {:<wf$}   valid range, C   worst |dg|, mg   verdict\n",
        "test", "fitted"
    ));
    for j in &b.judged {
        s.push_str(&format!(
            "  {:<w$}   {:>9.2}   {:<wf$}   {:>14}   {:>14.4}   {}\n",
            j.test,
            j.hours,
            j.fitted,
            format!("{:.1}..{:.1}", j.valid_c.0, j.valid_c.1),
            j.worst_mg,
            j.acceptance.acceptance.name()
        ));
    }
    s
}
