//! Static poses of unknown orientation (a position whose vector is empty in a positions
//! file): their directions estimated together with the 12 coefficients and their
//! temperature models, as in sphere-fit auto-calibration. At rest |a| = 1, so each pose
//! costs two unknowns (its direction) and gives three readings per window: the third
//! carries the calibration.
//!
//! The joint least squares over coefficients and directions is solved by alternation:
//! fit the model with the directions fixed (linear), then give every unknown pose the
//! direction that model reads from its windows (the weighted mean of `N(T)(U - U0(T))`,
//! normalised), until the directions stop moving. The start is an ellipsoid through the
//! poses' mean readings, or the model of the known poses when they determine one.
//!
//! Gravity alone does not see a rotation (nor a reflection) of the whole unit: with no
//! pose of known orientation the frame is fixed by convention, K(T0) lower triangular
//! with a positive diagonal (x along the x sensing axis, y in the x-y plane). Known and
//! unknown poses mix freely; then the known ones fix the frame.
use crate::data::positions::{Positions, Role};
use crate::data::recording::Recording;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::equilibrium::static_observations;
use crate::fit::identify::Obs;
use crate::fit::noise::{noise, Noise};
use crate::fit::temperature::{fit_joint, Frame, ModelFit, Setting};
use crate::model::basis::{temperature_clusters, Basis};
use crate::model::lsq::weighted_lsq;
use firmware_core::model::{invert, Coeffs};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use serde::Serialize;

/// Alternations at most.
pub const MAX_ITERATIONS: usize = 500;
/// The longest stretch of an alternation's step tried.
pub const MAX_STRETCH: f64 = 64.0;
/// The directions have converged when none moves more than this, rad (a microradian
/// moves |a| by far less than a microgram).
pub const CONVERGED_RAD: f64 = 1e-6;

/// One estimated pose.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PoseEstimate {
    /// Position name.
    pub name: String,
    /// Estimated unit vector.
    pub a: [f64; 3],
    /// 1-sigma of the direction, rad (rms of the two directions across it).
    pub sigma_rad: f64,
    /// Its windows in the fit (0: not in the static fit, read from the final model).
    pub windows: usize,
}

/// The estimated orientations.
#[derive(Debug, Clone)]
pub struct Orientation {
    /// The positions with every unknown one estimated (and marked known).
    pub positions: Positions,
    /// The estimates.
    pub poses: Vec<PoseEstimate>,
    /// How the frame was fixed, when no known pose fixes it.
    pub frame: Option<String>,
    /// Alternations done.
    pub iterations: usize,
    /// The model fitted with them.
    pub fit: ModelFit,
}

/// The provisional temperature model used while estimating: a polynomial of order 2
/// (1 with two temperatures, 0 with one); the final model is chosen afterwards.
pub fn provisional_basis(temps: &[f64]) -> Basis {
    Basis::Poly {
        order: temperature_clusters(temps).len().saturating_sub(1).min(2),
    }
}

/// Whether `rec` has a position of unknown orientation with dwells.
pub fn has_unknown(rec: &Recording) -> bool {
    rec.dwells
        .iter()
        .any(|d| !rec.positions.is_known(d.position))
}

/// The reading of each window in unit axes by `fit`, weighted: per pose the normal
/// matrix and right side of `min sum w |K a - (u - U0)|^2`.
fn read_poses(
    fit: &ModelFit,
    obs: &[Obs],
    noise: &Noise,
    poses: &[usize],
) -> Vec<(Matrix3<f64>, Vector3<f64>, usize)> {
    let cal = fit.calibration(0.0, false);
    let mut acc = vec![(Matrix3::zeros(), Vector3::zeros(), 0usize); poses.len()];
    for o in obs {
        let Ok(k) = poses.binary_search(&o.position) else {
            continue;
        };
        let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, o.temp_c));
        let km = Matrix3::from_fn(|i, j| c.k[i][j]);
        let w = Matrix3::from_diagonal(&Vector3::from_fn(|i, _| {
            o.n as f64 / noise.sigma[i].powi(2)
        }));
        let r = Vector3::from_fn(|i, _| o.u[i] - c.u0[i]);
        acc[k].0 += km.transpose() * w * km;
        acc[k].1 += km.transpose() * w * r;
        acc[k].2 += 1;
    }
    acc
}

