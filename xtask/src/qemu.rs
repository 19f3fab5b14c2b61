//! QEMU mps2-an386 (Cortex-M4F): the firmware test binary built for it, the one command
//! line that runs an ELF under it (semihosting, optionally the instruction-count plugin),
//! and the bit-for-bit comparison of the target's `vec` lines with the host's.
use crate::embedded::Vectors;
use crate::measure::Build;
use crate::toolchain::{cross_cmd, TARGET};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The instruction-count plugin, built with the host's gcc into `dir`.
pub fn plugin(dir: &Path) -> Result<PathBuf, String> {
    let plugin = dir.join("icount.so");
    let src = crate::root().join("firmware-core/qemu-test/plugin/icount.c");
    crate::sh(
        Command::new("gcc")
            .args(["-O2", "-shared", "-fPIC", "-o"])
            .arg(&plugin)
            .arg(src),
    )?;
    Ok(plugin)
}

/// `firmware-core/qemu-test` built with the features of `build`, the test vectors
/// embedded; its ELF copied into `dir` (one target dir serves every build, as build-std
/// is shared, so each ELF is kept aside).
pub fn build_harness(
    sysroot: &Path,
    v: &Vectors,
    dir: &Path,
    build: Build,
) -> Result<PathBuf, String> {
    let crate_dir = crate::root().join("firmware-core/qemu-test");
    let target_dir = crate::root().join("target/qemu-test");
    let mut c = cross_cmd(sysroot, "cargo");
    c.current_dir(&crate_dir)
        .args(["build", "--release", "--target-dir"])
        .arg(&target_dir)
        .env("FW_TEST_BLOB", &v.blob)
        .env("FW_TEST_BLOB_PHYS", &v.physics_blob)
        .env("FW_TEST_BLOB_TERMS", &v.terms_blob)
        .env("FW_TEST_INPUTS", &v.inputs);
    if !build.features().is_empty() {
        c.args(["--features", build.features()]);
    }
    crate::sh(&mut c)?;
    let elf = dir.join(match build {
        Build::Terms => "fw-qemu-test-terms.elf",
        Build::Physics => "fw-qemu-test-physics.elf",
        Build::Core => "fw-qemu-test-core.elf",
    });
    std::fs::copy(target_dir.join(TARGET).join("release/fw-qemu-test"), &elf)
        .map_err(|e| format!("{}: {e}", elf.display()))?;
    Ok(elf)
}

/// The instruction-count plugin's settings: the window between two marker addresses
/// (hex, from llvm-nm), its counts written to `log`.
pub struct Counting<'a> {
    /// The plugin's shared object.
    pub plugin: &'a Path,
    /// Address of the marker that opens a window.
    pub start: &'a str,
    /// Address of the marker that closes it.
    pub stop: &'a str,
    /// Where the plugin writes one `icount N` line per window.
    pub log: &'a Path,
}

/// Run `elf` on the emulated board (60 s at most), counting instructions if asked.
pub fn run(elf: &Path, counting: Option<&Counting>) -> Result<Output, String> {
    let mut c = Command::new("timeout");
    c.args([
        "60",
        "qemu-system-arm",
        "-machine",
        "mps2-an386",
        "-cpu",
        "cortex-m4",
        "-nographic",
        "-semihosting-config",
        "enable=on,target=native",
    ]);
    if let Some(k) = counting {
        c.arg("-plugin")
            .arg(format!(
                "{},start=0x{},stop=0x{}",
                k.plugin.display(),
                k.start,
                k.stop
            ))
            .args(["-d", "plugin", "-D"])
            .arg(k.log);
    }
    c.arg("-kernel").arg(elf).output().map_err(|e| {
        format!(
            "qemu-system-arm: {e} (install it: apt-get install -t bookworm-backports qemu-system-arm)"
        )
    })
}

/// The `vec` lines of the target's output against the host's, bit for bit: how many
/// agree, or how many differ with the first few side by side.
pub fn compare(target: &str, host: &str) -> Result<usize, String> {
    let got: Vec<&str> = target.lines().filter(|l| l.starts_with("vec ")).collect();
    let want: Vec<&str> = host.lines().filter(|l| l.starts_with("vec ")).collect();
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
    if diffs.is_empty() {
        Ok(want.len())
    } else {
        Err(format!(
            "{} of {} results differ from the host:\n{}",
            diffs.len(),
            want.len(),
            diffs.iter().take(8).cloned().collect::<Vec<_>>().join("\n")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::compare;

    #[test]
    fn every_vec_line_must_agree_bit_for_bit() {
        let host = "vec a 0 3f800000 0 0 0\nvec a 1 3f800001 0 0 0\nf64-departure 1e-7\n";
        assert_eq!(
            compare(
                "done\nvec a 0 3f800000 0 0 0\nvec a 1 3f800001 0 0 0\n",
                host
            ),
            Ok(2)
        );
        let one_bit = compare("vec a 0 3f800000 0 0 0\nvec a 1 3f800000 0 0 0\n", host);
        assert!(one_bit.is_err_and(|e| e.starts_with("1 of 2 results differ")));
        let short = compare("vec a 0 3f800000 0 0 0\n", host);
        assert_eq!(short, Err("1 results from the target, 2 expected".into()));
        assert!(compare("", "").is_err(), "no result at all is no pass");
    }
}
