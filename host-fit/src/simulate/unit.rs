//! The simulated unit's true coefficients against temperature: the paper unit (its
//! Tables 1-2 and the rows designed in docs/paper-unit.md) or a configured table.
use crate::error::{ErrorKind, HostError, Result};
use crate::simulate::config::{Bend, Curvature, Interp, SimConfig, UnitModel};

/// The built-in paper unit: the paper's Tables 1-2 at -40, +20, +70 C, and at -10 and
/// +45 C the values designed in docs/paper-unit.md; the unit follows the quartic
/// through the five rows.
pub const PAPER_UNIT_TEMPS: [f64; 5] = [-40.0, -10.0, 20.0, 45.0, 70.0];
/// Rows of [`PAPER_UNIT_TEMPS`].
#[allow(clippy::excessive_precision)]
pub const PAPER_UNIT: [[f64; 12]; 5] = [
    [
        -0.5507426300,
        -0.5479068100,
        -0.5483220100,
        -0.0003893000,
        0.0160224100,
        -0.0127721400,
        -0.0007443200,
        -0.0143301900,
        -0.0002316100,
        0.0118121900,
        0.0005754400,
        0.0004126900,
    ],
    [
        -0.5506751496,
        -0.5482272612,
        -0.5484570453,
        -0.0004535921,
        0.0162078360,
        -0.0130007006,
        -0.0007065928,
        -0.0144998779,
        -0.0002932453,
        0.0080060119,
        -0.0022872747,
        -0.0023029858,
    ],
    [
        -0.5506086300,
        -0.5485489000,
        -0.5485922400,
        -0.0005174200,
        0.0163932800,
        -0.0132288100,
        -0.0006684100,
        -0.0146695700,
        -0.0003544100,
        0.0044908400,
        -0.0044229900,
        -0.0034709900,
    ],
    [
        -0.5512216709,
        -0.5491460324,
        -0.5495720313,
        -0.0004019488,
        0.0163136806,
        -0.0133683539,
        -0.0005945658,
        -0.0148917529,
        -0.0002294216,
        0.0039263478,
        -0.0056703701,
        -0.0026539220,
    ],
    [
        -0.5514026900,
        -0.5493305900,
        -0.5497968100,
        -0.0004282900,
        0.0165293700,
        -0.0136451900,
        -0.0006839600,
        -0.0147883000,
        -0.0002716700,
        0.0035977800,
        -0.0064360900,
        -0.0022373200,
    ],
];

/// The unit's true coefficients as a function of temperature.
#[derive(Debug, Clone)]
pub struct TrueUnit {
    temps: Vec<f64>,
    rows: Vec<[f64; 12]>,
    poly: bool,
    curvature: Option<Curvature>,
    bend: Option<Bend>,
    t0: f64,
}

impl TrueUnit {
    /// From the configuration.
    pub fn new(cfg: &SimConfig) -> Result<TrueUnit> {
        let (temps, rows) = match cfg.unit.model {
            UnitModel::Paper => (PAPER_UNIT_TEMPS.to_vec(), PAPER_UNIT.to_vec()),
            UnitModel::Table => (cfg.unit.temps_c.clone(), cfg.unit.coeffs.clone()),
        };
        if temps.is_empty() || temps.len() != rows.len() || temps.windows(2).any(|w| w[0] >= w[1]) {
            return Err(HostError::new(
                ErrorKind::Invalid,
                "unit.temps_c must be strictly increasing, one per row of unit.coeffs",
            ));
        }
        let poly = match cfg.unit.interp {
            Interp::Poly => true,
            Interp::Pwl => false,
        };
        Ok(TrueUnit {
            temps,
            rows,
            poly,
            curvature: cfg.effects.temp_curvature,
            bend: cfg.effects.temp_bend,
            t0: cfg.t0_c,
        })
    }

    /// The 12 coefficients at temperature `t`.
    pub fn coeffs(&self, t: f64) -> [f64; 12] {
        let n = self.temps.len();
        let mut out = [0.0; 12];
        if n == 1 {
            out = self.rows[0];
        } else if self.poly {
            // Lagrange form of the polynomial through all rows.
            for (j, (tj, row)) in self.temps.iter().zip(&self.rows).enumerate() {
                let mut l = 1.0;
                for (m, tm) in self.temps.iter().enumerate() {
                    if m != j {
                        l *= (t - tm) / (tj - tm);
                    }
                }
                for (o, v) in out.iter_mut().zip(row) {
                    *o += l * v;
                }
            }
        } else {
            let s = self.temps[1..n - 1].iter().filter(|b| t >= **b).count();
            let f = (t - self.temps[s]) / (self.temps[s + 1] - self.temps[s]);
            for c in 0..12 {
                out[c] = self.rows[s][c] + (self.rows[s + 1][c] - self.rows[s][c]) * f;
            }
        }
        if let Some(cv) = &self.curvature {
            let g = (std::f64::consts::TAU * (t - self.t0) / cv.period_c).sin();
            for i in 0..3 {
                out[9 + i] += cv.u0_v[i] * g;
                out[i] *= 1.0 + cv.k_rel[i] * g;
            }
        }
        if let Some(b) = &self.bend {
            let h = (t - b.knot_c).max(0.0);
            for i in 0..3 {
                out[9 + i] += b.u0_v_per_c[i] * h;
                out[i] *= 1.0 + b.k_rel_per_c[i] * h;
            }
        }
        out
    }
}
