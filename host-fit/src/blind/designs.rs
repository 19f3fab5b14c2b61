//! The designs of the classes beyond the catalogue: chamber and tilter programs that
//! identify what each concealed term needs. A product a_i a_j is zero at every
//! six-position (TP) dwell and a cube a_i^3 equals a_i there, so those cases visit the 12
//! edge diagonals at 45 degrees or the 8 cube corners besides TP1..TP6; a turn-on step
//! needs a power cycle at a constant temperature (a step between two stops is a change
//! with temperature), a temperature-sized warm-up power cycles far from T0, a rate term
//! positions visited while the chamber ramps. Every design visits -20, 10, 40, 10, -20 C
//! from a start at T0 = 20 C (10 C heating and cooling, -20 C twice cooling, so a drift
//! in time is not a temperature dependence or a hysteresis), rotates the order of the
//! positions from stop to stop (a settling is not one position's offset) and alternates
//! short and long dwells (a settling after each move differs between them).
use crate::data::positions::Positions;
use crate::simulate::program::Step;
use crate::simulate::SimConfig;

/// The reference temperature and the chamber's start, C.
pub const T0_C: f64 = 20.0;
/// The stops, C.
pub const STOPS_C: [f64; 5] = [-20.0, 10.0, 40.0, 10.0, -20.0];
/// Each stop's soak at the rest position before the positions, s.
pub const SOAK_S: f64 = 1200.0;
/// The chamber's ramps, C/min.
pub const RAMP_C_PER_MIN: f64 = 1.0;
/// A tilter move, s (rows `-`).
pub const MOVE_S: f64 = 10.0;
/// Dwells alternate between these, s, in the order of the visits.
pub const DWELLS_S: [f64; 2] = [40.0, 120.0];
/// A dwell while the chamber ramps (a turning design), s.
pub const RAMP_DWELL_S: f64 = 60.0;
/// A power-off, s (stated in the recording as `power_off_s`).
pub const OFF_S: f64 = 300.0;
/// Where the unit rests through ramps and soaks.
pub const REST: &str = "TP1";

/// The positions a design visits at each stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PositionSet {
    /// TP1..TP6 and PP1..PP6 (12, no positions file): the suite's own.
    Standard,
    /// TP1..TP6 and the 12 edge diagonals E01..E12 at 45 degrees (18).
    Edges,
    /// TP1..TP6, PP1..PP6 and the 12 edge diagonals (24).
    EdgesTilted,
    /// TP1..TP6, PP1..PP6 and the 8 cube corners C1..C8 (20).
    Corners,
}

/// When the unit is powered off and on again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Power {
    /// Only the recording's start.
    Steady,
    /// Once, half-way through the positions of the second stop (10 C, heating): a
    /// turn-on to turn-on test at one temperature.
    MidStop,
    /// After the soaks of the first and the third stop (-20 C and 40 C), before their
    /// positions: power-ons far from T0 on both sides.
    AtStops,
}

/// A design: positions, power cycles, and whether the tilter turns while the chamber
/// ramps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Design {
    /// The positions of every stop.
    pub positions: PositionSet,
    /// The power cycles.
    pub power: Power,
    /// The tilter turns through TP1..TP6, PP1..PP6 through each ramp too.
    pub turning: bool,
}

impl PositionSet {
    /// The design of a product term for a seed: seeds 1, 2, 3, 4 visit the edges (18),
    /// the edges and PP (24), the corners (20), the edges again.
    pub fn of_seed(seed: u64) -> PositionSet {
        match seed % 3 {
            1 => PositionSet::Edges,
            2 => PositionSet::EdgesTilted,
            _ => PositionSet::Corners,
        }
    }

    /// The positions defined beyond TP and PP (a positions file's rows).
    pub fn extra(self) -> Vec<(String, [f64; 3])> {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let c = 1.0 / 3f64.sqrt();
        let edges = || {
            let mut v = Vec::new();
            for (i, j) in [(0, 1), (0, 2), (1, 2)] {
                for (si, sj) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    let mut a = [0.0; 3];
                    a[i] = si * h;
                    a[j] = sj * h;
                    v.push((format!("E{:02}", v.len() + 1), a));
                }
            }
            v
        };
        match self {
            PositionSet::Standard => Vec::new(),
            PositionSet::Edges | PositionSet::EdgesTilted => edges(),
            PositionSet::Corners => (0..8)
                .map(|k| {
                    let s = |b: usize| if k >> b & 1 == 0 { c } else { -c };
                    (format!("C{}", k + 1), [s(0), s(1), s(2)])
                })
                .collect(),
        }
    }

    /// The names visited at each stop, in the order of the first stop.
    pub fn names(self) -> Vec<String> {
        let tp = (1..=6).map(|i| format!("TP{i}"));
        let pp = (1..=6).map(|i| format!("PP{i}"));
        let extra = self.extra().into_iter().map(|(n, _)| n);
        match self {
            PositionSet::Standard => tp.chain(pp).collect(),
            PositionSet::Edges => tp.chain(extra).collect(),
            PositionSet::EdgesTilted | PositionSet::Corners => tp.chain(pp).chain(extra).collect(),
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            PositionSet::Standard => "12 positions",
            PositionSet::Edges => "18 positions: TP and edges",
            PositionSet::EdgesTilted => "24 positions: TP, PP and edges",
            PositionSet::Corners => "20 positions: TP, PP and corners",
        }
    }
}

