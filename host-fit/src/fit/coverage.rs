//! Which positions each stop lacks: a position the schedule has at its other stops but
//! that has no static dwell at one, named with the stop, so that a lost dwell is said
//! (every command that fits warns) instead of silently thinning the data there.
use crate::data::recording::Recording;
use crate::data::stops::stops;
use std::collections::BTreeSet;

/// A position missing at stops.
#[derive(Debug, Clone, PartialEq)]
pub struct Missing {
    /// The position's name.
    pub position: String,
    /// Whether it is a verification position (else a calibration one).
    pub verification: bool,
    /// The stops (temperature, C) without a static dwell of it.
    pub missing_at_c: Vec<f64>,
    /// The stops with one.
    pub present_at_c: Vec<f64>,
}

impl Missing {
    /// The warning.
    pub fn text(&self) -> String {
        let list = |v: &[f64]| {
            v.iter()
                .map(|t| format!("{t:.1}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (role, effect) = if self.verification {
            ("verification", "it is not judged there")
        } else {
            ("calibration", "the fit there rests on the other positions")
        };
        format!(
            "{role} position {} has no static dwell at the {} C stop{} (it has at {} C): {effect}",
            self.position,
            list(&self.missing_at_c),
            if self.missing_at_c.len() > 1 { "s" } else { "" },
            list(&self.present_at_c)
        )
    }
}

/// The positions missing at some stop of `rec`. A stop is a run of static dwells at
/// one temperature ([`stops`]) holding at least half of the recording's regular
/// positions (those with static dwells at two stops or more); a regular position without
/// a static dwell at such a stop is missing there.
pub fn missing(rec: &Recording) -> Vec<Missing> {
    let groups: Vec<(f64, BTreeSet<usize>)> = stops(rec, &|_| true, 3.0)
        .into_iter()
        .map(|s| {
            let set = s
                .dwells
                .iter()
                .filter_map(|i| rec.dwells.get(*i).map(|d| d.position))
                .collect();
            (s.temp_c, set)
        })
        .collect();
    let mut count: std::collections::BTreeMap<usize, usize> = Default::default();
    for (_, set) in &groups {
        for p in set {
            *count.entry(*p).or_default() += 1;
        }
    }
    let regular: BTreeSet<usize> = count
        .iter()
        .filter(|(_, n)| **n >= 2)
        .map(|(p, _)| *p)
        .collect();
    let at_stops: Vec<&(f64, BTreeSet<usize>)> = groups
        .iter()
        .filter(|(_, set)| 2 * set.intersection(&regular).count() >= regular.len())
        .collect();
    regular
        .iter()
        .filter_map(|p| {
            let (has, lacks): (Vec<&(f64, BTreeSet<usize>)>, Vec<_>) = at_stops
                .iter()
                .copied()
                .partition(|(_, set)| set.contains(p));
            (!lacks.is_empty()).then(|| Missing {
                position: rec.positions.name(*p).to_string(),
                verification: rec
                    .positions
                    .has_role(*p, crate::data::positions::Role::Verification),
                missing_at_c: lacks.iter().map(|(t, _)| *t).collect(),
                present_at_c: has.iter().map(|(t, _)| *t).collect(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::positions::Positions;
    use std::fmt::Write;

    /// Every TP and PP position for 30 samples at each of three stops, `skip` (position,
    /// stop) left out.
    fn rec(skip: &[(&str, f64)]) -> Recording {
        let mut s = String::from("t_s,position,temp_c,ux_v,uy_v,uz_v\n");
        let mut t = 0.0;
        let pos = Positions::default();
        for stop in [-30.0, 20.0, 60.0] {
            for p in pos
                .list
                .iter()
                .filter(|p| !skip.contains(&(p.name.as_str(), stop)))
            {
                for _ in 0..30 {
                    let _ = writeln!(
                        s,
                        "{t},{},{stop:.1},{},{},{}",
                        p.name, p.a[0], p.a[1], p.a[2]
                    );
                    t += 1.0;
                }
            }
        }
        Recording::from_reader(std::path::Path::new("r.csv"), s.as_bytes(), pos).unwrap()
    }

    #[test]
    fn a_position_missing_at_a_stop_is_named_with_the_stop_and_its_role() {
        assert_eq!(missing(&rec(&[])), Vec::new());
        let m = missing(&rec(&[
            ("TP4", 20.0),
            ("PP3", 60.0),
            ("PP5", -30.0),
            ("PP5", 60.0),
        ]));
        let texts: Vec<String> = m.iter().map(Missing::text).collect();
        // PP5, at one stop only, is not one of the schedule's regular positions
        assert_eq!(
            texts,
            [
                "calibration position TP4 has no static dwell at the 20.0 C stop (it has at -30.0, 60.0 C): the fit there rests on the other positions",
                "verification position PP3 has no static dwell at the 60.0 C stop (it has at -30.0, 20.0 C): it is not judged there",
            ]
        );
    }
}
