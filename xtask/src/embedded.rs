//! `cargo xtask embedded`: firmware-core on a Cortex-M4F. The host's test vectors, the
//! firmware test built with `physics` and `terms`, with `physics` only, and with neither,
//! run under QEMU (bit for bit, then measured), the C harness, the report
//! (target/embedded/summary.md) and the budgets.
use crate::measure::{self, Build, Measured};
use crate::qemu::{self, Counting};
use crate::steps::{Outcome, Steps};
use crate::toolchain::toolchain;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The test vectors from host-fit: a PWL blob, a blob with physics terms, a blob with
/// discovered terms, an input table, and the host's f32 results for each blob.
pub struct Vectors {
    /// The PWL blob of `host-fit fit` on a simulated recording.
    pub blob: PathBuf,
    /// The blob of `host-fit diagnose --out` on a unit with in-flight effects.
    pub physics_blob: PathBuf,
    /// The committed golden blob with a full table of discovered terms
    /// (firmware-core/tests/data/example_blob_terms.hex: the paper unit, physics terms and
    /// 8 discovered terms of every kind of factor).
    pub terms_blob: PathBuf,
    /// The input table, edge cases included.
    pub inputs: PathBuf,
    /// `host-fit fw-vectors` of the PWL blob.
    pub expected: String,
    /// `host-fit fw-vectors` of the physics blob (tags `p...`).
    pub expected_physics: String,
    /// `host-fit fw-vectors` of the terms blob (tags `t...`).
    pub expected_terms: String,
}

impl Vectors {
    /// What a build must print: the results of every blob it compensates.
    pub fn expected(&self, build: Build) -> String {
        match build {
            Build::Terms => format!(
                "{}{}{}",
                self.expected, self.expected_physics, self.expected_terms
            ),
            Build::Physics => format!("{}{}", self.expected, self.expected_physics),
            Build::Core => self.expected.clone(),
        }
    }
}

/// The golden blob with discovered terms, committed as hex.
const TERMS_BLOB_HEX: &str = "firmware-core/tests/data/example_blob_terms.hex";

/// What the QEMU step hands the steps after it.
struct Run {
    sysroot: PathBuf,
    dir: PathBuf,
    vectors: Vectors,
    builds: Vec<Measured>,
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
    let md = crate::summary::report(&run.builds, &c_line);
    let out = crate::root().join("target/embedded");
    let _ = std::fs::create_dir_all(&out);
    let _ = std::fs::write(out.join("summary.md"), &md);
    println!("{md}");
    // every budget of every build, all failures collected
    let missed: Vec<(String, String)> = run
        .builds
        .iter()
        .flat_map(|m| crate::budgets::missed(m, m.build.label()))
        .collect();
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

/// The tools, the vectors, and every build run and measured.
fn under_qemu() -> Result<Run, String> {
    crate::setup::qemu()?;
    crate::setup::tools()?;
    let sysroot = toolchain()?;
    let dir = crate::root().join("target/qemu");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let vectors = vectors(&dir)?;
    let plugin = qemu::plugin(&dir)?;
    let builds = Build::ALL
        .iter()
        .map(|b| variant(&sysroot, &vectors, &dir, &plugin, *b))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Run {
        sysroot,
        dir,
        vectors,
        builds,
    })
}

/// The bytes of a hex file (whitespace ignored).
fn unhex(text: &str) -> Result<Vec<u8>, String> {
    let digits: Vec<u8> = text.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    digits
        .chunks(2)
        .map(|p| {
            std::str::from_utf8(p)
                .ok()
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .filter(|_| p.len() == 2)
                .ok_or_else(|| format!("not hex: {:?}", String::from_utf8_lossy(p)))
        })
        .collect()
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
    // discovered terms: the committed golden blob, its results from host-fit
    let tblob = dir.join("terms.blob");
    let hex_path = crate::root().join(TERMS_BLOB_HEX);
    let hex =
        std::fs::read_to_string(&hex_path).map_err(|e| format!("{}: {e}", hex_path.display()))?;
    std::fs::write(&tblob, unhex(&hex)?).map_err(|e| e.to_string())?;
    let expected_terms = host_fit(&[
        "fw-vectors",
        "--blob",
        &s(&tblob),
        "--inputs",
        &s(&inputs),
        "--tag-prefix",
        "t",
    ])?
    .replace("f64-departure ", "f64-departure-terms ");
    Ok(Vectors {
        blob,
        physics_blob: pblob,
        terms_blob: tblob,
        inputs,
        expected,
        expected_physics,
        expected_terms,
    })
}

/// One build of the firmware test run under QEMU with the counting plugin, compared
/// with the host, and measured.
fn variant(
    sysroot: &Path,
    v: &Vectors,
    dir: &Path,
    plugin: &Path,
    build: Build,
) -> Result<Measured, String> {
    let elf = qemu::build_harness(sysroot, v, dir, build)?;
    let expected = v.expected(build);
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
    let refused = |what: &str| stdout.lines().any(|l| l == format!("{what} refused"));
    if !build.physics() && !refused("physics") {
        return Err("built without physics, the physics blob was not refused".into());
    }
    if !build.terms() && !refused("terms") {
        return Err("built without terms, the blob with discovered terms was not refused".into());
    }
    let mut departures = Vec::new();
    for (key, what) in [
        ("f64-departure ", "the PWL blob"),
        ("f64-departure-physics ", "the blob with physics terms"),
        ("f64-departure-terms ", "the blob with discovered terms"),
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
        build,
        samples,
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
