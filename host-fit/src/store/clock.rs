//! Times of the record store: UTC, RFC 3339 with microseconds and a `Z`
//! (`2026-12-01T18:29:03.123456Z`), one fixed width so that text order is time order
//! (the store sorts and compares them as text); and the bounds of a reference period
//! given on the command line (a date or such a time).
use crate::error::{ErrorKind, HostError, Result};

/// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's `days_from_civil`,
/// exact for every year the store will meet).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The date of a day count since 1970-01-01 (the inverse of [`days_from_civil`]).
fn civil_from_days(z: i64) -> (i64, i64, i64) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// The RFC 3339 text of a time in microseconds since 1970-01-01 UTC.
pub fn rfc3339(micros: i64) -> String {
    let secs = micros.div_euclid(1_000_000);
    let us = micros.rem_euclid(1_000_000);
    let (y, m, d) = civil_from_days(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{us:06}Z",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

/// Now, in microseconds since 1970-01-01 UTC (0 for a clock set before 1970).
pub fn now_micros() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_micros()).unwrap_or(i64::MAX))
}

/// Now, as the store writes it.
pub fn now() -> String {
    rfc3339(now_micros())
}

/// Microseconds since 1970 of a store time or a bound given by hand: `YYYY-MM-DD`, or
/// `YYYY-MM-DDTHH:MM:SS[.frac]Z` (UTC only: a time the store compares must be UTC).
/// `end_of_day`: a date alone stands for its last microsecond (the end of a period).
pub fn parse(s: &str, end_of_day: bool) -> Option<i64> {
    let b = s.as_bytes();
    let num = |r: std::ops::Range<usize>| -> Option<i64> {
        let t = s.get(r)?;
        (!t.is_empty() && t.bytes().all(|c| c.is_ascii_digit()))
            .then(|| t.parse().ok())
            .flatten()
    };
    if b.len() < 10 || b[4] != b'-' || b[7] != b'-' {
        return None;
    }
    let (y, m, d) = (num(0..4)?, num(5..7)?, num(8..10)?);
    if !(1..=12).contains(&m) || !(1..=31).contains(&d) {
        return None;
    }
    let day = days_from_civil(y, m, d);
    // a day past the month's end (2026-02-30) comes back as another date: refused
    if civil_from_days(day) != (y, m, d) {
        return None;
    }
    if b.len() == 10 {
        let us = day * 86_400_000_000;
        return Some(if end_of_day {
            us + 86_400_000_000 - 1
        } else {
            us
        });
    }
    if b.len() < 20 || b[10] != b'T' || b[13] != b':' || b[16] != b':' || *b.last()? != b'Z' {
        return None;
    }
    let (hh, mm, ss) = (num(11..13)?, num(14..16)?, num(17..19)?);
    if hh > 23 || mm > 59 || ss > 60 {
        return None;
    }
    let frac = &s[19..s.len() - 1];
    let us = match frac.strip_prefix('.') {
        None if frac.is_empty() => 0,
        Some(f) if !f.is_empty() && f.len() <= 9 && f.bytes().all(|c| c.is_ascii_digit()) => {
            let mut v: i64 = f.parse().ok()?;
            for _ in f.len()..6 {
                v *= 10;
            }
            for _ in 6..f.len() {
                v /= 10;
            }
            v
        }
        _ => return None,
    };
    Some(((day * 86_400 + hh * 3600 + mm * 60 + ss) * 1_000_000) + us)
}

/// A bound of a reference period given as `option` on the command line, as a store time.
pub fn bound(option: &str, s: &str, end_of_day: bool) -> Result<String> {
    parse(s, end_of_day).map(rfc3339).ok_or_else(|| {
        HostError::new(
            ErrorKind::Invalid,
            format!(
                "{option} `{s}` is not a date (YYYY-MM-DD) nor a UTC time (YYYY-MM-DDTHH:MM:SSZ)"
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rfc3339_round_trips_and_sorts_as_text() {
        // 2000-02-29 12:34:56.000789 UTC, leap day of a century leap year
        let t = (days_from_civil(2000, 2, 29) * 86_400 + 45_296) * 1_000_000 + 789;
        assert_eq!(rfc3339(t), "2000-02-29T12:34:56.000789Z");
        assert_eq!(parse(&rfc3339(t), false), Some(t));
        assert_eq!(rfc3339(0), "1970-01-01T00:00:00.000000Z");
        assert_eq!(days_from_civil(1970, 1, 1), 0);
        for day in [-1000i64, 0, 365, 10_957, 20_000, 60_000] {
            let (y, m, d) = civil_from_days(day);
            assert_eq!(days_from_civil(y, m, d), day);
        }
        let (a, b) = (
            rfc3339(1_700_000_000_000_000),
            rfc3339(1_700_000_000_000_001),
        );
        assert!(a < b && a.len() == b.len());
    }

    #[test]
    fn bounds_by_hand() {
        let day = days_from_civil(2026, 3, 1) * 86_400_000_000;
        assert_eq!(parse("2026-03-01", false), Some(day));
        assert_eq!(parse("2026-03-01", true), Some(day + 86_400_000_000 - 1));
        assert_eq!(parse("2026-03-01T00:00:01Z", false), Some(day + 1_000_000));
        assert_eq!(
            parse("2026-03-01T00:00:01.5Z", false),
            Some(day + 1_500_000)
        );
        for bad in [
            "2026-02-30",
            "2026-13-01",
            "26-03-01",
            "2026-03-01T10:00:00",
            "2026-03-01T10:00:00+01:00",
            "2026-03-01T25:00:00Z",
            "yesterday",
        ] {
            assert_eq!(parse(bad, false), None, "{bad}");
        }
        let e = bound("--reference-from", "March", false).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Invalid);
        assert!(e.message.contains("--reference-from `March`"), "{e}");
    }
}
