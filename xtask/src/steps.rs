//! The steps of a task: each printed as it starts and ends with its time, every failure
//! collected (a failed step never stops the next), and a final table of step, result and
//! time with the totals; the task exits non-zero at the end if any step failed.
use std::process::{Command, ExitCode};
use std::time::{Duration, Instant};

/// How one step ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// It did what it is for.
    Pass,
    /// It failed: what went wrong and what to do about it.
    Fail(String),
    /// It did not run: why.
    Skipped(String),
}

/// One step's name, outcome and time.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Step {
    /// What the step does, as the table names it.
    pub name: String,
    /// How it ended.
    pub outcome: Outcome,
    /// How long it ran (zero for a skipped step).
    pub time: Duration,
}

/// The steps of a task, in the order they ran.
pub struct Steps {
    steps: Vec<Step>,
    started: Instant,
    /// A line printed above the final table (which tier of the test ran).
    title: Option<String>,
}

impl Default for Steps {
    fn default() -> Self {
        Self::new()
    }
}

impl Steps {
    /// No step yet; the task's clock starts now.
    pub fn new() -> Self {
        Steps {
            steps: Vec::new(),
            started: Instant::now(),
            title: None,
        }
    }

    /// Say above the final table what ran (the test's tier), and print it now too.
    pub fn title(&mut self, title: &str) {
        eprintln!("{title}");
        self.title = Some(title.to_string());
    }

    /// Run a command as a step: it passes when the command exits with success.
    pub fn run(&mut self, name: &str, mut cmd: Command) -> bool {
        let line = command_line(&cmd);
        self.step(name, || match cmd.status() {
            Ok(s) if s.success() => Ok(()),
            Ok(s) => Err(format!("{s}; its output is above (`{line}`)")),
            Err(e) => Err(format!("could not start `{line}`: {e}")),
        })
        .is_ok()
    }

    /// Run `f` as a step, timed: an `Err` fails it with that message (which says what
    /// to do). The result is handed back for the steps that depend on it.
    pub fn step<T>(
        &mut self,
        name: &str,
        f: impl FnOnce() -> Result<T, String>,
    ) -> Result<T, String> {
        eprintln!("\n==> {name}");
        let t = Instant::now();
        let r = f();
        let outcome = match &r {
            Ok(_) => Outcome::Pass,
            Err(e) => Outcome::Fail(e.clone()),
        };
        self.record(name, outcome, t.elapsed());
        r
    }

    /// Run a preparation (an install, a download) that is a step of its own only when
    /// it fails: the steps it prepares are the ones the table lists.
    pub fn prepare<T>(&mut self, name: &str, f: impl FnOnce() -> Result<T, String>) -> Option<T> {
        let t = Instant::now();
        match f() {
            Ok(v) => Some(v),
            Err(e) => {
                self.record(name, Outcome::Fail(e), t.elapsed());
                None
            }
        }
    }

    /// A step that did not run, and why.
    pub fn skip(&mut self, name: &str, why: &str) {
        self.record(name, Outcome::Skipped(why.to_string()), Duration::ZERO);
    }

    /// A step measured elsewhere (or a verdict, taking no time of its own).
    pub fn record(&mut self, name: &str, outcome: Outcome, time: Duration) {
        match &outcome {
            Outcome::Pass => eprintln!("<== {name}: pass ({})", duration(time)),
            Outcome::Fail(why) => eprintln!("<== {name}: FAILED ({}): {why}", duration(time)),
            Outcome::Skipped(why) => eprintln!("<== {name}: skipped ({why})"),
        }
        self.steps.push(Step {
            name: name.to_string(),
            outcome,
            time,
        });
    }

    /// Whether any step failed.
    pub fn any_failed(&self) -> bool {
        self.steps
            .iter()
            .any(|s| matches!(s.outcome, Outcome::Fail(_)))
    }

