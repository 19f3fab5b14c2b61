//! Discovered terms as the blind suite reads them: the vocabulary of
//! physics-catalogue.md ("Beyond the catalogue: discovered terms") parsed from its text,
//! written here from the spec (not from the diagnosis's own types), so that the judge of
//! the term search does not share its code. Two terms are the same when they have the
//! same factors with the same powers, in any order, and their decays' time constants agree
//! within [`TAU_FACTOR`].
use std::fmt;

/// Two decays are the same term when their time constants agree within this factor (a
/// time constant is a nonlinear parameter found on a grid; twice or half the truth is
/// still the same physics, ten times is another).
pub const TAU_FACTOR: f64 = 2.0;

/// An event of the vocabulary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Event {
    /// The recording's start and every stated power-off's end.
    PowerOn,
    /// A new temperature stop begins.
    Stop,
    /// The unit was turned to another position.
    Position,
}

impl Event {
    fn parse(s: &str) -> Option<Event> {
        match s {
            "power_on" => Some(Event::PowerOn),
            "stop" => Some(Event::Stop),
            "position" => Some(Event::Position),
            _ => None,
        }
    }

    fn as_str(self) -> &'static str {
        match self {
            Event::PowerOn => "power_on",
            Event::Stop => "stop",
            Event::Position => "position",
        }
    }
}

/// One factor of a term (without its power).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub enum Factor {
    /// `a_x`, `a_y`, `a_z`: a specific-force component, g (0, 1, 2).
    Force(usize),
    /// `abs(a_x)` ...: its magnitude.
    AbsForce(usize),
    /// `dT`: temp_c - T0, C.
    DT,
    /// `dTdt`: the rate of temp_c, C/min.
    DTdt,
    /// `t`: hours since the recording's first row.
    T,
    /// `decay(EVENT,TAU)`, TAU in seconds.
    Decay(Event, f64),
    /// `step(EVENT)`.
    Step(Event),
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Factor {
    /// The vocabulary's order: force factors first (x, y, z), then dT, dTdt, t, then
    /// events.
    fn rank(self) -> (u8, usize) {
        match self {
            Factor::Force(i) => (0, i),
            Factor::AbsForce(i) => (1, i),
            Factor::DT => (2, 0),
            Factor::DTdt => (3, 0),
            Factor::T => (4, 0),
            Factor::Decay(e, _) => (5, e as usize),
            Factor::Step(e) => (6, e as usize),
        }
    }

    /// The same factor: decays of one event with time constants within [`TAU_FACTOR`].
    fn same(self, other: Factor) -> bool {
        match (self, other) {
            (Factor::Decay(e, a), Factor::Decay(f, b)) => {
                e == f && a > 0.0 && b > 0.0 && (a / b).max(b / a) <= TAU_FACTOR
            }
            (a, b) => a == b,
        }
    }

    fn parse(s: &str) -> Result<Factor, String> {
        let axis = |n: &str| AXES.iter().position(|a| *a == n);
        if let Some(i) = s.strip_prefix("a_").and_then(axis) {
            return Ok(Factor::Force(i));
        }
        if let Some(i) = s
            .strip_prefix("abs(a_")
            .and_then(|r| r.strip_suffix(')'))
            .and_then(axis)
        {
            return Ok(Factor::AbsForce(i));
        }
        match s {
            "dT" => return Ok(Factor::DT),
            "dTdt" => return Ok(Factor::DTdt),
            "t" => return Ok(Factor::T),
            _ => {}
        }
        let call = |name: &str| {
            s.strip_prefix(name)
                .and_then(|r| r.strip_prefix('('))
                .and_then(|r| r.strip_suffix(')'))
        };
        if let Some(arg) = call("step") {
            return Event::parse(arg.trim())
                .map(Factor::Step)
                .ok_or_else(|| format!("`{s}`: unknown event `{arg}`"));
        }
        if let Some(args) = call("decay") {
            let (ev, tau) = args
                .split_once(',')
                .ok_or_else(|| format!("`{s}`: decay(EVENT,TAU) needs two arguments"))?;
            let ev = Event::parse(ev.trim()).ok_or_else(|| format!("`{s}`: unknown event"))?;
            return Ok(Factor::Decay(ev, seconds(tau.trim())?));
        }
        Err(format!("`{s}` is not a factor of the vocabulary"))
    }
}

/// A time constant with its unit (`25s`, `12min`, `1.5h`) in seconds.
fn seconds(s: &str) -> Result<f64, String> {
    let (num, per) = [("min", 60.0), ("ms", 1e-3), ("s", 1.0), ("h", 3600.0)]
        .iter()
        .find_map(|(u, k)| s.strip_suffix(u).map(|n| (n, *k)))
        .ok_or_else(|| format!("time constant `{s}` has no unit (s, min, h)"))?;
    num.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(|v| v * per)
        .ok_or_else(|| format!("time constant `{s}` is not a positive number"))
}

