//! The digital twin's recordings with varied truth and nuisances, for the tests of the
//! data-chosen model (none of them was used to tune it), and the plain least-squares
//! fit they are compared with.
use host_fit::data::positions::{Positions, Role};
use host_fit::data::recording::{Recording, MAX_DWELL_DRIFT_C};
use host_fit::simulate::{
    simulate, Curvature, Interp, SimConfig, TrueUnit, UnitModel, PAPER_UNIT, PAPER_UNIT_TEMPS,
};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use std::path::Path;

fn seeded(seed: u64) -> SimConfig {
    SimConfig {
        seed,
        ..SimConfig::default()
    }
}

/// A twin whose truth is the table `rows` at `temps`, interpolated by `interp`.
fn table(seed: u64, temps: Vec<f64>, rows: Vec<[f64; 12]>, interp: Interp) -> SimConfig {
    let mut c = seeded(seed);
    c.unit.model = UnitModel::Table;
    c.unit.temps_c = temps;
    c.unit.coeffs = rows;
    c.unit.interp = interp;
    c
}

/// The twins: (name, configuration).
pub fn all() -> Vec<(&'static str, SimConfig)> {
    let paper = TrueUnit::new(&SimConfig::default()).unwrap();
    let mut out = vec![
        ("paper unit, seed 1", seeded(1)),
        ("paper unit, seed 2", seeded(2)),
        ("paper unit, seed 3", seeded(3)),
    ];
    // a cubic: the polynomial through four of the paper unit's rows
    let idx = [0usize, 1, 3, 4];
    out.push((
        "cubic truth",
        table(
            4,
            idx.iter().map(|i| PAPER_UNIT_TEMPS[*i]).collect(),
            idx.iter().map(|i| PAPER_UNIT[*i]).collect(),
            Interp::Poly,
        ),
    ));
    // piecewise-linear with its kinks between the stops (-25, 5, 32 C)
    let kinks = [-40.0, -25.0, 5.0, 32.0, 70.0];
    let rows = kinks
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let mut r = paper.coeffs(*t);
            let s = if k % 2 == 1 { 1.0 } else { -1.0 };
            if (1..4).contains(&k) {
                for (c, v) in r.iter_mut().enumerate() {
                    *v += if c >= 9 { s * 1e-3 } else { s * 5e-4 * *v };
                }
            }
            r
        })
        .collect();
    out.push((
        "pwl truth, kinks off the stops",
        table(5, kinks.to_vec(), rows, Interp::Pwl),
    ));
    let mut wavy = seeded(6);
    wavy.effects.temp_curvature = Some(Curvature {
        u0_v: [3e-4, -2e-4, 2e-4],
        k_rel: [2e-4, 1e-4, -2e-4],
        period_c: 37.0,
    });
    out.push(("outside every family (sin, 37 C period)", wavy));
    let mut noisy = seeded(7);
    noisy.unit.noise_v *= 5.0;
    out.push(("paper unit, 5x the noise", noisy));
    let mut missing = seeded(8);
    missing.schedule.stops[1].positions = Some(
        [
            "TP1", "TP2", "TP3", "TP5", "TP6", "PP1", "PP2", "PP3", "PP4", "PP5", "PP6",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
    );
    out.push(("paper unit, TP4 missing at -10 C", missing));
    let mut ramps = seeded(9);
    for s in &mut ramps.schedule.stops {
        s.ramp_c_per_min = 3.0;
        s.soak_s = 900.0;
    }
    out.push(("paper unit, 3 C/min ramps, short soaks", ramps));
    out
}

/// The recording of a twin.
pub fn recording(name: &str, cfg: &SimConfig) -> (String, Recording) {
    let sim = simulate(cfg, |_| {}).unwrap();
    let rec =
        Recording::from_reader(Path::new(name), sim.csv.as_bytes(), Positions::default()).unwrap();
    (sim.csv, rec)
}

/// The plain least-squares fit of the cubic model over the TP dwells at their own
/// temperatures (every dwell whose temperature spans at most 0.5 C, its mean at its
/// mean temperature, unit weights), then formula (13) at every verification dwell
/// (dwell mean, f64): the largest |dg|, mg.
pub fn plain_cubic_max_dg_mg(rec: &Recording) -> f64 {
    let x = |t: f64| (t - rec.t0_c) / 50.0;
    let phi = |t: f64| [1.0, x(t), x(t).powi(2), x(t).powi(3)];
    let dwells: Vec<_> = rec
        .dwells
        .iter()
        .filter(|d| {
            rec.positions.has_role(d.position, Role::Calibration)
                && d.temp_span_c <= MAX_DWELL_DRIFT_C
        })
        .collect();
    let mut theta = Vec::new();
    for axis in 0..3 {
        let mut a = DMatrix::zeros(dwells.len(), 16);
        let mut b = DVector::zeros(dwells.len());
        for (r, d) in dwells.iter().enumerate() {
            let v = rec.positions.vector(d.position);
            let g = [v[0], v[1], v[2], 1.0];
            for j in 0..4 {
                for (k, f) in phi(d.temp_c).iter().enumerate() {
                    a[(r, j * 4 + k)] = g[j] * f;
                }
            }
            b[r] = d.u_mean[axis];
        }
        theta.push(a.svd(true, true).solve(&b, 1e-14).unwrap());
    }
    let mut worst: f64 = 0.0;
    for d in rec
        .dwells
        .iter()
        .filter(|d| rec.positions.has_role(d.position, Role::Verification))
    {
        let p = phi(d.temp_c);
        let val =
            |axis: usize, j: usize| -> f64 { (0..4).map(|k| theta[axis][j * 4 + k] * p[k]).sum() };
        let k = Matrix3::from_fn(&val);
        let u0 = Vector3::from_fn(|i, _| val(i, 3));
        let a = k.try_inverse().unwrap() * (Vector3::from(d.u_mean) - u0);
        worst = worst.max((a.norm() - 1.0).abs() * 1e3);
    }
    worst
}
