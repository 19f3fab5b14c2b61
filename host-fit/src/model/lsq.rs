//! Weighted linear least squares: the one solver of the crate. Normal equations are
//! accumulated row by row (zeros skipped, so the sparse designs of the diagnosis stay
//! cheap, and folds of held-out data are simply added or subtracted), then solved on the
//! column-equilibrated matrix by a Cholesky factorisation with one rank test.
use nalgebra::{DMatrix, DVector};

/// Rank test: the equilibrated normal matrix (unit diagonal) counts as singular when a
/// pivot of its Cholesky factorisation (the square of a diagonal element of L: the part
/// of a column not explained by the columns before it) is at most this. A column
/// explained by the others to within 1 part in 3e5 is not determined by the data (and
/// the normal equations could not resolve it reliably in f64 anyway: their rounding is
/// eps times the condition number squared).
pub const RANK_TOL: f64 = 1e-11;

/// The weighted normal equations `(A^T W A, A^T W b)` of a set of rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Normal {
    /// `A^T W A`: its lower triangle (`i >= j`) always; rows added by
    /// [`Normal::add_sparse`] leave the upper triangle zero (the matrix is symmetric, the
    /// solver reads the lower triangle only, and half the work is spared).
    pub ata: DMatrix<f64>,
    /// `A^T W b`.
    pub atb: DVector<f64>,
}

/// A solved least-squares problem.
#[derive(Debug, Clone)]
pub struct Solution {
    /// The parameters.
    pub x: DVector<f64>,
    /// `(A^T W A)^-1`: the covariance when the weights are 1/variance.
    pub cov: DMatrix<f64>,
}

impl Normal {
    /// Empty equations for `p` parameters.
    pub fn new(p: usize) -> Self {
        Normal {
            ata: DMatrix::zeros(p, p),
            atb: DVector::zeros(p),
        }
    }

    /// The rows `r` of `(a, b)` with `include(r)`, weights `w`.
    pub fn of_rows(
        a: &DMatrix<f64>,
        b: &DVector<f64>,
        w: &[f64],
        include: impl Fn(usize) -> bool,
    ) -> Self {
        let p = a.ncols();
        let mut n = Normal::new(p);
        let mut nz = Vec::with_capacity(p);
        for r in 0..a.nrows() {
            if !include(r) {
                continue;
            }
            let row = a.row(r);
            nz.clear();
            nz.extend((0..p).filter(|&j| row[j] != 0.0));
            let wr = w.get(r).copied().unwrap_or(0.0);
            for &i in &nz {
                n.atb[i] += wr * row[i] * b[r];
                for &j in &nz {
                    n.ata[(i, j)] += wr * row[i] * row[j];
                }
            }
        }
        n
    }

    /// The equations of both sets of rows.
    pub fn plus(&self, other: &Normal) -> Normal {
        Normal {
            ata: &self.ata + &other.ata,
            atb: &self.atb + &other.atb,
        }
    }

    /// Add one row given by its nonzero entries `(column, value)`.
    ///
    /// The diagnosis's hottest loop (a third of a real recording's diagnosis): it fills
    /// the lower triangle only (the upper stays zero, see [`Normal::ata`]), column by
    /// column as nalgebra stores it. Each entry gets the same `w * vi * vj` in the same
    /// row order as the plain double loop over the whole matrix gives it (for rows whose
    /// columns are distinct, as every design's are), so the lower triangle, all the
    /// solver reads, is bit for bit that loop's.
    pub fn add_sparse(&mut self, row: &[(usize, f64)], b: f64, w: f64) {
        let n = self.ata.nrows();
        let ata = self.ata.as_mut_slice();
        // a design's row lists its columns in ascending order: then the lower triangle
        // of column j is the row from j's entry on, with no test per entry
        let ascending = row.windows(2).all(|p| p[0].0 < p[1].0);
        for (at, &(j, vj)) in row.iter().enumerate() {
            self.atb[j] += w * vj * b;
            let col = &mut ata[j * n..(j + 1) * n];
            if ascending {
                for &(i, vi) in &row[at..] {
                    col[i] += w * vi * vj;
                }
            } else {
                for &(i, vi) in row {
                    if i >= j {
                        col[i] += w * vi * vj;
                    }
                }
            }
        }
    }

    /// These equations (of the first columns) as the leading block of equations for
    /// `p` columns, the others zero.
    pub fn embedded(&self, p: usize) -> Normal {
        let mut n = Normal::new(p);
        let q = self.atb.len().min(p);
        n.ata
            .view_mut((0, 0), (q, q))
            .copy_from(&self.ata.view((0, 0), (q, q)));
        n.atb.rows_mut(0, q).copy_from(&self.atb.rows(0, q));
        n
    }

