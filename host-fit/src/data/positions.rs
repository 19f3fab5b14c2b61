//! Positions: the built-in TP1..TP6 and PP1..PP6 (model.md section 1), positions files,
//! and each position's role (calibration or verification), decided here once.
use crate::data::fields;
use crate::error::{ErrorKind, HostError, Result};
use serde::Serialize;
use std::path::Path;

/// What a position's dwells are used for.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str")]
#[strum(ascii_case_insensitive)]
pub enum Role {
    /// Fitted: identification and temperature models (TP1..TP6 by default).
    #[strum(to_string = "calibration", serialize = "cal")]
    Calibration,
    /// Held out of every fit and used to judge it, formula (13) (PP1..PP6 by default).
    #[strum(to_string = "verification", serialize = "check")]
    Verification,
}

impl Role {
    /// The role a positions file's `role` column names (either case; `cal` and `check`
    /// for short).
    fn parse(s: &str) -> Option<Role> {
        s.parse().ok()
    }
}

/// A named orientation: the unit vector of specific force in unit axes.
#[derive(Debug, Clone, PartialEq)]
pub struct Position {
    /// Name as used in recordings.
    pub name: String,
    /// Unit vector (g); NaN while the orientation is unknown, so that a vector used
    /// before it was estimated can never pass for data.
    pub a: [f64; 3],
    /// What its dwells are used for.
    pub role: Role,
    /// False for a static pose of unknown orientation (an empty vector in a positions
    /// file): its vector must be estimated (`fit::orientation`) before it is used.
    pub known: bool,
    /// True when the vector was estimated from the data, not given.
    pub estimated: bool,
}

/// The set of known positions.
#[derive(Debug, Clone, PartialEq)]
pub struct Positions {
    /// All positions, built-in first, then those of a positions file.
    pub list: Vec<Position>,
}

