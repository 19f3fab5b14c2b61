//! The C harness: firmware-core-ffi as a staticlib for the MCU, the C test program built
//! with arm-none-eabi-gcc and linked with it, run under QEMU on the same blobs and inputs
//! as the Rust harness, every output compared bit for bit with the host's.
use crate::embedded::Vectors;
use crate::toolchain::{cross_cmd, TARGET};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Build and run the C harness: its line for the report, or why it failed.
pub fn run(sysroot: &Path, dir: &Path, v: &Vectors) -> Result<String, String> {
    crate::setup::arm_gcc()?;
    let lib = staticlib(sysroot)?;
    let data_c = dir.join("c-data.c");
    std::fs::write(&data_c, data(v)?).map_err(|e| e.to_string())?;
    let elf = dir.join("fc-c-test.elf");
    compile(&data_c, &lib, &elf)?;
    let out = crate::qemu::run(&elf, None)?;
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
    let samples = crate::qemu::compare(&stdout, &v.expected(crate::measure::Build::Terms))
        .map_err(|e| format!("C harness: {e}"))?;
    // the program itself checks the codes and exits non-zero on a wrong one
    if !stdout.lines().any(|l| l.starts_with("refusals ")) {
        return Err("C harness: no refusal check printed".into());
    }
    let version = Command::new("arm-none-eabi-gcc")
        .arg("-dumpversion")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let flash: u64 = crate::measure::sections(&elf, &[".text", ".rodata"])?
        .iter()
        .map(|s| s.1)
        .sum();
    Ok(format!(
        "C harness: {samples} compensated samples (3 methods; the PWL blob from `host-fit fit`, the physics blob from `host-fit diagnose --out` and the golden blob with 8 discovered terms) through firmware_core.h (arm-none-eabi-gcc {version}, the firmware-core-ffi staticlib with `physics` and `terms`) bit-identical to the host's f32 evaluation, as the Rust harness's; a truncated blob and one with a flipped version bit refused with FC_ERR_TRUNCATED and FC_ERR_CRC; the linked C program: {flash} bytes of .text + .rodata, test data included"
    ))
}

/// firmware-core-ffi as a staticlib for the MCU, with the Rust harness's profile.
fn staticlib(sysroot: &Path) -> Result<PathBuf, String> {
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
    crate::sh(&mut c)?;
    Ok(target_dir
        .join(TARGET)
        .join("release/libfirmware_core_ffi.a"))
}

/// The blobs and inputs as C arrays.
fn data(v: &Vectors) -> Result<String, String> {
    let mut data = String::from("#include <stdint.h>\n");
    for (name, path) in [
        ("fc_test_blob", &v.blob),
        ("fc_test_blob_phys", &v.physics_blob),
        ("fc_test_blob_terms", &v.terms_blob),
        ("fc_test_inputs", &v.inputs),
    ] {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        data.push_str(&c_array(name, &bytes));
    }
    Ok(data)
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

/// The C program, its start-up and data linked with the staticlib, no C library.
fn compile(data_c: &Path, lib: &Path, elf: &Path) -> Result<(), String> {
    let root = crate::root();
    let src = root.join("firmware-core-ffi/c-test");
    crate::sh(
        Command::new("arm-none-eabi-gcc")
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
            .arg(data_c)
            .arg(lib)
            .arg("-lgcc")
            .arg("-o")
            .arg(elf),
    )
}

#[cfg(test)]
mod tests {
    use super::c_array;

    #[test]
    fn a_c_array_holds_every_byte_and_its_length() {
        let bytes: Vec<u8> = (0..17).collect();
        let c = c_array("x", &bytes);
        assert!(c.starts_with("const uint8_t x[] __attribute__((aligned(4))) = {\n  0, 1,"));
        assert!(c.contains(" 15,\n  16,\n};"), "{c}");
        assert!(c.ends_with("const uint32_t x_len = 17;\n"));
    }
}
