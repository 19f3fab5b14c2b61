//! `cargo xtask cross` and `cargo xtask embedded`: firmware-core on a Cortex-M4F.
//!
//! The cross compiler is Debian's rustc-web (with the matching library sources for
//! `-Zbuild-std=core`), downloaded with `apt-get download` and unpacked under
//! `target/cross-toolchain/` (cached: a second run does not download). The rustup
//! toolchain stays untouched for the host build. See ../shared/embedded/cross-build-notes.md.
use std::path::{Path, PathBuf};
use std::process::Command;

const PACKAGES: [&str; 13] = [
    "rustc-web",
    "cargo-web",
    "libstd-rust-web-1.96",
    "libstd-rust-web-dev",
    "rust-web-src",
    "rust-web-llvm",
    "libllvm22",
    "lld-22",
    "libgit2-1.5",
    "libhttp-parser2.9",
    "libmbedcrypto7",
    "libmbedtls14",
    "libmbedx509-1",
];
/// The MCU target.
pub const TARGET: &str = "thumbv7em-none-eabihf";

fn sh(cmd: &mut Command) -> Result<(), String> {
    let st = cmd.status().map_err(|e| format!("{cmd:?}: {e}"))?;
    if st.success() {
        Ok(())
    } else {
        Err(format!("{cmd:?} failed ({st})"))
    }
}

/// The unpacked toolchain (downloaded on first use).
pub fn toolchain() -> Result<PathBuf, String> {
    let dir = crate::root().join("target/cross-toolchain");
    let sysroot = dir.join("root");
    let stamp = dir.join("ok");
    if stamp.exists() && sysroot.join("usr/bin/rustc").exists() {
        return Ok(sysroot);
    }
    let debs = dir.join("debs");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&debs).map_err(|e| e.to_string())?;
    eprintln!(
        "xtask: downloading Debian's rustc-web toolchain (~150 MB) into {}",
        dir.display()
    );
    if sh(Command::new("apt-get")
        .arg("download")
        .args(PACKAGES)
        .current_dir(&debs))
    .is_err()
    {
        // stale package lists (the security archive keeps only the newest build)
        crate::setup::apt_update()?;
        sh(Command::new("apt-get")
            .arg("download")
            .args(PACKAGES)
            .current_dir(&debs))
        .map_err(|e| {
            format!("{e}\n(apt-get download needs current package lists: `apt-get update` as root)")
        })?;
    }
    std::fs::create_dir_all(&sysroot).map_err(|e| e.to_string())?;
    for entry in std::fs::read_dir(&debs).map_err(|e| e.to_string())? {
        let deb = entry.map_err(|e| e.to_string())?.path();
        let name = deb
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.starts_with("rust-web-src") {
            // only the library sources build-std needs: 519 MB instead of 885 MB
            let script = format!(
                "dpkg-deb --fsys-tarfile '{}' | tar -x -C '{}' --wildcards './usr/lib/rustlib/src/rust' './usr/src/rustc-*/library/*'",
                deb.display(),
                sysroot.display()
            );
            sh(Command::new("sh").arg("-c").arg(script))?;
        } else {
            sh(Command::new("dpkg").arg("-x").arg(&deb).arg(&sysroot))?;
        }
    }
    let _ = std::fs::remove_dir_all(&debs);
    std::fs::write(&stamp, b"").map_err(|e| e.to_string())?;
    Ok(sysroot)
}

/// A command run with the cross toolchain first in PATH.
pub fn cross_cmd(sysroot: &Path, program: &str) -> Command {
    let mut c = Command::new(sysroot.join("usr/bin").join(program));
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut paths = vec![sysroot.join("usr/bin")];
    paths.extend(std::env::split_paths(&path));
    c.env("PATH", std::env::join_paths(paths).unwrap_or_default())
        .env("LD_LIBRARY_PATH", sysroot.join("usr/lib/x86_64-linux-gnu"))
        .env("RUSTC_BOOTSTRAP", "1")
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("CARGO")
        .env_remove("RUSTC")
        .env_remove("RUSTDOC");
    c
}

