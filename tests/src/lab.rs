//! A lab's own recording, as a lab would bring it: the digital twin run with the lab's
//! position names (F1..F6 to calibrate, V1..V4 tilted to verify, with `role` in the
//! positions file), four stops, T0 = 25 C.
use std::path::{Path, PathBuf};

/// The lab's positions: name, unit vector, role.
pub const POSITIONS: [(&str, [f64; 3], &str); 10] = [
    ("F1", [0.0, 0.0, 1.0], "calibration"),
    ("F2", [0.0, -1.0, 0.0], "calibration"),
    ("F3", [0.0, 0.0, -1.0], "calibration"),
    ("F4", [0.0, 1.0, 0.0], "calibration"),
    ("F5", [-1.0, 0.0, 0.0], "calibration"),
    ("F6", [1.0, 0.0, 0.0], "calibration"),
    ("V1", [0.5, 0.5, FRAC_1_SQRT_2], "verification"),
    ("V2", [-0.5, 0.5, -FRAC_1_SQRT_2], "verification"),
    ("V3", [FRAC_1_SQRT_2, -0.5, 0.5], "verification"),
    ("V4", [-0.5, -FRAC_1_SQRT_2, 0.5], "verification"),
];

use std::f64::consts::FRAC_1_SQRT_2;

/// The lab's stops, C.
pub const STOPS: [f64; 4] = [-20.0, 5.0, 25.0, 50.0];

/// The unit's serial.
pub const UNIT: &str = "LAB-0007";

/// The twin's configuration (TOML) of the lab's test.
pub fn config(seed: u64) -> String {
    let names: Vec<String> = POSITIONS.iter().map(|p| format!("\"{}\"", p.0)).collect();
    let extra: Vec<String> = POSITIONS
        .iter()
        .map(|(n, a, _)| format!("[\"{n}\", [{:?}, {:?}, {:?}]]", a[0], a[1], a[2]))
        .collect();
    let stops: String = STOPS
        .iter()
        .map(|t| format!("\n[[schedule.stops]]\ntemp_c = {t}\nsoak_s = 2400.0\n"))
        .collect();
    format!(
        "seed = {seed}\nt0_c = 25.0\n\n[schedule]\nrate_hz = 1.0\ndwell_s = 60.0\nmove_s = 10.0\nrest_position = \"F1\"\npositions = [{}]\nextra_positions = [{}]\n{stops}\n[unit]\nserial = \"{UNIT}\"\n",
        names.join(", "),
        extra.join(", ")
    )
}

/// The positions file, with its `role` column.
pub fn positions_csv() -> String {
    let mut s = String::from("name,fx,fy,fz,role\n");
    for (n, a, role) in POSITIONS {
        s.push_str(&format!("{n},{},{},{},{role}\n", a[0], a[1], a[2]));
    }
    s
}

/// The lab's files in `dir`.
pub struct LabFiles {
    /// The recording (`simulate` of [`config`]).
    pub recording: PathBuf,
    /// The positions file.
    pub positions: PathBuf,
    /// The twin's truth (`simulate --truth`).
    pub truth: PathBuf,
}

/// Write the twin's configuration, run `host-fit simulate` on it (recording and truth)
/// and write the positions file, all in `dir` (created).
pub fn write(dir: &Path, seed: u64) -> LabFiles {
    std::fs::create_dir_all(dir).unwrap();
    let cfg = dir.join(format!("lab-{seed}.toml"));
    std::fs::write(&cfg, config(seed)).unwrap();
    let f = LabFiles {
        recording: dir.join(format!("lab-{seed}.csv")),
        positions: dir.join("positions.csv"),
        truth: dir.join(format!("truth-{seed}.json")),
    };
    std::fs::write(&f.positions, positions_csv()).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let (code, _, err) = crate::cli(&[
        "simulate",
        &s(&cfg),
        "--out",
        &s(&f.recording),
        "--truth",
        &s(&f.truth),
        "--force",
    ]);
    assert_eq!(code, 0, "{err}");
    f
}
