//! The `output_unit` values of recording-format.md: the unit of the three output columns.
//! The model is linear, so the unit only labels the numbers, except `counts`, whose
//! integers are a digital sensor's own steps (the quantisation the diagnosis's floor
//! must count).
use firmware_core::blob::OutputUnit as Firmware;
use serde::{Deserialize, Serialize};

/// The unit of a recording's output columns (`# output_unit=`).
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum OutputUnit {
    /// Volts (`V`, the default).
    #[default]
    Volt,
    /// Millivolts (`mV`).
    Millivolt,
    /// Metres per second squared (`m/s2`, also written `m/s^2`).
    MetresPerS2,
    /// Standard gravities (`g`).
    G,
    /// Thousandths of g (`mg`).
    MilliG,
    /// A digital sensor's counts (`counts`): integers as read, or averages.
    Counts,
    /// Any other label: kept and reported once, the numbers used as they are.
    Other(String),
}

impl OutputUnit {
    /// The unit a `output_unit` value names (never an error: an unknown label is kept).
    /// The spellings are firmware-core's ([`Firmware::from_label`]), the one table both
    /// the reader and the blob use.
    pub fn parse(s: &str) -> OutputUnit {
        let s = s.trim();
        // firmware-core's enum is non_exhaustive: find the known unit that records as
        // the label's code, so no arm hides a unit added there
        let code = Firmware::from_label(s);
        [
            OutputUnit::Volt,
            OutputUnit::Millivolt,
            OutputUnit::MetresPerS2,
            OutputUnit::G,
            OutputUnit::MilliG,
            OutputUnit::Counts,
        ]
        .into_iter()
        .find(|u| u.in_blob() == code)
        .unwrap_or_else(|| OutputUnit::Other(s.to_string()))
    }

    /// The unit as the blob records it (byte 15).
    pub fn in_blob(&self) -> Firmware {
        match self {
            OutputUnit::Volt => Firmware::Volt,
            OutputUnit::Millivolt => Firmware::MilliVolt,
            OutputUnit::MetresPerS2 => Firmware::MetrePerSecond2,
            OutputUnit::G => Firmware::G,
            OutputUnit::MilliG => Firmware::MilliG,
            OutputUnit::Counts => Firmware::Counts,
            OutputUnit::Other(_) => Firmware::Other,
        }
    }

    /// The label as the format writes it.
    pub fn as_str(&self) -> &str {
        match self {
            OutputUnit::Other(s) => s,
            known => known.in_blob().label(),
        }
    }

    /// One of the format's own values (not a kept label).
    pub fn is_known(&self) -> bool {
        !matches!(self, OutputUnit::Other(_))
    }
}

impl std::fmt::Display for OutputUnit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl TryFrom<String> for OutputUnit {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        Ok(OutputUnit::parse(&s))
    }
}

impl From<OutputUnit> for String {
    fn from(u: OutputUnit) -> String {
        u.as_str().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every value the format names, both spellings of m/s2, and a kept label.
    #[test]
    fn the_formats_values_parse_and_print_back() {
        for (s, u) in [
            ("V", OutputUnit::Volt),
            ("mV", OutputUnit::Millivolt),
            ("m/s2", OutputUnit::MetresPerS2),
            ("m/s^2", OutputUnit::MetresPerS2),
            ("g", OutputUnit::G),
            ("mg", OutputUnit::MilliG),
            ("counts", OutputUnit::Counts),
        ] {
            assert_eq!(OutputUnit::parse(s), u, "{s}");
            assert!(u.is_known());
            assert_eq!(OutputUnit::parse(u.as_str()), u);
        }
        let lsb = OutputUnit::parse("LSB");
        assert_eq!(lsb, OutputUnit::Other("LSB".into()));
        assert!(!lsb.is_known());
        assert_eq!(lsb.to_string(), "LSB");
    }
}