/// A positions-file vector whose length is further than this from 1 is refused (a
/// vector in degrees, a typo), not normalised: stricter than recording-format.md, which
/// normalises every length with a warning. Within it, rounding of written-out
/// components: normalised with a warning, as the format says.
pub const MAX_LENGTH_ERROR: f64 = 0.01;

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
                .enumerate()
                .map(|(i, (n, a))| Position {
                    name: n.to_string(),
                    a: *a,
                    role: if i < 6 {
                        Role::Calibration
                    } else {
                        Role::Verification
                    },
                    known: true,
                    estimated: false,
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

    /// The vector of position `i` (NaN for a position of unknown orientation: check
    /// [`Positions::is_known`] or [`Positions::require_known`] first).
    pub fn vector(&self, i: usize) -> [f64; 3] {
        self.list.get(i).map(|p| p.a).unwrap_or([f64::NAN; 3])
    }

    /// Whether position `i` has a known (given or estimated) orientation.
    pub fn is_known(&self, i: usize) -> bool {
        self.list.get(i).is_some_and(|p| p.known)
    }

    /// An error naming the first of `used` whose orientation is unknown, for code that
    /// needs vectors and was not given estimated ones.
    pub fn require_known(&self, used: impl IntoIterator<Item = usize>, what: &str) -> Result<()> {
        let mut unknown: Vec<&str> = used
            .into_iter()
            .filter(|i| !self.is_known(*i))
            .map(|i| self.name(i))
            .collect();
        unknown.sort_unstable();
        unknown.dedup();
        match unknown.first() {
            None => Ok(()),
            Some(first) => Err(HostError::new(ErrorKind::Insufficient, format!(
                "{what} needs the orientation of every position it uses; `{first}` ({} of unknown orientation in all) has none: estimate them first (fit::orientation)",
                unknown.len()
            ))),
        }
    }

    /// Give position `i` an (estimated) orientation, `a` a unit vector.
    pub fn set_estimated(&mut self, i: usize, a: [f64; 3]) {
        if let Some(p) = self.list.get_mut(i) {
            p.a = a;
            p.known = true;
            p.estimated = true;
        }
    }

    /// Whether position `i`'s vector was estimated from the data.
    pub fn is_estimated(&self, i: usize) -> bool {
        self.list.get(i).is_some_and(|p| p.estimated)
    }

    /// Make every position defined by a file unknown: its vector is not trusted (the
    /// command line's `--unknown-orientations`, for vectors estimated from the data).
    pub fn forget_vectors(&mut self, names: &[String]) {
        for p in &mut self.list {
            if names.contains(&p.name) {
                p.a = [f64::NAN; 3];
                p.known = false;
                p.estimated = false;
            }
        }
    }

    /// The name of position `i`.
    pub fn name(&self, i: usize) -> &str {
        self.list.get(i).map(|p| p.name.as_str()).unwrap_or("?")
    }

    /// Whether position `i` has `role`.
    pub fn has_role(&self, i: usize, role: Role) -> bool {
        self.list.get(i).is_some_and(|p| p.role == role)
    }

    /// The names of the positions with `role`.
    pub fn names_with(&self, role: Role) -> Vec<String> {
        self.list
            .iter()
            .filter(|p| p.role == role)
            .map(|p| p.name.clone())
            .collect()
    }

    /// Add or replace a position; a replaced position keeps its role unless `role` says.
    pub fn set(&mut self, name: &str, a: [f64; 3], role: Option<Role>) {
        self.put(name, Some(a), role);
    }

    /// Add or replace a static pose of unknown orientation.
    pub fn set_unknown(&mut self, name: &str, role: Option<Role>) {
        self.put(name, None, role);
    }

    fn put(&mut self, name: &str, a: Option<[f64; 3]>, role: Option<Role>) {
        let v = a.unwrap_or([f64::NAN; 3]);
        match self.index(name) {
            Some(i) => {
                if let Some(p) = self.list.get_mut(i) {
                    p.a = v;
                    p.known = a.is_some();
                    p.estimated = false;
                    p.role = role.unwrap_or(p.role);
                }
            }
            None => self.list.push(Position {
                name: name.to_string(),
                a: v,
                role: role.unwrap_or(Role::Calibration),
                known: a.is_some(),
                estimated: false,
            }),
        }
    }

    /// Make exactly the named positions the verification positions (the command line's
    /// `--positions-for-check`); every other position becomes a calibration position.
    pub fn set_verification(&mut self, names: &[String], option: &str) -> Result<()> {
        if let Some(bad) = names.iter().find(|n| self.index(n).is_none()) {
            return Err(HostError::new(
                ErrorKind::Invalid,
                format!(
                "unknown position `{bad}` in {option} (not built in and not in a positions file)"
            ),
            ));
        }
        for p in &mut self.list {
            p.role = if names.contains(&p.name) {
                Role::Verification
            } else {
                Role::Calibration
            };
        }
        Ok(())
    }

    /// The built-ins plus a positions file (`name,fx,fy,fz[,role]`; an empty vector,
    /// `W0001,,,`, is a static pose of unknown orientation); returns the warnings.
    pub fn with_file(path: &Path) -> Result<(Positions, Vec<String>)> {
        let text = std::fs::read(path).map_err(|e| HostError::io(path, &e))?;
        let text = String::from_utf8(text)
            .map_err(|_| HostError::in_file(ErrorKind::Malformed, path, "is not UTF-8 text"))?;
        Self::parse(path, &text)
    }

    /// Parse positions-file text (see [`Positions::with_file`]). The optional `role`
    /// column (`calibration` or `verification`) sets a position's role; a new position
    /// without it is a calibration position, a replaced built-in keeps its role.
    pub fn parse(path: &Path, text: &str) -> Result<(Positions, Vec<String>)> {
        let mut pos = Positions::default();
        let mut warnings = Vec::new();
        let mut header: Option<([usize; 4], Option<usize>)> = None;
        let mut n_rows = 0usize;
        for (line_no, line) in fields::data_lines(text) {
            let Some((cols, role_col)) = header else {
                let idx = fields::header_columns(path, line_no, line, &["name", "fx", "fy", "fz"])?;
                let role_col = line
                    .split(',')
                    .position(|c| c.trim().eq_ignore_ascii_case("role"));
                header = Some(([idx[0], idx[1], idx[2], idx[3]], role_col));
                continue;
            };
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let PositionRow {
                name,
                vector: v,
                role,
            } = parse_row(path, line_no, &fields, cols, role_col)?;
            let Some(v) = v else {
                pos.set_unknown(name, role);
                n_rows += 1;
                continue;
            };
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm == 0.0 || !norm.is_finite() {
                return Err(HostError::at(
                    ErrorKind::Malformed,
                    path,
                    line_no,
                    format!("position `{name}` has a zero-length vector"),
                ));
            }
            if (norm - 1.0).abs() > MAX_LENGTH_ERROR {
                return Err(HostError::at_field(
                    ErrorKind::Malformed,
                    path,
                    line_no,
                    "fx,fy,fz",
                    format!(
                        "position `{name}` has length {norm:.4}, more than {}% from 1: a unit vector of specific force (g) is expected (angles in degrees are not a vector)",
                        MAX_LENGTH_ERROR * 100.0
                    ),
                ));
            }
            if (norm - 1.0).abs() > 1e-6 {
                warnings.push(format!(
                    "{}:{line_no}: position `{name}` has length {norm:.9}; normalised to unit length",
                    path.display()
                ));
            }
            pos.set(name, v.map(|x| x / norm), role);
            n_rows += 1;
        }
        if header.is_none() {
            return Err(HostError::in_file(
                ErrorKind::Malformed,
                path,
                "no header line `name,fx,fy,fz`",
            ));
        }
        if n_rows == 0 {
            warnings.push(format!("{}: no positions defined", path.display()));
        }
        Ok((pos, warnings))
    }
}

/// One line of a positions file, checked.
struct PositionRow<'a> {
    /// The position's name.
    name: &'a str,
    /// Its vector of specific force, g; None for a pose whose orientation is unknown.
    vector: Option<[f64; 3]>,
    /// The role the line gives it, if any.
    role: Option<Role>,
}