/// `cargo xtask cross`: firmware-core for the thumb target, with no default features,
/// each feature alone (`physics`, `defmt`: defmt is checked here, on the target, as
/// defmt's library guide says), and all of them.
pub fn cross(steps: &mut crate::Steps) {
    let sysroot = match toolchain() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("xtask: cross toolchain: {e}");
            steps.failed.push("cross toolchain".into());
            return;
        }
    };
    for feats in [None, Some("physics"), Some("defmt"), Some("all")] {
        let mut c = cross_cmd(&sysroot, "cargo");
        c.current_dir(crate::root()).args([
            "build",
            "-p",
            "firmware-core",
            "--release",
            "--target",
            TARGET,
            "-Zbuild-std=core",
            "--target-dir",
        ]);
        c.arg(crate::root().join("target/thumb"));
        match feats {
            None => c.arg("--no-default-features"),
            Some("all") => c.args(["--all-features"]),
            Some(f) => c.args(["--no-default-features", "--features", f]),
        };
        let name = format!(
            "cross build firmware-core ({})",
            feats.unwrap_or("no default features")
        );
        steps.run(&name, c);
    }
}

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

struct Measured {
    sizes: Vec<(String, u64)>,
    components: Vec<(String, u64)>,
    icount: Vec<(String, u64)>,
    lines: Vec<String>,
    soft_double: Vec<String>,
    /// Painted stack of blob validation, of compensate; size of the compensator state.
    stack_decode: Option<u64>,
    stack_compensate: Option<u64>,
    state: Option<u64>,
}

/// The budgets `cargo xtask embedded` enforces (issue 13).
const BUDGET_DECODE_STACK: u64 = 1024;
const BUDGET_COMPENSATE_STACK: u64 = 512;
const BUDGET_STATE: u64 = 256;
const BUDGET_FLASH: u64 = 6 * 1024;
/// Method 1 per sample: at most 2.5x its floor of 18 operations.
const M1_FLOOR: u64 = 18;
const BUDGET_M1: u64 = M1_FLOOR * 5 / 2;

/// The firmware test under QEMU, built with and without the `physics` feature, and
/// the C harness (its summary line, or why it failed).
fn run_embedded() -> Result<(Measured, Measured, Result<String, String>), String> {
    crate::setup::qemu()?;
    crate::setup::tools()?;
    let sysroot = toolchain()?;
    let dir = crate::root().join("target/qemu");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
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
    let expected_phys = host_fit(&[
        "fw-vectors",
        "--blob",
        &s(&pblob),
        "--inputs",
        &s(&inputs),
        "--tag-prefix",
        "p",
    ])?
    .replace("f64-departure ", "f64-departure-physics ");

    let crate_dir = crate::root().join("firmware-core/qemu-test");
    // the icount plugin
    let plugin = dir.join("icount.so");
    sh(Command::new("gcc")
        .args(["-O2", "-shared", "-fPIC", "-o"])
        .arg(&plugin)
        .arg(crate_dir.join("plugin/icount.c")))?;
    let mut variants = Vec::new();
    for physics in [true, false] {
        let target_dir = crate::root().join("target/qemu-test");
        let mut c = cross_cmd(&sysroot, "cargo");
        c.current_dir(&crate_dir)
            .args(["build", "--release", "--target-dir"])
            .arg(&target_dir)
            .env("FW_TEST_BLOB", &blob)
            .env("FW_TEST_BLOB_PHYS", &pblob)
            .env("FW_TEST_INPUTS", &inputs);
        if physics {
            c.args(["--features", "physics"]);
        }
        sh(&mut c)?;
        // one target dir for both builds (build-std is shared); each ELF kept aside
        let elf = dir.join(if physics {
            "fw-qemu-test-physics.elf"
        } else {
            "fw-qemu-test-core.elf"
        });
        std::fs::copy(target_dir.join(TARGET).join("release/fw-qemu-test"), &elf)
            .map_err(|e| format!("{}: {e}", elf.display()))?;
        let want = if physics {
            format!("{expected}{expected_phys}")
        } else {
            expected.clone()
        };
        variants.push(run_variant(&elf, &plugin, &dir, &want, physics)?);
    }
    let core = variants.pop().ok_or("no core variant")?;
    let full = variants.pop().ok_or("no physics variant")?;
    let want = format!("{expected}{expected_phys}");
    let c = c_harness(&sysroot, &dir, [&blob, &pblob, &inputs], &want);
    Ok((full, core, c))
}