/// The ellipsoid through the mean readings of the static dwells: `(N, U0)` with
/// `|N (u - U0)| = 1`, N upper triangular.
fn ellipsoid(obs: &[Obs]) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let n = obs.len();
    let mut a = DMatrix::zeros(n, 9);
    for (r, o) in obs.iter().enumerate() {
        let [x, y, z] = o.u;
        let row = [
            x * x,
            y * y,
            z * z,
            2.0 * x * y,
            2.0 * x * z,
            2.0 * y * z,
            x,
            y,
            z,
        ];
        for (j, v) in row.iter().enumerate() {
            a[(r, j)] = *v;
        }
    }
    let w: Vec<f64> = obs.iter().map(|o| o.n as f64).collect();
    let s = weighted_lsq(&a, &DVector::from_element(n, 1.0), &w)?;
    let x = &s.x;
    let m = Matrix3::new(x[0], x[3], x[4], x[3], x[1], x[5], x[4], x[5], x[2]);
    let b = Vector3::new(x[6], x[7], x[8]);
    let c = -0.5 * m.try_inverse()? * b;
    let scale = 1.0 + (c.transpose() * m * c)[0];
    let chol = (m / scale).cholesky()?;
    Some((chol.l().transpose(), c))
}

fn unit(v: Vector3<f64>) -> Option<[f64; 3]> {
    let n = v.norm();
    (n > 0.0 && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// Estimate the unknown poses of `rec` with the temperature model `basis`.
pub fn estimate_with(rec: &Recording, basis: &Basis) -> Result<Orientation> {
    let cal = |p: usize| rec.positions.has_role(p, Role::Calibration);
    let (mut obs, _) = static_observations(rec, &cal);
    let nz = noise(rec);
    let mut poses: Vec<usize> = obs
        .iter()
        .map(|o| o.position)
        .filter(|p| !rec.positions.is_known(*p))
        .collect();
    poses.sort_unstable();
    poses.dedup();
    let known: Vec<Obs> = obs
        .iter()
        .filter(|o| rec.positions.is_known(o.position))
        .cloned()
        .collect();
    let frame = if known_directions(&known) < 2 {
        Frame::LowerTriangular
    } else {
        Frame::Given
    };
    let setting = Setting {
        noise: &nz,
        t0_c: rec.t0_c,
        frame,
        path: &rec.path,
    };
    let known_fit = fit_joint(
        &known,
        basis,
        &Setting {
            frame: Frame::Given,
            ..setting
        },
    );
    // the known poses fix the frame: their model reads the others
    let start = match known_fit {
        Ok(f) if frame == Frame::Given => read_poses(&f, &obs, &nz, &poses)
            .iter()
            .map(|(h, r, _)| h.try_inverse().and_then(|hi| unit(hi * r)))
            .collect::<Option<Vec<_>>>(),
        _ => ellipsoid_start(&obs, &poses),
    };
    let mut dirs = start.ok_or_else(|| {
        HostError::in_file(
            ErrorKind::Insufficient,
            &rec.path,
            format!(
                "cannot start estimating the {} poses of unknown orientation: their readings do not span the sphere (need at least 9 poses in different directions, or 4 known positions not in one plane)",
                poses.len()
            ),
        )
    })?;
    let fit_at = |obs: &mut Vec<Obs>, dirs: &[[f64; 3]]| {
        for o in obs.iter_mut() {
            if let Ok(k) = poses.binary_search(&o.position) {
                o.a = dirs[k];
                o.estimated = true;
            }
        }
        fit_joint(obs, basis, &setting)
    };
    let mut fit = fit_at(&mut obs, &dirs)?;
    let mut iterations = 0;
    loop {
        iterations += 1;
        let step: Vec<[f64; 3]> = read_poses(&fit, &obs, &nz, &poses)
            .iter()
            .zip(&dirs)
            .map(|((h, r, _), old)| h.try_inverse().and_then(|hi| unit(hi * r)).unwrap_or(*old))
            .collect();
        // Alternation crawls along directions the data constrain weakly (offsets and
        // directions of poses bunched in one hemisphere trade against each other); the
        // steps keep their direction there, so the step is stretched while that lowers
        // the chi-square.
        let (mut best_dirs, mut best) = (step.clone(), fit_at(&mut obs, &step)?);
        let mut stretch = 2.0;
        while stretch <= MAX_STRETCH {
            let trial: Vec<[f64; 3]> = dirs
                .iter()
                .zip(&step)
                .map(|(o, n)| {
                    let (o, n) = (Vector3::from(*o), Vector3::from(*n));
                    unit(o + (n - o) * stretch).unwrap_or(*o.as_ref())
                })
                .collect();
            match fit_at(&mut obs, &trial) {
                Ok(f) if f.chi2 < best.chi2 => {
                    (best_dirs, best) = (trial, f);
                    stretch *= 2.0;
                }
                _ => break,
            }
        }
        let moved = dirs
            .iter()
            .zip(&best_dirs)
            .map(|(a, b)| (Vector3::from(*a) - Vector3::from(*b)).norm())
            .fold(0.0, f64::max);
        log::debug!(
            "orientation {iterations}: chi2 {} stretch {stretch} moved {moved:e}",
            best.chi2
        );
        dirs = best_dirs;
        fit = best;
        if moved < CONVERGED_RAD || iterations >= MAX_ITERATIONS {
            break;
        }
    }
    // the observations carry the directions of the last fit
    fit = fit_at(&mut obs, &dirs)?;
    let done = Alternated {
        obs: &obs,
        poses: &poses,
        dirs: &dirs,
        iterations,
        frame,
    };
    finish(rec, &nz, &done, fit)
}

/// The directions the alternation starts from when no known pose fixes the frame: read
/// through the ellipsoid of the poses' mean readings, turned into the lower frame.
fn ellipsoid_start(obs: &[Obs], poses: &[usize]) -> Option<Vec<[f64; 3]>> {
    ellipsoid(obs).map(|(n, c)| {
        // K = N^-1 is upper triangular; turn the start into the lower frame
        let q = n
            .try_inverse()
            .map(|k| lower_frame(&k))
            .unwrap_or_else(Matrix3::identity);
        let n = q.transpose() * n;
        poses
            .iter()
            .map(|p| {
                let (s, k) = obs
                    .iter()
                    .filter(|o| o.position == *p)
                    .fold((Vector3::zeros(), 0.0), |(s, k), o| {
                        (s + Vector3::from(o.u) * o.n as f64, k + o.n as f64)
                    });
                unit(n * (s / k - c)).unwrap_or([0.0, 0.0, 1.0])
            })
            .collect()
    })
}

/// Where the alternation ended.
struct Alternated<'a> {
    obs: &'a [Obs],
    poses: &'a [usize],
    dirs: &'a [[f64; 3]],
    iterations: usize,
    frame: Frame,
}

/// How many non-parallel directions the known poses have (0, 1 or 2 = enough).
fn known_directions(known: &[Obs]) -> usize {
    let Some(first) = known.first() else {
        return 0;
    };
    let f = Vector3::from(first.a);
    if known
        .iter()
        .any(|o| Vector3::from(o.a).cross(&f).norm() > 1e-3)
    {
        2
    } else {
        1
    }
}

/// The orthogonal Q with K Q lower triangular with a positive diagonal (the frame's
/// convention when no known pose fixes it): from the QR decomposition of K^T.
fn lower_frame(k: &Matrix3<f64>) -> Matrix3<f64> {
    let qr = k.transpose().qr();
    let (mut q, r) = (qr.q(), qr.r());
    for i in 0..3 {
        if r[(i, i)] < 0.0 {
            q.column_mut(i).neg_mut();
        }
    }
    q
}

fn finish(
    rec: &Recording,
    nz: &Noise,
    done: &Alternated<'_>,
    fit: ModelFit,
) -> Result<Orientation> {
    let Alternated {
        obs,
        poses,
        dirs,
        iterations,
        frame,
    } = *done;
    let mut positions = rec.positions.clone();
    let scale = (0..3).map(|i| fit.axis_scale(i, nz.dof > 0)).sum::<f64>() / 3.0;
    let reads = read_poses(&fit, obs, nz, poses);
    let mut out = Vec::new();
    for ((p, a), (h, _, windows)) in poses.iter().zip(dirs).zip(&reads) {
        // the variance across the direction: the trace of H^-1 less its radial part
        let sigma = h
            .try_inverse()
            .map(|hi| {
                let d = Vector3::from(*a);
                ((hi.trace() - (d.transpose() * hi * d)[0]).max(0.0) * scale / 2.0).sqrt()
            })
            .unwrap_or(f64::NAN);
        positions.set_estimated(*p, *a);
        out.push(PoseEstimate {
            name: rec.positions.name(*p).to_string(),
            a: *a,
            sigma_rad: sigma,
            windows: *windows,
        });
    }
    read_the_rest(rec, &fit, &mut positions, &mut out);
    Ok(Orientation {
        positions,
        poses: out,
        frame: (frame == Frame::LowerTriangular).then(|| {
            "no pose of known orientation: frame fixed by convention, K(T0) lower triangular with a positive diagonal (a rotation or reflection of the whole unit is not observable from gravity)".to_string()
        }),
        iterations,
        fit,
    })
}

/// The unknown poses outside the static calibration fit (verification poses, poses
/// taken while the temperature moved) read from the final model: the direction of
/// their compensated mean, so that every pose has a vector.
fn read_the_rest(
    rec: &Recording,
    fit: &ModelFit,
    positions: &mut Positions,
    out: &mut Vec<PoseEstimate>,
) {
    let cal = fit.calibration(0.0, false);
    for (i, p) in rec.positions.list.iter().enumerate() {
        if p.known || positions.is_known(i) {
            continue;
        }
        let mut s = Vector3::zeros();
        for d in rec.dwells.iter().filter(|d| d.position == i) {
            let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, d.temp_c));
            if let Some(n) = invert(&c.k) {
                let a = firmware_core::model::apply(&n, d.u_mean, c.u0);
                s += Vector3::from(a) * d.len() as f64;
            }
        }
        if let Some(a) = unit(s) {
            positions.set_estimated(i, a);
            out.push(PoseEstimate {
                name: p.name.clone(),
                a,
                sigma_rad: f64::NAN,
                windows: 0,
            });
        }
    }
}
