//! The four-stop twin of a lab's test (-30, 5, 25, 60 C; T0 = 25 C; 12 positions; seed 3), a
//! one-stop variant of it, and the recording with one dwell taken out, as a lab's
//! recordings come: for the verdicts and the missing-dwell tests.
use crate::{cli, s};
use std::path::{Path, PathBuf};

/// The twin's configuration (TOML).
pub const FOUR: &str = r#"seed = 3
t0_c = 25.0
[chamber]
start_c = 25.0
tau_air_s = 120.0
tau_case_s = 600.0
[sensor]
noise_c = 0.02
quantum_c = 0.0625
[schedule]
rate_hz = 1.0
dwell_s = 60.0
move_s = 10.0
rest_position = "TP1"
positions = ["TP1", "TP2", "TP3", "TP4", "TP5", "TP6", "PP1", "PP2", "PP3", "PP4", "PP5", "PP6"]
[[schedule.stops]]
temp_c = -30.0
soak_s = 2400.0
ramp_c_per_min = 1.0
[[schedule.stops]]
temp_c = 5.0
soak_s = 2400.0
ramp_c_per_min = 1.0
[[schedule.stops]]
temp_c = 25.0
soak_s = 2400.0
ramp_c_per_min = 1.0
[[schedule.stops]]
temp_c = 60.0
soak_s = 2400.0
ramp_c_per_min = 1.0
[unit]
serial = "LAB-1"
model = "paper"
interp = "poly"
noise_v = 2e-5
resolution_v = 1e-7
"#;

/// The same twin with one stop at -29.5 C, reached at the start (no ramp, short soak).
pub fn one_stop() -> String {
    let head = FOUR.split("[[schedule.stops]]").next().unwrap_or_default();
    let unit = FOUR.find("[unit]").map_or("", |i| &FOUR[i..]);
    format!(
        "{}[[schedule.stops]]\ntemp_c = -29.5\nsoak_s = 600.0\nramp_c_per_min = 1.0\n{unit}",
        head.replace("start_c = 25.0", "start_c = -29.5")
    )
}

/// `simulate` of `toml` as `dir/NAME.csv` (the test fails when it does not run).
pub fn simulate(dir: &Path, name: &str, toml: &str) -> PathBuf {
    let cfg = dir.join(format!("{name}.toml"));
    std::fs::write(&cfg, toml).expect("the twin's configuration written");
    let rec = dir.join(format!("{name}.csv"));
    let (code, _, err) = cli(&["simulate", s(&cfg), "--out", s(&rec)]);
    assert_eq!(code, 0, "{err}");
    rec
}

/// `rec` without the `nth` (from 0) run of rows at `position`, written as `out`: a dwell
/// the lab lost, the rows around it untouched (a gap in time where it was).
pub fn without_dwell(rec: &Path, position: &str, nth: usize, out: &Path) {
    let text = std::fs::read_to_string(rec).expect("the recording read");
    let (mut runs, mut prev, mut kept) = (0usize, String::new(), String::new());
    for line in text.lines() {
        let pos = line.split(',').nth(1).unwrap_or("");
        let data = !line.starts_with('#') && !line.starts_with("t_s");
        if data && pos == position && prev != position {
            runs += 1;
        }
        let drop = data && pos == position && runs == nth + 1;
        if data {
            prev = pos.to_string();
        }
        if !drop {
            kept.push_str(line);
            kept.push('\n');
        }
    }
    assert!(
        runs > nth,
        "{}: no dwell {nth} of {position}",
        rec.display()
    );
    std::fs::write(out, kept).expect("the recording written");
}