impl Design {
    /// The suite's positions, no power cycle, the tilter still through the ramps.
    pub const STANDARD: Design = Design {
        positions: PositionSet::Standard,
        power: Power::Steady,
        turning: false,
    };

    /// Its name in reports.
    pub fn name(self) -> String {
        let power = match self.power {
            Power::Steady => "",
            Power::MidStop => ", a power cycle mid-stop",
            Power::AtStops => ", power cycles at -20 and 40 C",
        };
        let turning = if self.turning {
            ", turning through ramps"
        } else {
            ""
        };
        format!("{}{power}{turning}", self.positions.name())
    }

    /// Put this design into `c`: its program, its positions and power cycles (stated in
    /// the recording), T0 and the chamber's start.
    pub fn apply(self, c: &mut SimConfig) {
        let (program, offs) = self.program();
        c.t0_c = T0_C;
        c.chamber.start_c = T0_C;
        c.schedule.stops = Vec::new();
        c.schedule.sweep = None;
        c.schedule.rest_position = REST.into();
        c.schedule.positions = self.positions.names();
        c.schedule.extra_positions = self.positions.extra();
        c.schedule.power_offs = offs;
        c.logger.power_off_metadata = true;
        c.schedule.program = program;
    }

    /// The chamber and tilter program, and the power-offs `[start_s, duration_s]`.
    pub fn program(self) -> (Vec<Step>, Vec<[f64; 2]>) {
        let mut p = Program {
            set: T0_C,
            ..Program::default()
        };
        let names = self.positions.names();
        for (k, &temp) in STOPS_C.iter().enumerate() {
            self.ramp(&mut p, temp);
            p.row(temp, REST);
            p.t += SOAK_S;
            if self.power == Power::AtStops && (k == 0 || k == 2) {
                p.power_cycle(temp);
            }
            // each stop starts further along the list: no position is always first
            let n = names.len();
            let order = (0..n).map(|j| &names[(j + k * 5) % n]);
            for (j, name) in order.enumerate() {
                p.row(temp, "-");
                p.t += MOVE_S;
                p.row(temp, name);
                p.t += DWELLS_S[j % 2];
                if self.power == Power::MidStop && k == 1 && j + 1 == n / 2 {
                    p.power_cycle(temp);
                }
            }
            p.row(temp, "-");
            p.t += MOVE_S;
        }
        let last = STOPS_C[STOPS_C.len() - 1];
        p.row(last, REST);
        p.t += RAMP_DWELL_S;
        p.row(last, REST);
        (p.steps, p.offs)
    }

    /// The chamber's ramp from the program's set point to `to`, from the unit's arrival
    /// at rest: the unit resting, or turning through TP and PP with dwells of
    /// [`RAMP_DWELL_S`].
    fn ramp(self, p: &mut Program, to: f64) {
        let from = p.set;
        let span = (to - from).abs() / RAMP_C_PER_MIN * 60.0;
        let start = p.t;
        let set_at = |t: f64| from + (to - from) * ((t - start) / span).clamp(0.0, 1.0);
        p.row(from, REST);
        if self.turning {
            let turn = PositionSet::Standard.names();
            p.t += MOVE_S;
            let mut j = 0;
            while p.t + 3.0 * MOVE_S + RAMP_DWELL_S <= start + span {
                p.row(set_at(p.t), "-");
                p.t += MOVE_S;
                p.row(set_at(p.t), &turn[j % turn.len()]);
                p.t += RAMP_DWELL_S;
                j += 1;
            }
            p.row(set_at(p.t), "-");
            p.t += MOVE_S;
            p.row(set_at(p.t), REST);
        }
        p.t = start + span;
        p.set = to;
    }
}

/// A program being written: its rows, the time and set point reached, the power-offs.
#[derive(Default)]
struct Program {
    steps: Vec<Step>,
    offs: Vec<[f64; 2]>,
    t: f64,
    set: f64,
}

impl Program {
    /// A row at the current time (the set point runs linearly to the next row's).
    fn row(&mut self, setpoint_c: f64, position: &str) {
        self.steps.push(Step {
            time_s: self.t,
            setpoint_c,
            position: position.into(),
        });
    }

