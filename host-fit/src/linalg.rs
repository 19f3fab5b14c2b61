//! Weighted linear least squares by SVD, with the parameter covariance.
use nalgebra::{DMatrix, DVector};

/// A solved weighted least-squares problem.
#[derive(Debug, Clone)]
pub struct Lsq {
    /// The parameters.
    pub x: DVector<f64>,
    /// `(A^T W A)^-1`: the covariance when the weights are 1/variance.
    pub cov: DMatrix<f64>,
    /// Weighted residual sum of squares.
    pub wrss: f64,
    /// Residuals (unweighted), one per observation.
    pub residuals: DVector<f64>,
}

/// Relative singular-value threshold below which a design counts as rank deficient.
pub const RANK_TOL: f64 = 1e-10;

/// Solve `min sum w_k (b_k - A_k x)^2`; `None` when `A` is rank deficient.
pub fn weighted_lsq(a: &DMatrix<f64>, b: &DVector<f64>, w: &[f64]) -> Option<Lsq> {
    let (n, p) = a.shape();
    if n < p || p == 0 || w.len() != n {
        return None;
    }
    let sw: Vec<f64> = w.iter().map(|v| v.max(0.0).sqrt()).collect();
    let mut aw = a.clone();
    let mut bw = b.clone();
    for (r, s) in sw.iter().enumerate() {
        aw.row_mut(r).scale_mut(*s);
        bw[r] *= s;
    }
    // Column scaling keeps the threshold meaningful when columns differ in magnitude.
    let scale: Vec<f64> = (0..p)
        .map(|j| {
            let c = aw.column(j).norm();
            if c > 0.0 {
                c
            } else {
                1.0
            }
        })
        .collect();
    for (j, s) in scale.iter().enumerate() {
        aw.column_mut(j).scale_mut(1.0 / s);
    }
    let svd = aw.svd(true, true);
    let smax = svd.singular_values.max();
    if smax.is_nan() || smax <= 0.0 || svd.singular_values.iter().any(|s| *s <= RANK_TOL * smax) {
        return None;
    }
    let u = svd.u.as_ref()?;
    let vt = svd.v_t.as_ref()?;
    let s_inv = svd.singular_values.map(|s| 1.0 / s);
    let utb = u.transpose() * &bw;
    let y = utb.component_mul(&s_inv);
    let mut x = vt.transpose() * y;
    let vs = vt.transpose() * DMatrix::from_diagonal(&s_inv);
    let mut cov = &vs * vs.transpose();
    for j in 0..p {
        x[j] /= scale[j];
        for k in 0..p {
            cov[(j, k)] /= scale[j] * scale[k];
        }
    }
    let residuals = b - a * &x;
    let wrss = residuals.iter().zip(w).map(|(r, w)| w * r * r).sum();
    Some(Lsq {
        x,
        cov,
        wrss,
        residuals,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_a_line_and_detects_rank_deficiency() {
        let a = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0]);
        let b = DVector::from_vec(vec![1.0, 3.0, 5.0]);
        let s = weighted_lsq(&a, &b, &[1.0; 3]).unwrap();
        assert!((s.x[0] - 1.0).abs() < 1e-14 && (s.x[1] - 2.0).abs() < 1e-14);
        let d = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 2.0, 4.0, 3.0, 6.0]);
        assert!(weighted_lsq(&d, &b, &[1.0; 3]).is_none());
    }
}