    /// [`Normal::add_sparse`] of a row in ascending column order, less what it adds to
    /// the block of the columns before `first` (already there, see [`Normal::embedded`]):
    /// every other entry of the lower triangle gets the same `w * vi * vj` in the same
    /// row order, so the equations are bit for bit those of `add_sparse`.
    pub fn add_sparse_beyond(&mut self, row: &[(usize, f64)], b: f64, w: f64, first: usize) {
        let n = self.ata.nrows();
        let ata = self.ata.as_mut_slice();
        let beyond = row.partition_point(|e| e.0 < first);
        for (at, &(j, vj)) in row.iter().enumerate() {
            let col = &mut ata[j * n..(j + 1) * n];
            let from = if j >= first {
                self.atb[j] += w * vj * b;
                at
            } else {
                beyond
            };
            for &(i, vi) in &row[from..] {
                col[i] += w * vi * vj;
            }
        }
    }

    /// The equations of these rows without `other`'s (a fold held out).
    pub fn minus(&self, other: &Normal) -> Normal {
        Normal {
            ata: &self.ata - &other.ata,
            atb: &self.atb - &other.atb,
        }
    }

    /// Solve; `None` when the rows do not determine every parameter ([`RANK_TOL`]).
    pub fn solve(&self) -> Option<Solution> {
        let (l, d) = self.factor()?;
        let p = d.len();
        let sb = DVector::from_fn(p, |i, _| self.atb[i] / d[i]);
        let y = l.solve(&sb);
        let x = DVector::from_fn(p, |i, _| y[i] / d[i]);
        let inv = l.inverse();
        let cov = DMatrix::from_fn(p, p, |i, j| inv[(i, j)] / (d[i] * d[j]));
        Some(Solution { x, cov })
    }

    /// Whether these rows determine every parameter ([`RANK_TOL`]), without solving.
    pub fn is_determined(&self) -> bool {
        self.factor().is_some()
    }

    /// The parameters only (no covariance: cheaper, for profiling).
    pub fn solve_x(&self) -> Option<DVector<f64>> {
        let (l, d) = self.factor()?;
        let p = d.len();
        let y = l.solve(&DVector::from_fn(p, |i, _| self.atb[i] / d[i]));
        Some(DVector::from_fn(p, |i, _| y[i] / d[i]))
    }

    /// The factorised matrix, to solve `(A^T W A) x = v` for many right-hand sides `v`
    /// (the right-hand side of these equations is not used); `None` when singular
    /// ([`RANK_TOL`]).
    pub fn factorised(&self) -> Option<Factorised> {
        let (l, d) = self.factor()?;
        Some(Factorised { l, d })
    }

    /// The Cholesky factor of the equilibrated matrix and the equilibration, after the
    /// rank test.
    fn factor(&self) -> Option<(nalgebra::Cholesky<f64, nalgebra::Dyn>, Vec<f64>)> {
        let p = self.ata.ncols();
        let d: Vec<f64> = (0..p).map(|j| self.ata[(j, j)].sqrt()).collect();
        if p == 0 || d.iter().any(|v| *v <= 0.0 || !v.is_finite()) {
            return None;
        }
        // the lower triangle mirrored: rows added sparsely keep no upper triangle
        let s = DMatrix::from_fn(p, p, |i, j| self.ata[(i.max(j), i.min(j))] / (d[i] * d[j]));
        let l = s.cholesky()?;
        let lm = l.l_dirty();
        if (0..p).any(|k| {
            let v = lm[(k, k)] * lm[(k, k)];
            v.is_nan() || v <= RANK_TOL
        }) {
            return None;
        }
        Some((l, d))
    }
}

/// `A^T W A` factorised once (see [`Normal::factorised`]).
pub struct Factorised {
    l: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    d: Vec<f64>,
}

impl Factorised {
    /// `(A^T W A)^-1 v`.
    pub fn solve(&self, v: &DVector<f64>) -> DVector<f64> {
        let p = self.d.len();
        let y = self.l.solve(&DVector::from_fn(p, |i, _| v[i] / self.d[i]));
        DVector::from_fn(p, |i, _| y[i] / self.d[i])
    }
}

