//! `batch`, `simulate` and `demo`: many units, the twin, and the main job.
use super::args::{BatchArgs, DemoArgs, SimulateArgs};
use super::common::w;
use crate::error::{HostError, Result};
use crate::output::{check_writable, write_atomic, write_json};
use crate::simulate::SimConfig;
use serde::Serialize;
use std::io::Write;

pub(super) fn batch(a: BatchArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    let t = std::time::Instant::now();
    let res = crate::batch::run(&a.dir, &a.out, a.jobs, a.model, a.diagnose, a.force)?;
    let bad: Vec<_> = res.iter().filter(|r| r.status != "ok").collect();
    for r in &bad {
        let _ = writeln!(err, "{}: {}", r.file.display(), r.status);
    }
    w(
        out,
        format!(
            "{} units in {:.1} s: {} ok, {} failed; summary {}",
            res.len(),
            t.elapsed().as_secs_f64(),
            res.len() - bad.len(),
            bad.len(),
            a.out.join("summary.csv").display()
        ),
    )
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
    let sim = crate::simulate::simulate(&cfg, |_| {})?;
    write_atomic(&a.out, sim.csv.as_bytes(), a.force)?;
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

pub(super) fn demo(a: DemoArgs, out: &mut dyn Write) -> Result<()> {
    let oc = crate::demo::run(&a.out, a.seed, a.force)?;
    w(out, crate::analysis::table(&oc.rows))?;
    w(
        out,
        format!("summary: {}", a.out.join("summary.json").display()),
    )?;
    w(
        out,
        format!("report:  {}", a.out.join("report.html").display()),
    )
}