fn parse_row<'a>(
    path: &Path,
    line_no: usize,
    fields: &[&'a str],
    [ni, xi, yi, zi]: [usize; 4],
    role_col: Option<usize>,
) -> Result<PositionRow<'a>> {
    let get = |k: usize, name: &str| -> Result<&'a str> {
        fields.get(k).copied().ok_or_else(|| {
            HostError::at_field(
                ErrorKind::Malformed,
                path,
                line_no,
                name,
                "missing value (too few fields)",
            )
        })
    };
    let name = get(ni, "name")?;
    if name.is_empty() || name == "-" {
        return Err(HostError::at_field(
            ErrorKind::Malformed,
            path,
            line_no,
            "name",
            "empty or `-` position name",
        ));
    }
    let cols = [(xi, "fx"), (yi, "fy"), (zi, "fz")];
    let raw: Vec<&str> = cols
        .iter()
        .map(|(k, f)| get(*k, f))
        .collect::<Result<_>>()?;
    // all three empty: a pose whose orientation is to be estimated; one or two empty is
    // a damaged line, not a convention
    let v = if raw.iter().all(|s| s.is_empty()) {
        None
    } else {
        let mut v = [0.0; 3];
        for (slot, (s, (_, fname))) in v.iter_mut().zip(raw.iter().zip(cols)) {
            *slot = fields::number(path, line_no, fname, s)?;
        }
        Some(v)
    };
    let role = match role_col
        .and_then(|k| fields.get(k))
        .filter(|s| !s.is_empty())
    {
        None => None,
        Some(s) => Some(Role::parse(s).ok_or_else(|| {
            HostError::at_field(
                ErrorKind::Malformed,
                path,
                line_no,
                "role",
                format!("`{s}` is not a role (calibration or verification)"),
            )
        })?),
    };
    Ok(PositionRow {
        name,
        vector: v,
        role,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whitespace_only_fields_are_empty_and_the_vector_stays_nan() {
        // found by the fuzzer: vertical tabs trim to empty fields
        let text = "name,fx,fy,fz\nZ_0,0.6,0,0.8\nIXISme,,\x0b, \x0b, 0.,090";
        let (p, _) = Positions::parse(Path::new("p.csv"), text).unwrap();
        let i = p.index("IXISme").unwrap();
        assert!(!p.is_known(i) && p.vector(i).iter().all(|v| v.is_nan()));
        let z = p.index("Z_0").unwrap();
        let n: f64 = p.vector(z).iter().map(|v| v * v).sum();
        assert!((n - 1.0).abs() < 1e-12);
    }

    #[test]
    fn an_empty_vector_is_a_pose_of_unknown_orientation() {
        let text = "name,fx,fy,fz,role\nW1,,,\nW2,0,0,1,verification\nTP1,,,,\n";
        let (p, _) = Positions::parse(Path::new("p.csv"), text).unwrap();
        let w1 = p.index("W1").unwrap();
        assert!(!p.is_known(w1) && p.vector(w1).iter().all(|v| v.is_nan()));
        assert!(p.has_role(w1, Role::Calibration));
        assert_eq!(p.vector(p.index("W2").unwrap()), [0.0, 0.0, 1.0]);
        // a vector far from unit length is refused (here 2, written for 1); one within
        // 1% is normalised
        let e = Positions::parse(Path::new("p.csv"), "name,fx,fy,fz\nW1,0,0,2\n").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Malformed);
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(2), Some("fx,fy,fz")),
            "{e}"
        );
        let (q, w) = Positions::parse(Path::new("p.csv"), "name,fx,fy,fz\nW1,0,0,1.009\n").unwrap();
        assert_eq!(q.vector(q.index("W1").unwrap()), [0.0, 0.0, 1.0]);
        assert!(w[0].contains("normalised"), "{w:?}");
        // a built-in may be declared unknown too
        let tp1 = p.index("TP1").unwrap();
        assert!(!p.is_known(tp1));
        let e = p.require_known([tp1, w1], "the fit").unwrap_err();
        // it names the first position it lacks
        assert_eq!(e.kind(), ErrorKind::Insufficient);
        assert!(e.message.contains("`TP1`"), "{e}");
        let mut q = p.clone();
        q.set_estimated(w1, [1.0, 0.0, 0.0]);
        assert!(q.is_known(w1) && q.is_estimated(w1));
        // half a vector is an error naming the field
        let e = Positions::parse(Path::new("p.csv"), "name,fx,fy,fz\nW1,1,,\n").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Malformed);
        assert_eq!((e.line, e.field.as_deref()), (Some(2), Some("fy")), "{e}");
    }
}
