//! A finding's parameters, typed: what each is ([`Quantity`]: a per-axis term's
//! coefficient, a time constant, a threshold ...), its value, its 1-sigma and its unit,
//! which comes from the quantity itself ([`Quantity::unit`]), never from its name.
//! Serialised into the JSON contract's three maps (`parameters`, `uncertainties`,
//! `units`, keyed by the quantity's name) and read back from them by serde.
use crate::model::params::Term;
use crate::model::units::Unit;
use firmware_core::model::AXES;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

/// What a finding's parameter is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// A per-axis term's coefficient (`r_x`, `k2_z`, `bend_u0_y` ...), in the term's
    /// unit.
    Term {
        /// Which term.
        term: Term,
        /// Axis (0 x, 1 y, 2 z).
        axis: usize,
    },
    /// `scale_asymmetry`'s `delta_i = c_i / K_ii`, relative.
    Delta {
        /// Axis.
        axis: usize,
    },
    /// `fixture_error`'s rotation angle 1 or 2, rad.
    Angle {
        /// 1 or 2.
        n: u8,
    },
    /// A time constant, s: a warm-up's, a lag's one or two poles (`pole` 1 or 2) for
    /// all axes, or a lag's per axis.
    Tau {
        /// 1 or 2.
        pole: u8,
        /// The axis of a lag per axis (None: all axes).
        axis: Option<usize>,
    },
    /// The rate estimator's time constant, s.
    RateTau,
    /// `hysteresis`: the change that sets the direction, C.
    Threshold,
    /// `hysteresis` as a play operator: the travel over which the state moves from one
    /// direction's value to the other's after a reversal, C.
    PlayWidth,
    /// `hysteresis`: the direction before the first change.
    InitialDirection,
    /// `temp_curvature`: where the bend sits, C.
    Knot,
    /// `temp_curvature`: the fine offset basis's breakpoints.
    Breakpoints,
    /// `fixture_error`: the stop the position changed at (1-based).
    FromStop,
}

impl Quantity {
    /// Its unit.
    pub fn unit(self) -> Unit {
        match self {
            Quantity::Term { term, .. } => term.unit(),
            Quantity::Delta { .. } => Unit::Relative,
            Quantity::Angle { .. } => Unit::Radian,
            Quantity::Tau { .. } | Quantity::RateTau => Unit::Second,
            Quantity::Threshold | Quantity::PlayWidth | Quantity::Knot => Unit::Celsius,
            Quantity::InitialDirection => Unit::Direction,
            Quantity::Breakpoints => Unit::Count,
            Quantity::FromStop => Unit::Ordinal,
        }
    }
}

/// Its name in the contract (`r_x`, `tau_s`, `tau_y_s`, `angle1_rad` ...).
impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ax = |i: usize| AXES.get(i).copied().unwrap_or("?");
        match *self {
            Quantity::Term { term, axis } => write!(f, "{}_{}", term.symbol(), ax(axis)),
            Quantity::Delta { axis } => write!(f, "delta_{}", ax(axis)),
            Quantity::Angle { n } => write!(f, "angle{n}_rad"),
            Quantity::Tau {
                pole: 1,
                axis: None,
            } => f.write_str("tau_s"),
            Quantity::Tau { pole, axis: None } => write!(f, "tau{pole}_s"),
            Quantity::Tau { axis: Some(i), .. } => write!(f, "tau_{}_s", ax(i)),
            Quantity::RateTau => f.write_str("rate_tau_s"),
            Quantity::Threshold => f.write_str("threshold_c"),
            Quantity::PlayWidth => f.write_str("play_width_c"),
            Quantity::InitialDirection => f.write_str("initial_direction"),
            Quantity::Knot => f.write_str("knot_c"),
            Quantity::Breakpoints => f.write_str("breakpoints"),
            Quantity::FromStop => f.write_str("from_stop"),
        }
    }
}