    /// Print the table and the failures, and exit non-zero if any step failed.
    pub fn finish(self) -> ExitCode {
        if let Some(t) = &self.title {
            println!("\n{t}");
        }
        println!("\n{}", table(&self.steps, self.started.elapsed()));
        let failures = failures(&self.steps);
        if !failures.is_empty() {
            eprintln!("\n{failures}");
        }
        println!("{}", counts(&self.steps));
        if self.any_failed() {
            ExitCode::FAILURE
        } else {
            ExitCode::SUCCESS
        }
    }
}

/// A command as it would be typed: the program's file name and its arguments.
fn command_line(cmd: &Command) -> String {
    let program = std::path::Path::new(cmd.get_program())
        .file_name()
        .unwrap_or(cmd.get_program())
        .to_string_lossy()
        .into_owned();
    std::iter::once(program)
        .chain(cmd.get_args().map(|a| a.to_string_lossy().into_owned()))
        .collect::<Vec<_>>()
        .join(" ")
}

/// `0.4 s`, `59.9 s`, `1 min 05 s`.
pub fn duration(d: Duration) -> String {
    let tenths = (d.as_secs_f64() * 10.0).round() as u128;
    if tenths < 600 {
        format!("{}.{} s", tenths / 10, tenths % 10)
    } else {
        let whole = d.as_secs_f64().round() as u64;
        format!("{} min {:02} s", whole / 60, whole % 60)
    }
}

/// The result column: `pass`, `FAILED`, `skipped (why)`.
fn result(o: &Outcome) -> String {
    match o {
        Outcome::Pass => "pass".into(),
        Outcome::Fail(_) => "FAILED".into(),
        Outcome::Skipped(why) => format!("skipped ({why})"),
    }
}

/// The final table: one row per step (name, result, time) and the totals, the wall time
/// of the whole task included (it holds the preparations that are no step of their own).
pub fn table(steps: &[Step], wall: Duration) -> String {
    let rows: Vec<[String; 3]> = steps
        .iter()
        .map(|s| {
            let time = match s.outcome {
                Outcome::Skipped(_) => "-".to_string(),
                _ => duration(s.time),
            };
            [s.name.clone(), result(&s.outcome), time]
        })
        .collect();
    let head = ["step".to_string(), "result".into(), "time".into()];
    let sum: Duration = steps.iter().map(|s| s.time).sum();
    let total = [
        counts(steps).trim_start_matches("xtask: ").to_string(),
        String::new(),
        duration(sum),
    ];
    let all = || {
        std::iter::once(&head)
            .chain(&rows)
            .chain(std::iter::once(&total))
    };
    let width = |c: usize| all().map(|r| r[c].chars().count()).max().unwrap_or(0);
    let (w0, w1, w2) = (width(0), width(1), width(2));
    let line = |r: &[String; 3]| {
        format!("{:<w0$}  {:<w1$}  {:>w2$}", r[0], r[1], r[2])
            .trim_end()
            .to_string()
    };
    let rule = format!("{}  {}  {}", "-".repeat(w0), "-".repeat(w1), "-".repeat(w2));
    let mut out = vec![line(&head), rule.clone()];
    out.extend(rows.iter().map(line));
    out.push(rule);
    out.push(line(&total));
    out.push(format!("wall time of the task: {}", duration(wall)));
    out.join("\n")
}