/// A solved weighted least-squares problem with its residuals.
#[derive(Debug, Clone)]
pub struct Lsq {
    /// The parameters.
    pub x: DVector<f64>,
    /// `(A^T W A)^-1`: the covariance when the weights are 1/variance.
    pub cov: DMatrix<f64>,
    /// Weighted residual sum of squares.
    pub wrss: f64,
    /// Residuals (unweighted), one per observation, computed from the data (not from
    /// the normal equations, which would lose them to cancellation).
    pub residuals: DVector<f64>,
}

/// Solve `min sum w_k (b_k - A_k x)^2`; `None` when `A` does not determine `x`.
pub fn weighted_lsq(a: &DMatrix<f64>, b: &DVector<f64>, w: &[f64]) -> Option<Lsq> {
    let (n, p) = a.shape();
    if n < p || p == 0 || w.len() != n {
        return None;
    }
    let s = Normal::of_rows(a, b, w, |_| true).solve()?;
    let residuals = b - a * &s.x;
    let wrss = residuals.iter().zip(w).map(|(r, w)| w * r * r).sum();
    Some(Lsq {
        x: s.x,
        cov: s.cov,
        wrss,
        residuals,
    })
}

/// The residual of `b` after its least-squares fit on the columns of `a` (unit weights):
/// the part of `b` no combination of the columns explains. A column the columns before it
/// already determine (to [`RANK_TOL`], a zero column among them) is left out, so a design
/// of deficient rank projects onto the space its columns span, as a minimum-norm solution
/// would. `None` when `a` has no rows or no column with data.
pub fn residual(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    let mut keep: Vec<usize> = Vec::new();
    for j in 0..a.ncols() {
        let mut cols = keep.clone();
        cols.push(j);
        let sub = a.select_columns(&cols);
        let w = vec![1.0; a.nrows()];
        if Normal::of_rows(&sub, b, &w, |_| true).is_determined() {
            keep = cols;
        }
    }
    if keep.is_empty() {
        return None;
    }
    let sub = a.select_columns(&keep);
    weighted_lsq(&sub, b, &vec![1.0; a.nrows()]).map(|s| s.residuals)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leading block accumulated apart, embedded, and the rest added beyond it, gives
    /// bit for bit the equations of the whole rows.
    #[test]
    fn a_leading_block_apart_gives_the_same_equations_bit_for_bit() {
        let mut rng = crate::rng::Rng::new(11);
        let (p, first) = (10, 6);
        let mut rows: Vec<Vec<(usize, f64)>> = Vec::new();
        for _ in 0..400 {
            let mut row = Vec::new();
            for c in 0..p {
                if rng.uniform() < 0.6 {
                    let scale = 10f64.powi((rng.uniform() * 6.0) as i32 - 3);
                    row.push((c, rng.normal() * scale));
                }
            }
            rows.push(row);
        }
        let bw: Vec<(f64, f64)> = rows.iter().map(|_| (rng.normal(), rng.uniform())).collect();
        let mut whole = Normal::new(p);
        let mut lead = Normal::new(first);
        for (row, &(b, w)) in rows.iter().zip(&bw) {
            whole.add_sparse(row, b, w);
            let k = row.partition_point(|e| e.0 < first);
            lead.add_sparse(&row[..k], b, w);
        }
        let mut split = lead.embedded(p);
        for (row, &(b, w)) in rows.iter().zip(&bw) {
            split.add_sparse_beyond(row, b, w, first);
        }
        let bits = |n: &Normal| {
            (
                n.ata.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                n.atb.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            )
        };
        assert_eq!(bits(&split), bits(&whole));
    }

    /// The column-by-column accumulation of the lower triangle gives, bit for bit, what
    /// the entry-by-entry double loop gives there, and the same solution (rows in
    /// ascending column order and in any order): sparse rows of distinct columns in any order, weights and
    /// values of every size.
    #[test]
    fn add_sparse_is_the_entry_by_entry_sum_bit_for_bit() {
        let mut rng = crate::rng::Rng::new(7);
        let p = 9;
        let mut fast = Normal::new(p);
        let mut plain = Normal::new(p);
        for _ in 0..500 {
            let mut cols: Vec<usize> = (0..p).collect();
            let k = 1 + (rng.uniform() * p as f64) as usize % p;
            for i in 0..p {
                let j = i + (rng.uniform() * (p - i) as f64) as usize % (p - i);
                cols.swap(i, j);
            }
            let mut row: Vec<(usize, f64)> = cols[..k]
                .iter()
                .map(|&c| {
                    (
                        c,
                        rng.normal() * 10f64.powi((rng.uniform() * 8.0) as i32 - 4),
                    )
                })
                .collect();
            // half the rows in a design's ascending column order (the fast path), half
            // in any order
            if rng.uniform() < 0.5 {
                row.sort_by_key(|e| e.0);
            }
            let (b, w) = (rng.normal(), rng.uniform() * 3.0);
            fast.add_sparse(&row, b, w);
            for &(i, vi) in &row {
                plain.atb[i] += w * vi * b;
                for &(j, vj) in &row {
                    plain.ata[(i, j)] += w * vi * vj;
                }
            }
        }
        let lower = |m: &DMatrix<f64>| {
            let mut v = Vec::new();
            for j in 0..p {
                for i in j..p {
                    v.push(m[(i, j)].to_bits());
                }
            }
            v
        };
        assert_eq!(lower(&fast.ata), lower(&plain.ata));
        assert!((0..p).all(|j| (0..j).all(|i| fast.ata[(i, j)] == 0.0)));
        // and solved alike, to the bit
        let (a, b) = (fast.solve().unwrap(), plain.solve().unwrap());
        assert_eq!(a.x, b.x);
        assert_eq!(a.cov, b.cov);
        assert_eq!(
            fast.atb.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            plain.atb.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn fits_a_line_and_detects_rank_deficiency() {
        let a = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0]);
        let b = DVector::from_vec(vec![1.0, 3.0, 5.0]);
        let s = weighted_lsq(&a, &b, &[1.0; 3]).unwrap();
        assert!((s.x[0] - 1.0).abs() < 1e-14 && (s.x[1] - 2.0).abs() < 1e-14);
        assert!(s.wrss < 1e-25);
        let d = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 2.0, 4.0, 3.0, 6.0]);
        assert!(weighted_lsq(&d, &b, &[1.0; 3]).is_none());
        // nearly parallel columns, condition ~1e7: not determined
        let e = DMatrix::from_row_slice(3, 2, &[1.0, 1.0, 1.0, 1.0 + 1e-7, 1.0, 1.0]);
        assert!(weighted_lsq(&e, &b, &[1.0; 3]).is_none());
    }

    /// The residual of a projection is the data minus its least-squares fit, also where
    /// a column repeats another or is zero (the space spanned, as an SVD's minimum-norm
    /// solution gives): to 1e-12 of the exact values.
    #[test]
    fn the_residual_of_a_projection_holds_for_deficient_rank() {
        let b = DVector::from_vec(vec![1.0, 3.0, 4.0, 8.0]);
        // the line through (0, 1), (1, 3), (2, 4), (3, 8): y = 0.7 + 2.2 x
        let want = [0.3, 0.1, -1.1, 0.7];
        let fitted = [0.7, 2.9, 5.1, 7.3];
        let full = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
        let deficient = DMatrix::from_row_slice(
            4,
            4,
            &[
                1.0, 0.0, 0.0, 2.0, 1.0, 1.0, 0.0, 2.0, 1.0, 2.0, 0.0, 2.0, 1.0, 3.0, 0.0, 2.0,
            ],
        );
        for a in [full, deficient] {
            let r = residual(&a, &b).unwrap();
            for i in 0..4 {
                assert!((r[i] - (b[i] - fitted[i])).abs() < 1e-12, "{r}");
                assert!((r[i] - want[i]).abs() < 1e-12, "{r}");
            }
        }
        assert!(residual(&DMatrix::zeros(4, 1), &b).is_none());
    }

    #[test]
    fn folds_add_up_to_the_whole() {
        let a = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
        let b = DVector::from_vec(vec![1.0, 2.9, 5.2, 7.0]);
        let w = [1.0, 2.0, 1.0, 0.5];
        let even = Normal::of_rows(&a, &b, &w, |r| r % 2 == 0);
        let odd = Normal::of_rows(&a, &b, &w, |r| r % 2 == 1);
        let all = Normal::of_rows(&a, &b, &w, |_| true);
        assert!((&even.plus(&odd).ata - &all.ata).norm() < 1e-12);
        let s = all.solve().unwrap();
        // covariance of a weighted line fit: the inverse of sum w [1 x; x x^2]
        let (sw, sx, sxx) = (4.5, 2.0 + 2.0 + 1.5, 2.0 + 4.0 + 4.5);
        let det = sw * sxx - sx * sx;
        assert!((s.cov[(0, 0)] - sxx / det).abs() < 1e-12);
        assert!((s.cov[(1, 1)] - sw / det).abs() < 1e-12);
    }
}