/// The quantity of a contract name.
impl FromStr for Quantity {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let axis = |a: &str| AXES.iter().position(|x| *x == a);
        let fixed = [
            Quantity::Tau {
                pole: 1,
                axis: None,
            },
            Quantity::Tau {
                pole: 2,
                axis: None,
            },
            Quantity::RateTau,
            Quantity::Threshold,
            Quantity::PlayWidth,
            Quantity::InitialDirection,
            Quantity::Knot,
            Quantity::Breakpoints,
            Quantity::FromStop,
            Quantity::Angle { n: 1 },
            Quantity::Angle { n: 2 },
        ];
        if let Some(q) = fixed.into_iter().find(|q| q.to_string() == s) {
            return Ok(q);
        }
        let per_axis = s
            .strip_prefix("tau_")
            .and_then(|r| r.strip_suffix("_s"))
            .and_then(axis)
            .map(|i| Quantity::Tau {
                pole: 1,
                axis: Some(i),
            })
            .or_else(|| {
                let (head, a) = s.rsplit_once('_')?;
                let i = axis(a)?;
                match head {
                    "delta" => Some(Quantity::Delta { axis: i }),
                    _ => Term::from_symbol(head).map(|term| Quantity::Term { term, axis: i }),
                }
            });
        per_axis.ok_or_else(|| format!("`{s}` is no parameter of a finding"))
    }
}

/// One parameter of a finding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameter {
    /// What it is.
    pub quantity: Quantity,
    /// Its value, in its unit.
    pub value: f64,
    /// Its 1-sigma (NaN where none is defined: a value taken from a grid).
    pub sigma: f64,
}

/// A finding's parameters, in the output unit of the recording they were fitted on.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameters {
    /// The recording's output unit, what [`Unit::Output`] is in.
    pub output_unit: String,
    /// The parameters, in their order of the model.
    pub list: Vec<Parameter>,
    /// The unit of a discovered term's coefficient (the output unit per the term's
    /// factors, as [`crate::model::library::LibTerm::coefficient_unit`] writes it): the
    /// term, not [`Term::Discovered`], knows its factors.
    pub term_unit: Option<String>,
}

impl Parameters {
    /// The parameter `q`, if the finding has it.
    pub fn get(&self, q: Quantity) -> Option<&Parameter> {
        self.list.iter().find(|p| p.quantity == q)
    }

    /// The parameters in the order of their names (the contract's).
    pub fn by_name(&self) -> Vec<(String, &Parameter)> {
        let mut v: Vec<(String, &Parameter)> = self
            .list
            .iter()
            .map(|p| (p.quantity.to_string(), p))
            .collect();
        v.sort_by(|a, b| a.0.cmp(&b.0));
        v
    }

    /// A parameter's unit in words.
    pub fn unit_text(&self, p: &Parameter) -> String {
        match (p.quantity, &self.term_unit) {
            (
                Quantity::Term {
                    term: Term::Discovered,
                    ..
                },
                Some(u),
            ) => u.clone(),
            _ => p.quantity.unit().text(&self.output_unit),
        }
    }
}

/// The contract's three maps, keyed by the parameters' names.
#[derive(Serialize, Deserialize)]
struct Maps {
    parameters: BTreeMap<String, Option<f64>>,
    uncertainties: BTreeMap<String, Option<f64>>,
    units: BTreeMap<String, String>,
}

impl Serialize for Parameters {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = Maps {
            parameters: BTreeMap::new(),
            uncertainties: BTreeMap::new(),
            units: BTreeMap::new(),
        };
        for (name, p) in self.by_name() {
            m.parameters.insert(name.clone(), Some(p.value));
            m.uncertainties.insert(name.clone(), Some(p.sigma));
            m.units.insert(name, self.unit_text(p));
        }
        m.serialize(s)
    }
}