/// A C array of `bytes` named `name`, with its length.
fn c_array(name: &str, bytes: &[u8]) -> String {
    let mut s = format!("const uint8_t {name}[] __attribute__((aligned(4))) = {{");
    for (i, b) in bytes.iter().enumerate() {
        if i % 16 == 0 {
            s.push_str("\n ");
        }
        s.push_str(&format!(" {b},"));
    }
    s.push_str(&format!(
        "\n}};\nconst uint32_t {name}_len = {};\n",
        bytes.len()
    ));
    s
}

/// firmware-core-ffi as a staticlib for the MCU, the C test program built with
/// arm-none-eabi-gcc and linked with it, run under QEMU on the same blobs and inputs as
/// the Rust harness, every output compared bit for bit with the host's.
// TODO(issue 21): split (the xtask helper splits this file)
#[allow(clippy::too_many_lines)]
fn c_harness(
    sysroot: &Path,
    dir: &Path,
    [blob, pblob, inputs]: [&Path; 3],
    expected: &str,
) -> Result<String, String> {
    crate::setup::arm_gcc()?;
    let root = crate::root();
    let target_dir = root.join("target/ffi-thumb");
    let mut c = cross_cmd(sysroot, "cargo");
    c.current_dir(&root)
        .args([
            "rustc",
            "-p",
            "firmware-core-ffi",
            "--release",
            "--target",
            TARGET,
            "-Zbuild-std=core",
            "--crate-type",
            "staticlib",
            "--target-dir",
        ])
        .arg(&target_dir)
        // the Rust harness's profile: size-optimised, LTO, abort
        .env("CARGO_PROFILE_RELEASE_OPT_LEVEL", "s")
        .env("CARGO_PROFILE_RELEASE_LTO", "true")
        .env("CARGO_PROFILE_RELEASE_CODEGEN_UNITS", "1")
        .env("CARGO_PROFILE_RELEASE_PANIC", "abort");
    sh(&mut c)?;
    let lib = target_dir
        .join(TARGET)
        .join("release/libfirmware_core_ffi.a");
    let mut data = String::from("#include <stdint.h>\n");
    for (name, path) in [
        ("fc_test_blob", blob),
        ("fc_test_blob_phys", pblob),
        ("fc_test_inputs", inputs),
    ] {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        data.push_str(&c_array(name, &bytes));
    }
    let data_c = dir.join("c-data.c");
    std::fs::write(&data_c, data).map_err(|e| e.to_string())?;
    let src = root.join("firmware-core-ffi/c-test");
    let elf = dir.join("fc-c-test.elf");
    sh(Command::new("arm-none-eabi-gcc")
        .args([
            "-mcpu=cortex-m4",
            "-mthumb",
            "-mfloat-abi=hard",
            "-mfpu=fpv4-sp-d16",
            "-Os",
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-ffreestanding",
            "-nostdlib",
            "-ffunction-sections",
            "-fdata-sections",
            "-Wl,--gc-sections",
        ])
        .arg("-I")
        .arg(root.join("firmware-core-ffi/include"))
        .arg("-T")
        .arg(src.join("link.ld"))
        .arg(src.join("main.c"))
        .arg(src.join("startup.c"))
        .arg(&data_c)
        .arg(&lib)
        .arg("-lgcc")
        .arg("-o")
        .arg(&elf))?;
    let out = Command::new("timeout")
        .args([
            "60",
            "qemu-system-arm",
            "-machine",
            "mps2-an386",
            "-cpu",
            "cortex-m4",
            "-nographic",
            "-semihosting-config",
            "enable=on,target=native",
        ])
        .arg("-kernel")
        .arg(&elf)
        .output()
        .map_err(|e| format!("qemu-system-arm: {e}"))?;
    // SYS_WRITE0 output is QEMU's stderr (the Rust harness's SYS_WRITE goes to stdout)
    let stdout = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    if !out.status.success() {
        return Err(format!(
            "the C harness failed under QEMU ({}):\n{}",
            out.status,
            stdout.lines().rev().take(5).collect::<Vec<_>>().join("\n")
        ));
    }
    let got: Vec<&str> = stdout.lines().filter(|l| l.starts_with("vec ")).collect();
    let want: Vec<&str> = expected.lines().filter(|l| l.starts_with("vec ")).collect();
    let diffs = got.iter().zip(&want).filter(|(g, w)| g != w).count();
    if got.len() != want.len() || want.is_empty() || diffs > 0 {
        return Err(format!(
            "C harness: {} results, {} expected, {diffs} differ",
            got.len(),
            want.len()
        ));
    }
    // the program itself checks the codes and exits non-zero on a wrong one
    if !stdout.lines().any(|l| l.starts_with("refusals ")) {
        return Err("C harness: no refusal check printed".into());
    }
    let version = Command::new("arm-none-eabi-gcc")
        .arg("-dumpversion")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let size = Command::new("llvm-size")
        .arg("-A")
        .arg(&elf)
        .output()
        .map_err(|e| e.to_string())?;
    let flash: u64 = String::from_utf8_lossy(&size.stdout)
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                [name, sz, _] if [".text", ".rodata"].contains(name) => sz.parse::<u64>().ok(),
                _ => None,
            }
        })
        .sum();
    Ok(format!(
        "C harness: {} compensated samples (3 methods; the PWL blob from `host-fit fit` and the physics blob from `host-fit diagnose --out`) through firmware_core.h (arm-none-eabi-gcc {version}, the firmware-core-ffi staticlib with `physics`) bit-identical to the host's f32 evaluation, as the Rust harness's; a truncated blob and one with a flipped version bit refused with FC_ERR_TRUNCATED and FC_ERR_CRC; the linked C program: {flash} bytes of .text + .rodata, test data included",
        want.len()
    ))
}

