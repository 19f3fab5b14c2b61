//! What one firmware ELF and its run measure: section sizes (llvm-size), symbol sizes by
//! component and the soft-double routines linked (llvm-nm), instructions per window (the
//! counting plugin's log), and the stack and RAM figures the harness prints.
use std::path::Path;
use std::process::Command;

/// The three builds of the firmware test: firmware-core's features.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Build {
    /// `physics` and `terms` (firmware-core's default): every blob compensated.
    Terms,
    /// `physics` without `terms`: the blob with discovered terms must be refused.
    Physics,
    /// Neither: the blobs with physics or discovered terms must be refused.
    Core,
}

impl Build {
    /// Every build, in the order they are run and reported.
    pub const ALL: [Build; 3] = [Build::Terms, Build::Physics, Build::Core];

    /// The harness's cargo features.
    pub fn features(self) -> &'static str {
        match self {
            Build::Terms => "physics terms",
            Build::Physics => "physics",
            Build::Core => "",
        }
    }

    /// As the report and a failure name it.
    pub fn label(self) -> &'static str {
        match self {
            Build::Terms => "with physics and terms",
            Build::Physics => "with physics, without terms",
            Build::Core => "without physics",
        }
    }

    /// Whether the build compensates the in-flight physics terms.
    pub fn physics(self) -> bool {
        matches!(self, Build::Terms | Build::Physics)
    }

    /// Whether the build compensates discovered terms.
    pub fn terms(self) -> bool {
        self == Build::Terms
    }
}

/// The measurements of one build of the firmware test.
pub struct Measured {
    /// Which build.
    pub build: Build,
    /// Compensated samples bit-identical to the host's.
    pub samples: usize,
    /// The host's largest departure of the f32 results from the f64 evaluation of the
    /// same code (g), by blob.
    pub departures: Vec<(&'static str, String)>,
    /// Sections of the linked binary and their sizes.
    pub sizes: Vec<(String, u64)>,
    /// Symbol bytes by component, largest first.
    pub components: Vec<(String, u64)>,
    /// Instructions per measured window, by the harness's label.
    pub icount: Vec<(String, u64)>,
    /// The soft-double routines linked (none is the budget).
    pub soft_double: Vec<String>,
    /// Painted stack of blob validation.
    pub stack_decode: Option<u64>,
    /// Painted stack of `compensate` with a temperature update.
    pub stack_compensate: Option<u64>,
    /// `size_of::<FlashCompensator>`.
    pub state: Option<u64>,
    /// `size_of::<BlobView>`.
    pub blob_view: Option<u64>,
}

impl Measured {
    /// Instructions of a window, if it was counted.
    pub fn count(&self, label: &str) -> Option<u64> {
        self.icount.iter().find(|c| c.0 == label).map(|c| c.1)
    }

    /// Net instructions of a window: a window around `compensate` holds the markers and
    /// the call itself (argument and result marshalling), both measured with a no-op of
    /// the same signature; blob validation's window is measured against an empty one.
    pub fn net(&self, label: &str) -> Option<u64> {
        let base = if label == "decode" {
            "empty"
        } else {
            "call_overhead"
        };
        Some(self.count(label)?.saturating_sub(self.count(base)?))
    }

    /// The flash of compensation + blob validation: the library components.
    pub fn library_bytes(&self) -> u64 {
        self.components
            .iter()
            .filter(|c| LIBRARY.contains(&c.0.as_str()))
            .map(|c| c.1)
            .sum()
    }
}

/// `llvm-size -A` of `elf`: the sections named, in the binary's order.
pub fn sections(elf: &Path, names: &[&str]) -> Result<Vec<(String, u64)>, String> {
    let size = Command::new("llvm-size")
        .arg("-A")
        .arg(elf)
        .output()
        .map_err(|e| format!("llvm-size: {e} (install llvm)"))?;
    Ok(String::from_utf8_lossy(&size.stdout)
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                [name, sz, _] if names.contains(name) => Some((name.to_string(), sz.parse().ok()?)),
                _ => None,
            }
        })
        .collect())
}

/// `llvm-nm -C --print-size` of `elf`.
pub fn symbols(elf: &Path) -> Result<String, String> {
    let nm = Command::new("llvm-nm")
        .arg("-C")
        .arg("--print-size")
        .arg(elf)
        .output()
        .map_err(|e| format!("llvm-nm: {e} (install llvm)"))?;
    Ok(String::from_utf8_lossy(&nm.stdout).into_owned())
}

/// The address (hex) of a symbol in llvm-nm's output.
pub fn address<'a>(nm: &'a str, sym: &str) -> Result<&'a str, String> {
    nm.lines()
        .find(|l| l.strip_suffix(sym).is_some_and(|p| p.ends_with(' ')))
        .and_then(|l| l.split_whitespace().next())
        .ok_or(format!("no {sym}"))
}

/// The soft-double routines, by the names they are linked under.
const SOFT_DOUBLE: [&str; 10] = [
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
];