/// Every failed step with what went wrong and what to do, or "" when none failed.
pub fn failures(steps: &[Step]) -> String {
    steps
        .iter()
        .filter_map(|s| match &s.outcome {
            Outcome::Fail(why) => Some(format!(
                "FAILED: {}\n  {}",
                s.name,
                why.replace('\n', "\n  ")
            )),
            _ => None,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The closing line: `xtask: N passed, N failed` (`, N skipped` when any was).
pub fn counts(steps: &[Step]) -> String {
    let n = |f: fn(&Outcome) -> bool| steps.iter().filter(|s| f(&s.outcome)).count();
    let (p, f, s) = (
        n(|o| matches!(o, Outcome::Pass)),
        n(|o| matches!(o, Outcome::Fail(_))),
        n(|o| matches!(o, Outcome::Skipped(_))),
    );
    if s == 0 {
        format!("xtask: {p} passed, {f} failed")
    } else {
        format!("xtask: {p} passed, {f} failed, {s} skipped")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steps() -> Steps {
        let mut s = Steps::new();
        s.record("fmt", Outcome::Pass, Duration::from_millis(800));
        s.record(
            "clippy (workspace)",
            Outcome::Fail("exit status: 101; its output is above".into()),
            Duration::from_secs(75),
        );
        s.skip("fuzz", "XTASK_FUZZ_SECONDS=0");
        s
    }

    #[test]
    fn the_table_has_a_row_per_step_and_the_totals() {
        let s = steps();
        let t = table(&s.steps, Duration::from_secs(80));
        let want = "\
step                           result                                time
-----------------------------  ------------------------------  ----------
fmt                            pass                                 0.8 s
clippy (workspace)             FAILED                          1 min 15 s
fuzz                           skipped (XTASK_FUZZ_SECONDS=0)           -
-----------------------------  ------------------------------  ----------
1 passed, 1 failed, 1 skipped                                  1 min 16 s
wall time of the task: 1 min 20 s";
        assert_eq!(t, want);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines[7], "wall time of the task: 1 min 20 s");
        // the columns line up: every time ends at the same column
        let end = lines[0].len();
        assert!(lines[1..7].iter().all(|l| l.len() == end), "{t}");
    }

    #[test]
    fn every_failure_is_kept_and_fails_the_task() {
        let mut s = steps();
        s.record("later step", Outcome::Pass, Duration::from_secs(1));
        // a failure before a passing step still fails the task
        assert!(s.any_failed());
        assert_eq!(
            failures(&s.steps),
            "FAILED: clippy (workspace)\n  exit status: 101; its output is above"
        );
        assert_eq!(counts(&s.steps), "xtask: 2 passed, 1 failed, 1 skipped");
        assert_eq!(s.finish(), ExitCode::FAILURE);

        let mut ok = Steps::new();
        ok.record("fmt", Outcome::Pass, Duration::ZERO);
        ok.skip("fuzz", "XTASK_FUZZ_SECONDS=0");
        assert!(!ok.any_failed());
        assert_eq!(counts(&ok.steps), "xtask: 1 passed, 0 failed, 1 skipped");
        assert_eq!(ok.finish(), ExitCode::SUCCESS);
    }

    #[test]
    fn a_step_keeps_its_error_and_a_preparation_shows_only_when_it_fails() {
        let mut s = Steps::new();
        let r: Result<u8, String> =
            s.step("build", || Err("no compiler: apt-get install gcc".into()));
        assert_eq!(r, Err("no compiler: apt-get install gcc".to_string()));
        assert_eq!(s.prepare("toolchain", || Ok::<_, String>(7)), Some(7));
        assert_eq!(
            s.prepare::<u8>("install chromium", || Err("not root".into())),
            None
        );
        let names: Vec<&str> = s.steps.iter().map(|x| x.name.as_str()).collect();
        assert_eq!(names, ["build", "install chromium"]);
        assert!(matches!(&s.steps[1].outcome, Outcome::Fail(w) if w == "not root"));
        let mut cmd = Command::new("/bin/false");
        cmd.arg("--flag");
        assert!(!s.run("false", cmd));
        assert!(matches!(&s.steps[2].outcome, Outcome::Fail(w) if w.contains("`false --flag`")));
    }

    #[test]
    fn durations_read_in_seconds_then_minutes() {
        assert_eq!(duration(Duration::from_millis(420)), "0.4 s");
        assert_eq!(duration(Duration::from_millis(59_940)), "59.9 s");
        assert_eq!(duration(Duration::from_millis(59_960)), "1 min 00 s");
        assert_eq!(duration(Duration::from_secs(65)), "1 min 05 s");
        assert_eq!(duration(Duration::from_secs(1191)), "19 min 51 s");
    }
}