/// Run one ELF under QEMU with the counting plugin, compare, and measure.
// TODO(issue 21): split (the xtask helper splits this file)
#[allow(clippy::too_many_lines)]
fn run_variant(
    elf: &Path,
    plugin: &Path,
    dir: &Path,
    expected: &str,
    physics: bool,
) -> Result<Measured, String> {
    let nm = Command::new("llvm-nm")
        .arg("-C")
        .arg("--print-size")
        .arg(elf)
        .output()
        .map_err(|e| format!("llvm-nm: {e} (install llvm)"))?;
    let nm = String::from_utf8_lossy(&nm.stdout).into_owned();
    let addr = |sym: &str| {
        nm.lines()
            .find(|l| l.ends_with(&format!(" {sym}")))
            .and_then(|l| l.split_whitespace().next())
            .map(str::to_string)
    };
    let (start, stop) = (
        addr("fw_mark_start").ok_or("no fw_mark_start")?,
        addr("fw_mark_stop").ok_or("no fw_mark_stop")?,
    );
    let log = dir.join("plugin.log");
    let _ = std::fs::remove_file(&log);
    let out = Command::new("timeout")
        .args(["60", "qemu-system-arm", "-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-semihosting-config", "enable=on,target=native"])
        .arg("-plugin")
        .arg(format!("{},start=0x{start},stop=0x{stop}", plugin.display()))
        .args(["-d", "plugin", "-D"])
        .arg(&log)
        .arg("-kernel")
        .arg(elf)
        .output()
        .map_err(|e| format!("qemu-system-arm: {e} (install it: apt-get install -t bookworm-backports qemu-system-arm)"))?;
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "the firmware test failed under QEMU ({}):\n{stdout}{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    // bit for bit
    let got: Vec<&str> = stdout.lines().filter(|l| l.starts_with("vec ")).collect();
    let want: Vec<&str> = expected.lines().filter(|l| l.starts_with("vec ")).collect();
    if got.len() != want.len() || want.is_empty() {
        return Err(format!(
            "{} results from the target, {} expected",
            got.len(),
            want.len()
        ));
    }
    let diffs: Vec<String> = got
        .iter()
        .zip(&want)
        .filter(|(g, w)| g != w)
        .map(|(g, w)| format!("target {g}\n  host {w}"))
        .collect();
    if !diffs.is_empty() {
        return Err(format!(
            "{} of {} results differ from the host:\n{}",
            diffs.len(),
            want.len(),
            diffs.iter().take(8).cloned().collect::<Vec<_>>().join("\n")
        ));
    }
    let mut lines = vec![format!(
        "{} compensated samples (3 methods) bit-identical to the host's f32 evaluation",
        want.len()
    )];
    if !physics {
        if !stdout.lines().any(|l| l == "physics refused") {
            return Err("built without physics, the physics blob was not refused".into());
        }
        lines.push("the blob with physics terms is refused (Error::PhysicsNotBuiltIn)".into());
    }
    for (key, what) in [
        ("f64-departure ", "the PWL blob"),
        ("f64-departure-physics ", "the blob with physics terms"),
    ] {
        lines.extend(
            expected
                .lines()
                .filter_map(|l| l.strip_prefix(key))
                .map(|l| {
                    format!("f32 results vs the f64 evaluation of the same code, {what}: max {l} g")
                }),
        );
    }
    // counts
    let labels: Vec<String> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("measure "))
        .map(str::to_string)
        .collect();
    let counts: Vec<u64> = std::fs::read_to_string(&log)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.strip_prefix("icount "))
        .filter_map(|v| v.trim().parse().ok())
        .collect();
    if counts.len() != labels.len() {
        return Err(format!(
            "{} counted windows for {} labels",
            counts.len(),
            labels.len()
        ));
    }
    let icount: Vec<(String, u64)> = labels.into_iter().zip(counts).collect();
    let value = |key: &str| {
        stdout
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|v| v.trim().parse::<u64>().ok())
    };
    let (stack_decode, stack_compensate, state) = (
        value("stack decode "),
        value("stack compensate "),
        value("size compensator "),
    );
    for l in stdout.lines() {
        if let Some(v) = l.strip_prefix("stack decode ") {
            lines.push(format!(
                "maximum stack of blob decoding (painted stack): {v} bytes"
            ));
        } else if let Some(v) = l.strip_prefix("stack compensate ") {
            lines.push(format!("maximum stack of compensate, a temperature update included (painted stack): {v} bytes"));
        } else if let Some(v) = l.strip_prefix("size compensator ") {
            lines.push(format!("RAM of the compensator state (size_of::<FlashCompensator>): {v} bytes (target <= {BUDGET_STATE})"));
        } else if let Some(v) = l.strip_prefix("size blob ") {
            lines.push(format!(
                "RAM of a validated blob (size_of::<BlobView>; the tables stay in flash): {v} bytes"
            ));
        }
    }
    // sizes
    let size = Command::new("llvm-size")
        .arg("-A")
        .arg(elf)
        .output()
        .map_err(|e| e.to_string())?;
    let sizes: Vec<(String, u64)> = String::from_utf8_lossy(&size.stdout)
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                [name, sz, _]
                    if [".vector_table", ".text", ".rodata", ".data", ".bss"].contains(name) =>
                {
                    Some((name.to_string(), sz.parse().ok()?))
                }
                _ => None,
            }
        })
        .collect();
    let mut comp: Vec<(String, u64)> = Vec::new();
    let mut soft_double = Vec::new();
    for l in nm.lines() {
        let f: Vec<&str> = l.splitn(4, ' ').collect();
        let [_, sz, kind, name] = f.as_slice() else {
            continue;
        };
        if !["t", "T", "r", "R"].contains(kind) {
            continue;
        }
        let Ok(sz) = u64::from_str_radix(sz, 16) else {
            continue;
        };
        if [
            "__adddf3",
            "__subdf3",
            "__muldf3",
            "__divdf3",
            "__aeabi_dadd",
            "__aeabi_dmul",
            "__aeabi_ddiv",
            "__aeabi_dsub",
            "__extendsfdf2",
            "__truncdfsf2",
        ]
        .iter()
        .any(|d| name.contains(d))
        {
            soft_double.push(name.to_string());
        }
        let group = component(name);
        match comp.iter_mut().find(|c| c.0 == group) {
            Some(c) => c.1 += sz,
            None => comp.push((group, sz)),
        }
    }
    comp.sort_by_key(|c| std::cmp::Reverse(c.1));
    Ok(Measured {
        sizes,
        components: comp,
        icount,
        lines,
        soft_double,
        stack_decode,
        stack_compensate,
        state,
    })
}

