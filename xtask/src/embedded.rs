//! `cargo xtask embedded`: firmware-core on a Cortex-M4F. The host's test vectors, the
//! firmware test built with and without `physics` and run under QEMU (bit for bit, then
//! measured), the C harness, the report (target/embedded/summary.md) and the budgets.
use crate::measure::{self, Measured};
use crate::qemu::{self, Counting};
use crate::steps::{Outcome, Steps};
use crate::toolchain::toolchain;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The test vectors from host-fit: a PWL blob, a blob with physics terms, an input table,
/// and the host's f32 results for each blob.
pub struct Vectors {
    /// The PWL blob of `host-fit fit` on a simulated recording.
    pub blob: PathBuf,
    /// The blob of `host-fit diagnose --out` on a unit with in-flight effects.
    pub physics_blob: PathBuf,
    /// The input table, edge cases included.
    pub inputs: PathBuf,
    /// `host-fit fw-vectors` of the PWL blob.
    pub expected: String,
    /// `host-fit fw-vectors` of the physics blob (tags `p...`).
    pub expected_physics: String,
}

impl Vectors {
    /// What the build with `physics` must print: both blobs' results.
    pub fn expected_all(&self) -> String {
        format!("{}{}", self.expected, self.expected_physics)
    }
}

/// What the QEMU step hands the steps after it.
struct Run {
    sysroot: PathBuf,
    dir: PathBuf,
    vectors: Vectors,
    full: Measured,
    core: Measured,
}

/// The step names, as the table lists them.
const QEMU_STEP: &str = "embedded (bit-exact under QEMU)";
const C_STEP: &str = "embedded: C harness bit-exact";
const BUDGETS_STEP: &str = "embedded budgets";

/// `cargo xtask embedded`: run the firmware test under QEMU, compare bit for bit,
/// measure, write target/embedded/summary.md, and judge the budgets.
pub fn embedded(steps: &mut Steps) {
    let Ok(run) = steps.step(QEMU_STEP, under_qemu) else {
        steps.skip(C_STEP, "the QEMU step failed");
        steps.skip(BUDGETS_STEP, "nothing measured");
        return;
    };
    let c = steps.step(C_STEP, || {
        crate::c_harness::run(&run.sysroot, &run.dir, &run.vectors)
    });
    let c_line =
        c.unwrap_or_else(|e| format!("C harness: FAILED ({})", e.lines().next().unwrap_or("")));
    let md = crate::summary::report(&run.full, &run.core, &c_line);
    let out = crate::root().join("target/embedded");
    let _ = std::fs::create_dir_all(&out);
    let _ = std::fs::write(out.join("summary.md"), &md);
    println!("{md}");
    // every budget of both builds, all failures collected
    let mut missed = crate::budgets::missed(&run.full, "with physics");
    missed.extend(crate::budgets::missed(&run.core, "without physics"));
    if missed.is_empty() {
        steps.record(BUDGETS_STEP, Outcome::Pass, Duration::ZERO);
    }
    for (budget, why) in missed {
        let why = format!("{why} (target/embedded/summary.md has every figure)");
        steps.record(
            &format!("embedded budget: {budget}"),
            Outcome::Fail(why),
            Duration::ZERO,
        );
    }
}

/// The tools, the vectors, and both builds run and measured.
fn under_qemu() -> Result<Run, String> {
    crate::setup::qemu()?;
    crate::setup::tools()?;
    let sysroot = toolchain()?;
    let dir = crate::root().join("target/qemu");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let vectors = vectors(&dir)?;
    let plugin = qemu::plugin(&dir)?;
    let full = variant(&sysroot, &vectors, &dir, &plugin, true)?;
    let core = variant(&sysroot, &vectors, &dir, &plugin, false)?;
    Ok(Run {
        sysroot,
        dir,
        vectors,
        full,
        core,
    })
}