    /// Off and on again while the tilter waits between two positions (rows `-`, so no
    /// dwell spans the power-off), the chamber holding `temp`.
    fn power_cycle(&mut self, temp: f64) {
        self.row(temp, "-");
        self.offs.push([self.t + MOVE_S, OFF_S]);
        self.t += OFF_S + 2.0 * MOVE_S;
    }
}

/// The positions a recording of `c` is read with: the built-in ones and the design's
/// (as the positions file `simulate --positions-out` writes; new positions calibrate).
pub fn positions_of(c: &SimConfig) -> Positions {
    let mut p = Positions::default();
    for (name, v) in &c.schedule.extra_positions {
        p.set(name, *v, None);
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The products, squares and cubes of the specific force at the design's positions,
    /// beside the linear model's columns (1, a_x, a_y, a_z): the rank they reach.
    fn rank(set: PositionSet) -> (usize, usize) {
        let pos = {
            let mut c = SimConfig::default();
            Design {
                positions: set,
                ..Design::STANDARD
            }
            .apply(&mut c);
            positions_of(&c)
        };
        let rows: Vec<Vec<f64>> = set
            .names()
            .iter()
            .map(|n| {
                let a = pos.vector(pos.index(n).unwrap());
                vec![
                    1.0,
                    a[0],
                    a[1],
                    a[2],
                    a[0] * a[1],
                    a[0] * a[2],
                    a[1] * a[2],
                    a[0] * a[0],
                    a[1] * a[1],
                    a[0].powi(3),
                ]
            })
            .collect();
        (matrix_rank(&rows), rows[0].len())
    }

    fn matrix_rank(rows: &[Vec<f64>]) -> usize {
        let mut m = rows.to_vec();
        let cols = m[0].len();
        let mut r = 0;
        for c in 0..cols {
            let Some(p) = (r..m.len()).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))
            else {
                break;
            };
            if m[p][c].abs() < 1e-9 {
                continue;
            }
            m.swap(r, p);
            for i in 0..m.len() {
                if i != r {
                    let f = m[i][c] / m[r][c];
                    for k in 0..cols {
                        m[i][k] -= f * m[r][k];
                    }
                }
            }
            r += 1;
        }
        r
    }

    /// Products, squares and a cube are separable from the linear model and from each
    /// other on every product design, and not on the six TP positions alone.
    #[test]
    fn the_product_designs_identify_products_squares_and_cubes() {
        for set in [
            PositionSet::Edges,
            PositionSet::EdgesTilted,
            PositionSet::Corners,
        ] {
            let (r, cols) = rank(set);
            assert_eq!(r, cols, "{}", set.name());
            assert_eq!(set.names().len(), set.name()[..2].parse::<usize>().unwrap());
        }
        let tp: Vec<Vec<f64>> = Positions::default().list[..6]
            .iter()
            .map(|p| {
                let a = p.a;
                vec![1.0, a[0], a[1], a[2], a[0] * a[1], a[0].powi(3)]
            })
            .collect();
        assert!(matrix_rank(&tp) < 6);
    }

    #[test]
    fn new_positions_are_unit_vectors_with_names_of_their_own() {
        for set in [PositionSet::Edges, PositionSet::Corners] {
            let extra = set.extra();
            for (n, a) in &extra {
                let len: f64 = a.iter().map(|x| x * x).sum();
                assert!((len - 1.0).abs() < 1e-12, "{n}");
                assert!(Positions::default().index(n).is_none(), "{n}");
            }
            for (i, x) in extra.iter().enumerate() {
                assert!(extra[i + 1..].iter().all(|y| y.0 != x.0 && y.1 != x.1));
            }
        }
    }

    /// The program's rows run forward in time, the power-offs fall inside `-` rows (no
    /// dwell spans one), and a turning design dwells while the set point ramps.
    #[test]
    fn programs_run_forward_and_power_off_between_positions() {
        for power in [Power::Steady, Power::MidStop, Power::AtStops] {
            let d = Design {
                power,
                turning: power == Power::Steady,
                ..Design::STANDARD
            };
            let (steps, offs) = d.program();
            assert!(steps.windows(2).all(|w| w[0].time_s < w[1].time_s));
            let want = match power {
                Power::Steady => 0,
                Power::MidStop => 1,
                Power::AtStops => 2,
            };
            assert_eq!(offs.len(), want);
            for [s, dur] in &offs {
                let row = steps.iter().rfind(|r| r.time_s <= *s).unwrap();
                let next = steps.iter().find(|r| r.time_s > *s).unwrap();
                assert_eq!(row.position, "-");
                assert!(next.time_s >= s + dur, "{s}+{dur}: {}", next.time_s);
            }
            let ramping_dwells = steps
                .windows(2)
                .filter(|w| w[0].position.starts_with("PP") && w[0].setpoint_c != w[1].setpoint_c)
                .count();
            assert_eq!(ramping_dwells > 0, d.turning, "{}", d.name());
        }
    }
}