/// Components counted as "compensation + blob decode" (the library); the rest is the
/// test harness, its runtime and its data.
const LIBRARY: [&str; 9] = [
    "other (core, runtime)",
    "firmware-core compensate",
    "firmware-core temperature tables",
    "firmware-core model (inverse)",
    "firmware-core blob validation (in place)",
    "firmware-core crc",
    "firmware-core other",
    "libm",
    "compiler_builtins",
];

fn component(sym: &str) -> String {
    let s = sym.trim_start_matches('<');
    // the harness's wrapper around BlobView::new, which LTO inlines into it
    if s.starts_with("fw_qemu_test::decode_once") {
        return "firmware-core blob validation (in place)".into();
    }
    // the library never formats: all of core::fmt is the harness's printing
    if s.contains("core::fmt") || s.contains("PadAdapter") {
        return "harness printing (core::fmt)".into();
    }
    if s.starts_with(".Lanon") {
        return "harness data (embedded blob, input table, strings)".into();
    }
    if [
        "__INTERRUPTS",
        "__EXCEPTIONS",
        "Reset",
        "__rustc",
        "core::panicking",
        "core::result::unwrap_failed",
        "core::option",
    ]
    .iter()
    .any(|p| s.starts_with(p))
    {
        return "harness runtime (cortex-m, semihosting)".into();
    }
    for (prefix, name) in [
        ("firmware_core::compensate", "firmware-core compensate"),
        (
            "firmware_core::temperature",
            "firmware-core temperature tables",
        ),
        ("firmware_core::model", "firmware-core model (inverse)"),
        (
            "firmware_core::blob",
            "firmware-core blob validation (in place)",
        ),
        ("firmware_core::crc", "firmware-core crc"),
        ("firmware_core", "firmware-core other"),
        ("libm", "libm"),
        ("compiler_builtins", "compiler_builtins"),
        ("fw_qemu_test", "test harness"),
        ("cortex_m", "harness runtime (cortex-m, semihosting)"),
        ("core::fmt", "harness printing (core::fmt)"),
    ] {
        if s.starts_with(prefix) {
            return name.to_string();
        }
    }
    if s.starts_with("__") || s.starts_with("memcpy") || s.starts_with("memset") {
        "compiler_builtins".into()
    } else {
        "other (core, runtime)".into()
    }
}