/// `host-fit ARGS` (release, quiet): its standard output.
fn host_fit(args: &[&str]) -> Result<String, String> {
    let out = crate::cargo()
        .args(["run", "--quiet", "--release", "-p", "host-fit", "--"])
        .args(args)
        .output()
        .map_err(|e| e.to_string())?;
    if !out.status.success() {
        return Err(format!(
            "host-fit {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The test vectors, written into `dir`.
fn vectors(dir: &Path) -> Result<Vectors, String> {
    let (rec, blob, inputs) = (
        dir.join("rec.csv"),
        dir.join("unit.blob"),
        dir.join("inputs.bin"),
    );
    let s = |p: &Path| p.to_string_lossy().into_owned();
    host_fit(&["simulate", "--out", &s(&rec), "--force"])?;
    host_fit(&[
        "fit",
        &s(&rec),
        "--model",
        "pwl",
        "--out",
        &s(&blob),
        "--force",
    ])?;
    host_fit(&[
        "fw-vectors",
        "--blob",
        &s(&blob),
        "--make-inputs",
        &s(&inputs),
        "--force",
    ])?;
    let expected = host_fit(&["fw-vectors", "--blob", &s(&blob), "--inputs", &s(&inputs)])?;
    // the extended model: a unit with in-flight effects, diagnosed, its blob with physics
    let (prec, pblob) = (dir.join("in-flight.csv"), dir.join("in-flight.blob"));
    let cfg = crate::root().join("examples/sim/in-flight-effects.toml");
    host_fit(&["simulate", &s(&cfg), "--out", &s(&prec), "--force"])?;
    host_fit(&["diagnose", &s(&prec), "--out", &s(&pblob), "--force"])?;
    let expected_physics = host_fit(&[
        "fw-vectors",
        "--blob",
        &s(&pblob),
        "--inputs",
        &s(&inputs),
        "--tag-prefix",
        "p",
    ])?
    .replace("f64-departure ", "f64-departure-physics ");
    Ok(Vectors {
        blob,
        physics_blob: pblob,
        inputs,
        expected,
        expected_physics,
    })
}

/// One build of the firmware test run under QEMU with the counting plugin, compared
/// with the host, and measured.
fn variant(
    sysroot: &Path,
    v: &Vectors,
    dir: &Path,
    plugin: &Path,
    physics: bool,
) -> Result<Measured, String> {
    let elf = qemu::build_harness(sysroot, v, dir, physics)?;
    let expected = if physics {
        v.expected_all()
    } else {
        v.expected.clone()
    };
    let nm = measure::symbols(&elf)?;
    let log = dir.join("plugin.log");
    let _ = std::fs::remove_file(&log);
    let counting = Counting {
        plugin,
        start: measure::address(&nm, "fw_mark_start")?,
        stop: measure::address(&nm, "fw_mark_stop")?,
        log: &log,
    };
    let out = qemu::run(&elf, Some(&counting))?;
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "the firmware test failed under QEMU ({}):\n{stdout}{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let samples = qemu::compare(&stdout, &expected)?;
    let physics_refused = stdout.lines().any(|l| l == "physics refused");
    if !physics && !physics_refused {
        return Err("built without physics, the physics blob was not refused".into());
    }
    let mut departures = Vec::new();
    for (key, what) in [
        ("f64-departure ", "the PWL blob"),
        ("f64-departure-physics ", "the blob with physics terms"),
    ] {
        departures.extend(
            expected
                .lines()
                .filter_map(|l| l.strip_prefix(key))
                .map(|l| (what, l.to_string())),
        );
    }
    let (components, soft_double) = measure::components(&nm);
    Ok(Measured {
        samples,
        physics_refused,
        departures,
        sizes: measure::sections(
            &elf,
            &[".vector_table", ".text", ".rodata", ".data", ".bss"],
        )?,
        components,
        icount: measure::icounts(&stdout, &log)?,
        soft_double,
        stack_decode: measure::value(&stdout, "stack decode "),
        stack_compensate: measure::value(&stdout, "stack compensate "),
        state: measure::value(&stdout, "size compensator "),
        blob_view: measure::value(&stdout, "size blob "),
    })
}
