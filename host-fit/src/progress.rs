//! Progress of long work, so that nothing long is silent: a bar on stderr when stderr is
//! a terminal, otherwise one line per tenth of the work (to the command's error stream).
use indicatif::{ProgressBar, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Run `work` (which calls its argument once per finished item, from any thread) on a
/// thread of its own while this one reports the progress of `total` items named `unit`
/// (`"cases"`); returns what `work` returns.
pub fn with_progress<T: Send>(
    what: &str,
    unit: &str,
    total: usize,
    err: &mut dyn Write,
    work: impl FnOnce(&(dyn Fn() + Sync)) -> T + Send,
) -> T {
    let done = AtomicUsize::new(0);
    let tick = || {
        done.fetch_add(1, Ordering::Relaxed);
    };
    let bar = std::io::stderr().is_terminal().then(|| {
        let b = ProgressBar::new(total as u64);
        b.set_style(
            ProgressStyle::with_template(&format!(
                "{{msg}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} (eta {{eta}})"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b.set_message(what.to_string());
        b
    });
    let start = Instant::now();
    let mut tenths_told = 0;
    std::thread::scope(|s| {
        let h = s.spawn(|| work(&tick));
        loop {
            let finished = h.is_finished();
            let n = done.load(Ordering::Relaxed).min(total);
            match &bar {
                Some(b) => b.set_position(n as u64),
                None => {
                    let tenths = (n * 10).checked_div(total).unwrap_or(10);
                    if tenths > tenths_told {
                        tenths_told = tenths;
                        let _ = writeln!(
                            err,
                            "{what}: {n} of {total} {unit} ({}%), {:.0} s",
                            n * 100 / total.max(1),
                            start.elapsed().as_secs_f64()
                        );
                    }
                }
            }
            if finished {
                break;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        match h.join() {
            Ok(v) => v,
            Err(p) => std::panic::resume_unwind(p),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::with_progress;

    #[test]
    fn one_line_per_tenth_without_a_terminal_and_the_result_returned() {
        let mut err = Vec::new();
        let sum = with_progress("adding", "items", 20, &mut err, |tick| {
            (0..20)
                .inspect(|_| {
                    std::thread::sleep(std::time::Duration::from_millis(15));
                    tick();
                })
                .sum::<usize>()
        });
        assert_eq!(sum, 190);
        let text = String::from_utf8(err).unwrap();
        if !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
            let lines: Vec<&str> = text.lines().collect();
            assert!(
                (2..=10).contains(&lines.len()),
                "one line per tenth reached:\n{text}"
            );
            assert!(
                lines
                    .last()
                    .unwrap()
                    .starts_with("adding: 20 of 20 items (100%)"),
                "{text}"
            );
        }
    }
}