/// `cargo xtask embedded`: run the firmware test under QEMU, compare bit for bit,
/// measure, and write target/embedded/summary.md.
pub fn embedded(steps: &mut crate::Steps) {
    eprintln!("\n==> embedded: firmware-core under QEMU mps2-an386 (Cortex-M4F)");
    match run_embedded() {
        Ok((mut full, core, c)) => {
            let c_ok = c.is_ok();
            full.lines.push(match c {
                Ok(line) => line,
                Err(e) => {
                    eprintln!("xtask: embedded: {e}");
                    format!("C harness: FAILED ({})", e.lines().next().unwrap_or(""))
                }
            });
            if c_ok {
                steps.passed.push("embedded: C harness bit-exact".into());
            } else {
                steps.failed.push("embedded: C harness".into());
            }
            let md = format!(
                "## firmware-core on Cortex-M4F (QEMU mps2-an386), `cargo xtask embedded`\n\n\
                 The harness is built and run twice: with the `physics` feature (the default; \
                 the blob from `host-fit diagnose` is compensated too) and without it \
                 (`default-features = false`, for units calibrated without in-flight terms).\n\n\
                 ### With the `physics` feature\n\n{}\n### Without the `physics` feature\n\n{}",
                summary(&full, true),
                summary(&core, false)
            );
            let out = crate::root().join("target/embedded");
            let _ = std::fs::create_dir_all(&out);
            let _ = std::fs::write(out.join("summary.md"), &md);
            println!("{md}");
            steps.passed.push("embedded (bit-exact under QEMU)".into());
            // every budget of both builds, all failures collected
            let mut missed = budgets(&full, "with physics");
            missed.extend(budgets(&core, "without physics"));
            if missed.is_empty() {
                steps.passed.push("embedded budgets".into());
            }
            for m in missed {
                eprintln!("xtask: embedded budget missed: {m}");
                steps.failed.push(format!("embedded budget: {m}"));
            }
        }
        Err(e) => {
            eprintln!("xtask: embedded: {e}");
            steps.failed.push("embedded".into());
        }
    }
}

