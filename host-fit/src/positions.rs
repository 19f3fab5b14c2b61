//! Positions: the built-in TP1..TP6 and PP1..PP6 (model.md section 1) and positions files.
use crate::error::{HostError, Result};
use std::path::Path;

/// A named orientation: the unit vector of specific force in unit axes.
#[derive(Debug, Clone, PartialEq)]
pub struct Position {
    /// Name as used in recordings.
    pub name: String,
    /// Unit vector (g).
    pub a: [f64; 3],
}

/// The set of known positions.
#[derive(Debug, Clone, PartialEq)]
pub struct Positions {
    /// All positions, built-in first, then those of a positions file.
    pub list: Vec<Position>,
}

/// The tilt of the verification positions, degrees.
pub const PP_TILT_DEG: f64 = 25.0;

impl Default for Positions {
    fn default() -> Self {
        let (s, c) = PP_TILT_DEG.to_radians().sin_cos();
        let builtin: [(&str, [f64; 3]); 12] = [
            ("TP1", [0.0, 0.0, 1.0]),
            ("TP2", [0.0, -1.0, 0.0]),
            ("TP3", [0.0, 0.0, -1.0]),
            ("TP4", [0.0, 1.0, 0.0]),
            ("TP5", [-1.0, 0.0, 0.0]),
            ("TP6", [1.0, 0.0, 0.0]),
            ("PP1", [s, 0.0, c]),
            ("PP2", [0.0, -c, s]),
            ("PP3", [-s, 0.0, -c]),
            ("PP4", [0.0, c, -s]),
            ("PP5", [-c, s, 0.0]),
            ("PP6", [c, -s, 0.0]),
        ];
        Positions {
            list: builtin
                .iter()
                .map(|(n, a)| Position {
                    name: n.to_string(),
                    a: *a,
                })
                .collect(),
        }
    }
}

impl Positions {
    /// Index of a position by exact name.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.list.iter().position(|p| p.name == name)
    }

    /// The vector of position `i`.
    pub fn vector(&self, i: usize) -> [f64; 3] {
        self.list.get(i).map(|p| p.a).unwrap_or([0.0; 3])
    }

    /// The name of position `i`.
    pub fn name(&self, i: usize) -> &str {
        self.list.get(i).map(|p| p.name.as_str()).unwrap_or("?")
    }

    /// Add or replace a position.
    pub fn set(&mut self, name: &str, a: [f64; 3]) {
        match self.index(name) {
            Some(i) => {
                if let Some(p) = self.list.get_mut(i) {
                    p.a = a;
                }
            }
            None => self.list.push(Position {
                name: name.to_string(),
                a,
            }),
        }
    }

    /// The built-ins plus a positions file (`name,fx,fy,fz`); returns the warnings.
    pub fn with_file(path: &Path) -> Result<(Positions, Vec<String>)> {
        let text = std::fs::read(path).map_err(|e| HostError::io(path, &e))?;
        let text =
            String::from_utf8(text).map_err(|_| HostError::in_file(path, "is not UTF-8 text"))?;
        Self::parse(path, &text)
    }

    /// Parse positions-file text (see [`Positions::with_file`]).
    pub fn parse(path: &Path, text: &str) -> Result<(Positions, Vec<String>)> {
        let mut pos = Positions::default();
        let mut warnings = Vec::new();
        let mut header: Option<[usize; 4]> = None;
        let mut n_rows = 0usize;
        for (line_no, line) in crate::io::data_lines(text) {
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let Some(cols) = header else {
                let idx =
                    crate::io::header_columns(path, line_no, line, &["name", "fx", "fy", "fz"])?;
                header = Some([idx[0], idx[1], idx[2], idx[3]]);
                continue;
            };
            let [ni, xi, yi, zi] = cols;
            let get = |k: usize, name: &str| -> Result<&str> {
                fields.get(k).copied().ok_or_else(|| {
                    HostError::at_field(path, line_no, name, "missing value (too few fields)")
                })
            };
            let name = get(ni, "name")?;
            if name.is_empty() || name == "-" {
                return Err(HostError::at_field(
                    path,
                    line_no,
                    "name",
                    "empty or `-` position name",
                ));
            }
            let mut v = [0.0; 3];
            for (slot, (k, fname)) in v.iter_mut().zip([(xi, "fx"), (yi, "fy"), (zi, "fz")]) {
                *slot = crate::io::number(path, line_no, fname, get(k, fname)?)?;
            }
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm == 0.0 || !norm.is_finite() {
                return Err(HostError::at(
                    path,
                    line_no,
                    format!("position `{name}` has a zero-length vector"),
                ));
            }
            if (norm - 1.0).abs() > 1e-6 {
                warnings.push(format!(
                    "{}:{line_no}: position `{name}` has length {norm:.9}; normalised to unit length",
                    path.display()
                ));
            }
            pos.set(name, v.map(|x| x / norm));
            n_rows += 1;
        }
        if header.is_none() {
            return Err(HostError::in_file(path, "no header line `name,fx,fy,fz`"));
        }
        if n_rows == 0 {
            warnings.push(format!("{}: no positions defined", path.display()));
        }
        Ok((pos, warnings))
    }
}
