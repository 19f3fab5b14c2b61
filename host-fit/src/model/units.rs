//! The units of a model's parameters, typed: a term's coefficient is in the recording's
//! output unit per the units of what it multiplies (`V/g^2` for a K2 term, `V/C` for an
//! offset's bend, `V per C/s` for a rate term, and so for any product of factors), a
//! structural unknown in its own (s, C, rad ...). The text is made from the type, never
//! guessed from a name.
use std::fmt;

/// The unit of a quantity a term multiplies: one factor of a product.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Factor {
    /// Specific force, g.
    G,
    /// Temperature, or a difference of temperatures, C.
    C,
    /// Rate of temperature change, C/s.
    CPerS,
    /// Rate of temperature change, C/min.
    CPerMin,
    /// Time, s.
    S,
}

impl Factor {
    /// The factor's symbol.
    pub fn symbol(self) -> &'static str {
        match self {
            Factor::G => "g",
            Factor::C => "C",
            Factor::CPerS => "C/s",
            Factor::CPerMin => "C/min",
            Factor::S => "s",
        }
    }
}

/// A parameter's unit.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Unit {
    /// The recording's output unit per the product of these factors, each with its power
    /// (none: the output unit itself).
    Output(Vec<(Factor, u8)>),
    /// A relative change (of a scale factor): no unit.
    Relative,
    /// An angle, rad.
    Radian,
    /// Time, s.
    Second,
    /// Temperature, C.
    Celsius,
    /// The direction of the last temperature change: +1 heated, -1 cooled.
    Direction,
    /// A number of things (breakpoints).
    Count,
    /// A 1-based place in an order (a stop of the recording): no unit.
    Ordinal,
}

impl Unit {
    /// The output unit itself.
    pub fn output() -> Unit {
        Unit::Output(Vec::new())
    }

    /// The output unit per each of `factors` (power 1).
    pub fn output_per(factors: &[Factor]) -> Unit {
        Unit::Output(factors.iter().map(|f| (*f, 1)).collect())
    }

    /// The unit in words, `output_unit` standing for the recording's: a factor whose
    /// symbol is itself a ratio follows ` per ` (`V per C/s`), another a slash
    /// (`V/g^2`, `V/g/C`).
    pub fn text(&self, output_unit: &str) -> String {
        match self {
            Unit::Output(per) => {
                let mut s = output_unit.to_string();
                for (f, p) in per {
                    let sym = f.symbol();
                    s.push_str(if sym.contains('/') { " per " } else { "/" });
                    s.push_str(sym);
                    if *p > 1 {
                        s.push_str(&format!("^{p}"));
                    }
                }
                s
            }
            Unit::Relative => "relative".into(),
            Unit::Radian => "rad".into(),
            Unit::Second => "s".into(),
            Unit::Celsius => "C".into(),
            Unit::Direction => "+1 heated, -1 cooled".into(),
            Unit::Count => "count".into(),
            Unit::Ordinal => String::new(),
        }
    }

    /// The output unit a text of this unit names (`V` of `V per C/s`); None when the unit
    /// is not the output's, or `text` is not this unit's.
    pub fn output_unit_of<'t>(&self, text: &'t str) -> Option<&'t str> {
        match self {
            Unit::Output(_) => text.strip_suffix(self.text("").as_str()),
            Unit::Relative
            | Unit::Radian
            | Unit::Second
            | Unit::Celsius
            | Unit::Direction
            | Unit::Count
            | Unit::Ordinal => None,
        }
    }
}

/// A unit in the output unit `V`.
impl fmt::Display for Unit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text("V"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texts the JSON contract has always carried, now made from the types; and the
    /// output unit read back from each.
    #[test]
    fn units_read_as_the_contract_writes_them() {
        let cases = [
            (Unit::output_per(&[Factor::CPerS]), "mV per C/s"),
            (Unit::output(), "mV"),
            (Unit::output_per(&[Factor::G]), "mV/g"),
            (Unit::Output(vec![(Factor::G, 2)]), "mV/g^2"),
            (Unit::output_per(&[Factor::C]), "mV/C"),
            (Unit::output_per(&[Factor::G, Factor::C]), "mV/g/C"),
            (
                Unit::output_per(&[Factor::G, Factor::CPerMin]),
                "mV/g per C/min",
            ),
        ];
        for (u, text) in cases {
            assert_eq!(u.text("mV"), text);
            assert_eq!(u.output_unit_of(text), Some("mV"), "{text}");
        }
        assert_eq!(Unit::Ordinal.text("V"), "");
        assert_eq!(Unit::Direction.text("V"), "+1 heated, -1 cooled");
        assert_eq!(Unit::Second.output_unit_of("s"), None);
    }
}
