//! Axes of the plots: a value range mapped to pixels (linear or log10), ticks at round
//! values labelled without spurious digits (never `-0`), category names thinned so they
//! never overlap, and an SI prefix that keeps tick labels short (µV rather than 0.000012 V).

/// A value range mapped onto a pixel span.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// Lowest value shown.
    pub lo: f64,
    /// Highest value shown.
    pub hi: f64,
    /// Pixel of `lo`.
    pub p0: f64,
    /// Pixel of `hi`.
    pub p1: f64,
    /// log10 scale.
    pub log: bool,
}

impl Scale {
    fn t(&self, v: f64) -> f64 {
        if self.log {
            v.max(f64::MIN_POSITIVE).log10()
        } else {
            v
        }
    }

    /// The pixel of value `v`.
    pub fn px(&self, v: f64) -> f64 {
        let (a, b) = (self.t(self.lo), self.t(self.hi));
        self.p0 + (self.t(v) - a) / (b - a) * (self.p1 - self.p0)
    }

    /// The value at pixel `p`.
    pub fn value(&self, p: f64) -> f64 {
        let (a, b) = (self.t(self.lo), self.t(self.hi));
        let t = a + (p - self.p0) / (self.p1 - self.p0) * (b - a);
        if self.log {
            10f64.powf(t)
        } else {
            t
        }
    }

    /// Pixels per unit of value (linear scales).
    pub fn span_px(&self) -> f64 {
        (self.p1 - self.p0).abs()
    }
}

/// The range of `vals` (finite ones) widened by `pad` of its width on each side; a
/// single value gets a range around it. `log`: positive values only, padded in decades.
pub fn padded_range(vals: impl Iterator<Item = f64>, pad: f64, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let w = (b - a).max(0.5);
        return (10f64.powf(a - w * pad), 10f64.powf(b + w * pad));
    }
    let w = hi - lo;
    let w = if w > 0.0 {
        w
    } else {
        (hi.abs() * 0.1).max(1e-12)
    };
    (lo - w * pad, hi + w * pad)
}

/// A round step (1, 2 or 5 times a power of ten) giving about `n` intervals over `w`.
pub fn nice_step(w: f64, n: f64) -> f64 {
    let raw = (w / n.max(1.0)).abs().max(f64::MIN_POSITIVE);
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    let f = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    f * p
}

/// Decimals that show a multiple of `step` exactly.
fn decimals(step: f64) -> usize {
    let mut d = 0;
    let mut s = step.abs();
    while d < 12 && (s - s.round()).abs() > 1e-6 * s.max(1e-300) {
        s *= 10.0;
        d += 1;
    }
    d
}

/// `v` with `d` decimals, `0` for a value that rounds to zero (never `-0.0`).
pub fn label(v: f64, d: usize) -> String {
    let s = format!("{v:.d$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        format!("{:.d$}", 0.0)
    } else {
        s
    }
}

/// Ticks of a linear scale: round values inside `lo..hi`, about one per `px_per_tick`
/// pixels of `len_px`, with their labels.
pub fn linear_ticks(lo: f64, hi: f64, len_px: f64, px_per_tick: f64) -> Vec<(f64, String)> {
    let step = nice_step(hi - lo, len_px / px_per_tick);
    let d = decimals(step);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            (v, label(v, d))
        })
        .collect()
}

/// Ticks of a linear scale of counted things (units, runs): as [`linear_ticks`], but
/// never a step below 1, so that every label is a whole number.
pub fn integer_ticks(lo: f64, hi: f64, len_px: f64, px_per_tick: f64) -> Vec<(f64, String)> {
    let step = nice_step(hi - lo, len_px / px_per_tick).max(1.0);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            (v, format!("{v:.0}"))
        })
        .collect()
}

/// The largest of 1, 2 or 5 times a power of ten at or below `v` (> 0).
pub fn round_down_125(v: f64) -> f64 {
    if !(v.is_finite() && v > 0.0) {
        return v;
    }
    let e = v.log10().floor();
    let p = 10f64.powf(e);
    let m = [5.0, 2.0, 1.0]
        .into_iter()
        .find(|m| m * p <= v * (1.0 + 1e-9))
        .unwrap_or(1.0);
    m * p
}

/// Ticks of a log10 scale over `len_px` pixels: every decade inside `lo..hi`, with 2 and
/// 5 times them where a decade has room for three labels (60 px), and always the lowest
/// of these inside the range, so that the lowest values shown are read off a labelled
/// tick (an axis from 0.012 mg shows 0.02 and 0.05, not only 0.1 and up).
pub fn log_ticks(lo: f64, hi: f64, len_px: f64) -> Vec<(f64, String)> {
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let per_decade = len_px / (hi.log10() - lo.log10()).max(1e-9);
    let all = per_decade >= 60.0;
    let mut out: Vec<(f64, String)> = Vec::new();
    for e in a..=b {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(e);
            let inside = v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9);
            // the lowest tick is kept whatever the room: it labels the bottom
            if inside && (all || m == 1.0 || out.is_empty()) {
                out.push((v, label(v, (-e).max(0) as usize)));
            }
        }
    }
    // a lowest 2 or 5 that would crowd the decade above it: one label is enough there
    if !all && out.len() > 1 && out[0].0 * 10.0 > out[1].0 * (1.0 + 1e-9) {
        let gap = len_px * (out[1].0.log10() - out[0].0.log10()) / (hi.log10() - lo.log10());
        if gap < 14.0 {
            out.remove(1);
        }
    }
    out
}