impl fmt::Display for Factor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Factor::Force(i) => write!(f, "a_{}", AXES[*i]),
            Factor::AbsForce(i) => write!(f, "abs(a_{})", AXES[*i]),
            Factor::DT => write!(f, "dT"),
            Factor::DTdt => write!(f, "dTdt"),
            Factor::T => write!(f, "t"),
            Factor::Decay(e, tau) => write!(f, "decay({},{}s)", e.as_str(), tau.round()),
            Factor::Step(e) => write!(f, "step({})", e.as_str()),
        }
    }
}

/// A term: its factors with their powers, in the vocabulary's order.
#[derive(Debug, Clone, PartialEq)]
pub struct Term {
    factors: Vec<(Factor, u32)>,
}

impl Term {
    /// Parse a term's text (`a_x*a_y`, `a_x^3`, `dT*decay(power_on,20min)`); products in
    /// any order, a repeated factor counted as a power, spaces ignored.
    pub fn parse(text: &str) -> Result<Term, String> {
        let text: String = text.chars().filter(|c| !c.is_whitespace()).collect();
        let mut factors: Vec<(Factor, u32)> = Vec::new();
        for part in split_top(&text) {
            let (base, power) = match part.rsplit_once('^') {
                Some((b, p)) if !p.contains(')') => (
                    b,
                    p.parse::<u32>()
                        .ok()
                        .filter(|k| *k >= 1)
                        .ok_or_else(|| format!("`{part}`: a power is a whole number >= 1"))?,
                ),
                _ => (part, 1),
            };
            let f = Factor::parse(base)?;
            match factors.iter_mut().find(|(g, _)| g.same(f)) {
                Some((_, k)) => *k += power,
                None => factors.push((f, power)),
            }
        }
        if factors.is_empty() {
            return Err(format!("`{text}`: an empty term"));
        }
        factors.sort_by_key(|f| f.0.rank());
        Ok(Term { factors })
    }

    /// The same term: the same factors with the same powers (decays within
    /// [`TAU_FACTOR`]).
    pub fn same(&self, other: &Term) -> bool {
        self.factors.len() == other.factors.len()
            && self
                .factors
                .iter()
                .zip(&other.factors)
                .all(|((f, k), (g, l))| k == l && f.same(*g))
    }

    /// The number of factors counted with their powers (the vocabulary allows 3).
    pub fn degree(&self) -> u32 {
        self.factors.iter().map(|(_, k)| k).sum()
    }
}

impl fmt::Display for Term {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (n, (g, k)) in self.factors.iter().enumerate() {
            if n > 0 {
                write!(f, "*")?;
            }
            match k {
                1 => write!(f, "{g}")?,
                k => write!(f, "{g}^{k}")?,
            }
        }
        Ok(())
    }
}

/// `text` split at the `*` outside parentheses.
fn split_top(text: &str) -> Vec<&str> {
    let (mut depth, mut from, mut out) = (0i32, 0, Vec::new());
    for (i, c) in text.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            '*' if depth == 0 => {
                out.push(&text[from..i]);
                from = i + 1;
            }
            _ => {}
        }
    }
    out.push(&text[from..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(s: &str) -> Term {
        Term::parse(s).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn the_same_term_in_other_orders_and_powers() {
        assert!(t("a_x*a_y").same(&t("a_y * a_x")));
        assert!(t("a_x^2").same(&t("a_x*a_x")));
        assert!(t("a_x^3").same(&t("a_x^2*a_x")));
        assert!(t("dT*decay(power_on,20min)").same(&t("decay(power_on,1200s)*dT")));
        assert_eq!(
            t("decay(power_on,20min)*dT").to_string(),
            "dT*decay(power_on,1200s)"
        );
        assert_eq!(t("a_y*a_x").to_string(), "a_x*a_y");
        assert_eq!(t("a_z^2*dT").degree(), 3);
    }

    #[test]
    fn another_term_is_another_term() {
        assert!(!t("a_x*a_y").same(&t("a_x*a_z")));
        assert!(!t("a_x^2").same(&t("a_x")));
        assert!(!t("a_x^2").same(&t("abs(a_x)")));
        assert!(!t("a_x*t").same(&t("a_x*dT")));
        assert!(!t("step(power_on)").same(&t("step(stop)")));
        assert!(!t("decay(position,25s)").same(&t("decay(stop,25s)")));
        assert!(!t("dT*decay(power_on,20min)").same(&t("decay(power_on,20min)")));
    }

    #[test]
    fn decays_are_the_same_within_a_factor_of_two() {
        let truth = t("decay(position,30s)");
        assert!(t("decay(position,25s)").same(&truth));
        assert!(t("decay(position,1min)").same(&truth));
        assert!(!t("decay(position,61s)").same(&truth));
        assert!(!t("decay(position,14s)").same(&truth));
        assert!(t("decay(stop,0.5h)").same(&t("decay(stop,25min)")));
    }

    #[test]
    fn text_outside_the_vocabulary_is_an_error_not_a_panic() {
        for bad in [
            "",
            "a_w",
            "a_x^0",
            "a_x^-1",
            "decay(position)",
            "decay(position,25)",
            "decay(position,-5s)",
            "decay(handling,5s)",
            "step(power_on",
            "sqrt(a_x)",
            "a_x**a_y",
        ] {
            assert!(Term::parse(bad).is_err(), "`{bad}` parsed");
        }
    }
}