/// Read back from the three maps: every name a [`Quantity`], every unit the quantity's
/// own in one output unit (a null value or 1-sigma, as JSON writes a NaN, is NaN).
impl<'de> Deserialize<'de> for Parameters {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let m = Maps::deserialize(d)?;
        let mut list = Vec::new();
        let mut output_unit: Option<String> = None;
        let mut term_unit: Option<String> = None;
        for (name, value) in &m.parameters {
            let quantity: Quantity = name.parse().map_err(D::Error::custom)?;
            let unit = quantity.unit();
            let text = m.units.get(name).map(String::as_str).unwrap_or("");
            let discovered = matches!(
                quantity,
                Quantity::Term {
                    term: Term::Discovered,
                    ..
                }
            );
            if discovered {
                term_unit = Some(text.to_string());
            }
            match (unit.output_unit_of(text), &output_unit) {
                _ if discovered => {}
                (Some(ou), None) => output_unit = Some(ou.to_string()),
                (Some(ou), Some(known)) if ou == known => {}
                (None, _) if unit.text("") == text => {}
                _ => {
                    return Err(D::Error::custom(format!(
                        "parameter {name}: unit `{text}` is not {}",
                        unit.text(output_unit.as_deref().unwrap_or("the output unit"))
                    )))
                }
            }
            list.push(Parameter {
                quantity,
                value: value.unwrap_or(f64::NAN),
                sigma: m
                    .uncertainties
                    .get(name)
                    .copied()
                    .flatten()
                    .unwrap_or(f64::NAN),
            });
        }
        Ok(Parameters {
            output_unit: output_unit.unwrap_or_default(),
            list,
            term_unit,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every quantity: its name parses back to it.
    #[test]
    fn every_quantity_round_trips_through_its_name() {
        let mut all = vec![
            Quantity::Angle { n: 1 },
            Quantity::Angle { n: 2 },
            Quantity::Tau {
                pole: 1,
                axis: None,
            },
            Quantity::Tau {
                pole: 2,
                axis: None,
            },
            Quantity::RateTau,
            Quantity::Threshold,
            Quantity::PlayWidth,
            Quantity::InitialDirection,
            Quantity::Knot,
            Quantity::Breakpoints,
            Quantity::FromStop,
        ];
        for axis in 0..3 {
            all.push(Quantity::Delta { axis });
            all.push(Quantity::Tau {
                pole: 1,
                axis: Some(axis),
            });
            all.extend(Term::ALL.map(|term| Quantity::Term { term, axis }));
        }
        for q in all {
            assert_eq!(q.to_string().parse::<Quantity>(), Ok(q), "{q}");
        }
        assert!("tau_w_s".parse::<Quantity>().is_err());
        assert!("unknown".parse::<Quantity>().is_err());
    }

    /// The maps the contract has carried: the same keys and unit texts, and read back to
    /// the same parameters (a NaN 1-sigma written as null).
    #[test]
    fn parameters_serialise_into_the_contracts_maps_and_back() {
        let p = Parameters {
            output_unit: "mV".into(),
            term_unit: Some("mV/g^3".into()),
            list: vec![
                Parameter {
                    quantity: Quantity::Term {
                        term: Term::Rate,
                        axis: 0,
                    },
                    value: 0.02,
                    sigma: 1e-4,
                },
                // a discovered term's coefficient, in its own unit
                Parameter {
                    quantity: Quantity::Term {
                        term: Term::Discovered,
                        axis: 1,
                    },
                    value: 3e-4,
                    sigma: 2e-6,
                },
                Parameter {
                    quantity: Quantity::RateTau,
                    value: 10.0,
                    sigma: f64::NAN,
                },
                Parameter {
                    quantity: Quantity::FromStop,
                    value: 3.0,
                    sigma: f64::NAN,
                },
            ],
        };
        let j = serde_json::to_value(&p).unwrap();
        assert_eq!(
            j,
            serde_json::json!({
                "parameters": {"coefficient_y": 3e-4, "from_stop": 3.0, "r_x": 0.02, "rate_tau_s": 10.0},
                "uncertainties": {"coefficient_y": 2e-6, "from_stop": null, "r_x": 1e-4, "rate_tau_s": null},
                "units": {"coefficient_y": "mV/g^3", "from_stop": "", "r_x": "mV per C/s", "rate_tau_s": "s"},
            })
        );
        let back: Parameters = serde_json::from_value(j).unwrap();
        assert_eq!(back.output_unit, "mV");
        assert_eq!(back.term_unit.as_deref(), Some("mV/g^3"));
        for (a, b) in back.list.iter().zip(p.by_name()) {
            assert_eq!(a.quantity, b.1.quantity);
            assert_eq!(a.value, b.1.value);
            assert!(a.sigma == b.1.sigma || (a.sigma.is_nan() && b.1.sigma.is_nan()));
        }
        let mut bad = serde_json::to_value(&p).unwrap();
        bad["units"]["r_x"] = "mV/g".into();
        assert!(serde_json::from_value::<Parameters>(bad).is_err());
    }
}