/// Code and read-only data by component, largest first, and the soft-double routines.
pub fn components(nm: &str) -> (Vec<(String, u64)>, Vec<String>) {
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
        if SOFT_DOUBLE.iter().any(|d| name.contains(d)) {
            soft_double.push(name.to_string());
        }
        let group = component(name);
        match comp.iter_mut().find(|c| c.0 == group) {
            Some(c) => c.1 += sz,
            None => comp.push((group, sz)),
        }
    }
    comp.sort_by_key(|c| std::cmp::Reverse(c.1));
    (comp, soft_double)
}

/// The plugin's counts matched to the harness's `measure LABEL` lines, in order.
pub fn icounts(stdout: &str, log: &Path) -> Result<Vec<(String, u64)>, String> {
    let labels: Vec<String> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("measure "))
        .map(str::to_string)
        .collect();
    let counts: Vec<u64> = std::fs::read_to_string(log)
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
    Ok(labels.into_iter().zip(counts).collect())
}

/// The number the harness printed after `key` (`stack decode 472`).
pub fn value(stdout: &str, key: &str) -> Option<u64> {
    stdout
        .lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|v| v.trim().parse::<u64>().ok())
}

/// Components counted as "compensation + blob decode" (the library); the rest is the
/// test harness, its runtime and its data.
const LIBRARY: [&str; 10] = [
    "other (core, runtime)",
    "firmware-core compensate",
    "firmware-core discovered terms",
    "firmware-core temperature tables",
    "firmware-core model (inverse)",
    "firmware-core blob validation (in place)",
    "firmware-core crc",
    "firmware-core other",
    "libm",
    "compiler_builtins",
];

/// Symbol prefixes of the harness's runtime.
const RUNTIME: [&str; 7] = [
    "__INTERRUPTS",
    "__EXCEPTIONS",
    "Reset",
    "__rustc",
    "core::panicking",
    "core::result::unwrap_failed",
    "core::option",
];

/// Symbol prefixes and the component they belong to, the first match winning.
const PREFIXES: [(&str, &str); 12] = [
    ("firmware_core::compensate", "firmware-core compensate"),
    ("firmware_core::terms", "firmware-core discovered terms"),
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
];

/// The component a (demangled) symbol belongs to.
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
    if RUNTIME.iter().any(|p| s.starts_with(p)) {
        return "harness runtime (cortex-m, semihosting)".into();
    }
    if let Some((_, name)) = PREFIXES.iter().find(|(p, _)| s.starts_with(p)) {
        return name.to_string();
    }
    if s.starts_with("__") || s.starts_with("memcpy") || s.starts_with("memset") {
        "compiler_builtins".into()
    } else {
        "other (core, runtime)".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NM: &str = "\
00000400 00000010 T fw_mark_start
00000410 00000010 T fw_mark_stop
00000500 00000120 T firmware_core::compensate::FlashCompensator::sample
00000620 00000040 t <firmware_core::crc::Crc32 as core::default::Default>::default
00000700 00000030 T __aeabi_dmul
00000800 00000200 r .Lanon.1234.5
00000a00 00000008 d some_data
";

    #[test]
    fn symbols_are_grouped_and_soft_double_named() {
        let (comp, soft) = components(NM);
        assert_eq!(soft, ["__aeabi_dmul"]);
        let get = |k: &str| comp.iter().find(|c| c.0 == k).map(|c| c.1);
        assert_eq!(get("firmware-core compensate"), Some(0x120));
        assert_eq!(get("firmware-core crc"), Some(0x40));
        assert_eq!(get("compiler_builtins"), Some(0x30));
        assert_eq!(
            get("harness data (embedded blob, input table, strings)"),
            Some(0x200)
        );
        // data (`d`) is not code or read-only data; largest first
        assert_eq!(
            comp.iter().map(|c| c.1).sum::<u64>(),
            0x10 + 0x10 + 0x120 + 0x40 + 0x30 + 0x200
        );
        assert!(comp.windows(2).all(|w| w[0].1 >= w[1].1));
        assert_eq!(address(NM, "fw_mark_stop"), Ok("00000410"));
        assert!(
            address(NM, "mark_stop").is_err(),
            "a whole name, not a suffix"
        );
    }

    #[test]
    fn windows_are_net_of_their_overhead() {
        let m = Measured {
            build: Build::Physics,
            samples: 0,
            departures: Vec::new(),
            sizes: Vec::new(),
            components: vec![("libm".into(), 100), ("test harness".into(), 900)],
            icount: [
                ("empty", 5),
                ("call_overhead", 20),
                ("sample_m1", 63),
                ("decode", 905),
            ]
            .map(|(k, v)| (k.to_string(), v))
            .to_vec(),
            soft_double: Vec::new(),
            stack_decode: None,
            stack_compensate: None,
            state: None,
            blob_view: None,
        };
        assert_eq!(m.net("sample_m1"), Some(43));
        assert_eq!(m.net("decode"), Some(900));
        assert_eq!(m.net("sample_m2full"), None);
        assert_eq!(m.library_bytes(), 100);
        assert_eq!(
            value(
                "stack decode 472\nstack compensate 464\n",
                "stack compensate "
            ),
            Some(464)
        );
    }
}