/// The flash of compensation + blob validation: the library components.
fn library_bytes(m: &Measured) -> u64 {
    m.components
        .iter()
        .filter(|c| LIBRARY.contains(&c.0.as_str()))
        .map(|c| c.1)
        .sum()
}

/// Method 1's net instructions per sample.
fn m1_net(m: &Measured) -> Option<u64> {
    let get = |k: &str| m.icount.iter().find(|c| c.0 == k).map(|c| c.1);
    Some(get("sample_m1")?.saturating_sub(get("call_overhead")?))
}

/// Each budget this build misses, named with its measured value.
fn budgets(m: &Measured, build: &str) -> Vec<String> {
    let mut missed = Vec::new();
    let mut check = |name: &str, value: Option<u64>, limit: u64, unit: &str| match value {
        Some(v) if v <= limit => {}
        Some(v) => missed.push(format!("{name} ({build}): {v} {unit} > {limit} {unit}")),
        None => missed.push(format!("{name} ({build}): not measured")),
    };
    check("decode stack", m.stack_decode, BUDGET_DECODE_STACK, "bytes");
    check(
        "compensate stack",
        m.stack_compensate,
        BUDGET_COMPENSATE_STACK,
        "bytes",
    );
    check("compensator state", m.state, BUDGET_STATE, "bytes");
    check(
        "flash for compensation + blob validation",
        Some(library_bytes(m)),
        BUDGET_FLASH,
        "bytes",
    );
    check(
        "method 1 per sample (2.5x the floor of 18)",
        m1_net(m),
        BUDGET_M1,
        "instructions",
    );
    if !m.soft_double.is_empty() {
        missed.push(format!(
            "no soft-double routines ({build}): {}",
            m.soft_double.join(", ")
        ));
    }
    missed
}