/// Which of `n` category names to label on `len_px` pixels, when each label needs
/// `label_px`: every k-th, k the smallest that leaves a gap between neighbours.
pub fn category_stride(n: usize, len_px: f64, label_px: f64) -> usize {
    if n == 0 {
        return 1;
    }
    let per = len_px / n as f64;
    ((label_px + 6.0) / per).ceil().max(1.0) as usize
}

/// The SI prefix for values up to `max_abs` in `unit`: (factor to multiply by, unit
/// with its prefix), e.g. 1.2e-5 V -> (1e6, "µV"); g's thousandth is mg.
pub fn prefixed(max_abs: f64, unit: &str) -> (f64, String) {
    let m = if max_abs.is_finite() && max_abs > 0.0 {
        max_abs
    } else {
        1.0
    };
    let (f, p) = if m >= 1.0 {
        (1.0, "")
    } else if m >= 1e-3 {
        (1e3, "m")
    } else if m >= 1e-6 {
        (1e6, "µ")
    } else {
        (1e9, "n")
    };
    (f, format!("{p}{unit}"))
}

/// Approximate width in pixels of `s` in a sans-serif font of `size` pixels (a generous
/// average, so that labels placed by it never collide).
pub fn text_px(s: &str, size: f64) -> f64 {
    s.chars()
        .map(|c| match c {
            'i' | 'l' | 'j' | '.' | ',' | ':' | ';' | '|' | '!' | '\'' | ' ' => 0.33,
            'm' | 'w' | 'M' | 'W' => 0.92,
            c if c.is_ascii_uppercase() || c.is_ascii_digit() => 0.68,
            _ => 0.6,
        })
        .sum::<f64>()
        * size
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counted_axes_have_whole_ticks() {
        // six units on a wide axis: linear ticks would fall at 0.5, 1.5, ...
        let t = integer_ticks(0.5, 6.5, 1200.0, 70.0);
        assert_eq!(
            t.iter().map(|x| x.1.as_str()).collect::<Vec<_>>(),
            ["1", "2", "3", "4", "5", "6"]
        );
        let t = integer_ticks(0.5, 100_000.5, 1200.0, 70.0);
        assert!(t.iter().all(|x| x.0.fract() == 0.0 && !x.1.contains('.')));
    }

    #[test]
    fn ticks_are_round_and_never_negative_zero() {
        let t = linear_ticks(-0.04, 2.7, 800.0, 80.0);
        let labels: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(labels.first(), Some(&"0.0"), "{labels:?}");
        assert!(labels.iter().all(|l| !l.starts_with("-0")), "{labels:?}");
        assert_eq!(label(-1e-17, 1), "0.0");
        assert_eq!(label(-0.04, 1), "0.0");
        assert_eq!(label(-0.06, 1), "-0.1");
        let t = linear_ticks(-12.0, 12.0, 300.0, 45.0);
        assert!(t.iter().any(|x| x.1 == "0") && t.iter().any(|x| x.1 == "-10"));
    }

    #[test]
    fn log_ticks_decades_and_scale_round_trip() {
        // little room: decades, and the lowest round value above the axis' foot (the
        // decade just above it, 13 px away, gives way)
        let t = log_ticks(0.004, 15.0, 150.0);
        let labels: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(labels, ["0.005", "0.1", "1", "10"]);
        let t = log_ticks(0.004, 15.0, 200.0);
        let labels: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(labels, ["0.005", "0.01", "0.1", "1", "10"]);
        // room for three a decade: 1, 2 and 5 times each
        let t = log_ticks(0.012, 15.0, 330.0);
        let labels: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(
            labels,
            ["0.02", "0.05", "0.1", "0.2", "0.5", "1", "2", "5", "10"]
        );
        assert_eq!(round_down_125(0.012), 0.01);
        assert_eq!(round_down_125(0.0049), 0.002);
        assert_eq!(round_down_125(7.0), 5.0);
        let s = Scale {
            lo: 0.001,
            hi: 100.0,
            p0: 300.0,
            p1: 20.0,
            log: true,
        };
        assert!((s.px(0.1) - 188.0).abs() < 1e-9);
        assert!((s.value(188.0) - 0.1).abs() < 1e-12);
    }

    #[test]
    fn prefixes_and_strides() {
        assert_eq!(prefixed(1.2e-5, "V"), (1e6, "µV".to_string()));
        assert_eq!(prefixed(0.006, "g"), (1e3, "mg".to_string()));
        assert_eq!(prefixed(3.0, "m/s2"), (1.0, "m/s2".to_string()));
        assert_eq!(category_stride(6, 400.0, 30.0), 1);
        assert_eq!(category_stride(1050, 1200.0, 40.0), 41);
    }
}