fn summary(m: &Measured, physics: bool) -> String {
    let get = |k: &str| m.icount.iter().find(|c| c.0 == k).map(|c| c.1).unwrap_or(0);
    // a window around `compensate` holds the markers and the call itself (argument and
    // result marshalling): both are measured with a no-op of the same signature
    let base = get("call_overhead");
    let net = |k: &str| get(k).saturating_sub(if k == "decode" { get("empty") } else { base });
    let m1 = net("sample_m1");
    let mut s = String::new();
    for l in &m.lines {
        s.push_str(&format!("- {l}\n"));
    }
    s.push_str("\nInstructions executed (exact, TCG plugin; the call overhead, measured with a no-op of the same signature, subtracted):\n\n| operation | instructions | floor | multiple |\n|---|---|---|---|\n");
    s.push_str(&format!(
        "| method 1 per sample (cached N(T)) | {m1} | {M1_FLOOR} (9 mul, 6 add, 3 sub) | {:.1}x |\n",
        m1 as f64 / M1_FLOOR as f64
    ));
    for (k, name) in [
        ("sample_m2full", "method 2 per sample, full model"),
        ("sample_m2simp", "method 2 per sample, simplified"),
    ] {
        s.push_str(&format!(
            "| {name} | {} | 39 (a_hat 18, M a_hat + e 18, subtraction 3) | {:.1}x |\n",
            net(k),
            net(k) as f64 / 39.0
        ));
    }
    // with physics: + filters and offsets (rate, hysteresis, warm-up: 12 mul/add + 3
    // sub), the K2/asymmetry correction (6 mul, 3 add, 3 abs, 9 mul + 6 add + 3 sub)
    let phys_rows = if physics {
        &[
            (
                "sample_pm1",
                "method 1 per sample with the physics terms",
                18 + 15 + 30,
            ),
            (
                "sample_pm2full",
                "method 2 (full) per sample with the physics terms",
                39 + 15 + 30,
            ),
        ][..]
    } else {
        &[]
    };
    for &(k, name, floor) in phys_rows {
        s.push_str(&format!(
            "| {name} | {} | {floor} (the method's floor, the offsets 15, the K2/asymmetry correction 30) | {:.1}x |\n",
            net(k),
            net(k) as f64 / floor as f64
        ));
    }
    for (k, name) in [
        (
            "update_poly3",
            "temperature update, polynomial order 3 (+ one sample)",
        ),
        (
            "update_pwl5",
            "temperature update, PWL 5 breakpoints (+ one sample)",
        ),
    ] {
        s.push_str(&format!("| {name} | {} | | |\n", net(k)));
    }
    s.push_str(&format!(
        "| blob validation in place (the PWL blob through 5 stops, CRC included) | {} | | |\n",
        net("decode")
    ));
    s.push_str("\nFlash and RAM of the linked test binary (llvm-size -A):\n\n| section | bytes |\n|---|---|\n");
    for (n, v) in &m.sizes {
        s.push_str(&format!("| {n} | {v} |\n"));
    }
    s.push_str("\nBy component (llvm-nm symbol sizes, text + rodata; LTO inlines across crates, so inlined code counts where it landed):\n\n| component | bytes |\n|---|---|\n");
    for (n, v) in &m.components {
        s.push_str(&format!("| {n} | {v} |\n"));
    }
    let lib = library_bytes(m);
    let verdict = |ok: bool| if ok { "met" } else { "missed" };
    s.push_str(&format!(
        "\nCompensation + blob decode (the library components above: validation in place, no copy; compiler_builtins and unclassified core code counted in, as the worst case): **{lib} bytes** ({:.1} KiB; target <= 6 KiB: {}).\n",
        lib as f64 / 1024.0,
        verdict(lib <= BUDGET_FLASH)
    ));
    s.push_str(&format!(
        "\nBudgets (`cargo xtask embedded` fails on a miss): decode stack {} bytes (<= {BUDGET_DECODE_STACK}: {}), compensate stack {} bytes (<= {BUDGET_COMPENSATE_STACK}: {}), compensator state {} bytes (<= {BUDGET_STATE}: {}), flash {lib} bytes (<= {BUDGET_FLASH}: {}), method 1 {m1} instructions per sample (<= {BUDGET_M1}, 2.5x the floor: {}), soft-double routines: {}.\n",
        m.stack_decode.unwrap_or(0),
        verdict(m.stack_decode.is_some_and(|v| v <= BUDGET_DECODE_STACK)),
        m.stack_compensate.unwrap_or(0),
        verdict(m.stack_compensate.is_some_and(|v| v <= BUDGET_COMPENSATE_STACK)),
        m.state.unwrap_or(0),
        verdict(m.state.is_some_and(|v| v <= BUDGET_STATE)),
        verdict(lib <= BUDGET_FLASH),
        verdict(m1 <= BUDGET_M1),
        if m.soft_double.is_empty() { "none (met)" } else { "linked (missed)" },
    ));
    s.push_str(&format!(
        "\nSoft-double routines (__adddf3, __muldf3, __aeabi_d*, ...) in the binary: {}\n",
        if m.soft_double.is_empty() {
            "none".to_string()
        } else {
            m.soft_double.join(", ")
        }
    ));
    s
}
