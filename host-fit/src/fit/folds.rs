//! The cross-validation's fold design: which calibration dwells each fold holds out, so
//! that every training fold determines what the full data determine. A fold that takes
//! away the positions a stop's 12 coefficients rest on (one dwell already missing there,
//! and another held out) leaves a candidate undetermined, or determined only through an
//! ill-posed solve, and the choice would then be made by the fold design, not by the
//! data. So the folds are dealt in turn (the dwell of rank r to fold r mod k, as far as
//! it goes), and a dwell goes to a fold only where every design the full data determine
//! stays determined without that fold: each candidate model's, per axis, with its
//! even-order term where the full data have it, and each temperature's own `[a, 1]`
//! where the positions there determine it. A dwell that no fold can take is never held
//! out (it always trains), and the selection says which. Every candidate is then scored
//! on the same held-out dwells.
use crate::fit::identify::Obs;
use crate::fit::temperature::{check_coverage, design_row, kept_columns, ModelFit, Setting};
use crate::model::basis::Basis;
use crate::model::lsq::Normal;

/// Which fold holds out each dwell; None: never held out.
#[derive(Debug, Clone, PartialEq)]
pub struct FoldDesign {
    /// Folds.
    pub k: usize,
    /// (dwell, its fold), by dwell.
    fold: Vec<(usize, Option<usize>)>,
}

impl FoldDesign {
    /// The fold that holds out `dwell`; None when it is never held out.
    pub fn fold_of(&self, dwell: usize) -> Option<usize> {
        self.fold
            .binary_search_by_key(&dwell, |x| x.0)
            .ok()
            .and_then(|i| self.fold.get(i))
            .and_then(|x| x.1)
    }

    /// The dwells never held out (removing them would leave a design undetermined).
    pub fn never_held_out(&self) -> Vec<usize> {
        self.fold
            .iter()
            .filter(|x| x.1.is_none())
            .map(|x| x.0)
            .collect()
    }

    /// How many dwells are held out (in some fold).
    pub fn held_out(&self) -> usize {
        self.fold.iter().filter(|x| x.1.is_some()).count()
    }
}

/// One design the full data determine, which every training fold must keep
/// determining: its normal equations over all rows, and those of each fold's held-out
/// rows so far.
struct Kept<'b> {
    /// The candidate's basis (None: one temperature's own `[a, 1]` design).
    basis: Option<&'b Basis>,
    /// The axis (candidate designs).
    axis: usize,
    /// Column groups kept (candidate designs).
    keep: Vec<usize>,
    /// With the even-order term (candidate designs).
    with_k2: bool,
    /// The rows that enter (a temperature's design: its cluster's).
    member: Vec<bool>,
    full: Normal,
    held: Vec<Normal>,
}

impl Kept<'_> {
    /// The row of observation `o`, as (column, value) of its nonzero entries.
    fn row(&self, o: &Obs, t0: f64) -> Vec<(usize, f64)> {
        let dense = match self.basis {
            Some(b) => design_row(
                o,
                &b.eval(t0, o.temp_c),
                &self.keep,
                self.axis,
                self.with_k2,
            ),
            None => vec![o.a[0], o.a[1], o.a[2], 1.0],
        };
        dense
            .into_iter()
            .enumerate()
            .filter(|(_, v)| *v != 0.0)
            .collect()
    }

    /// The normal equations of the rows `idx` of `obs`.
    fn normal_of(&self, obs: &[Obs], idx: &[usize], t0: f64) -> Normal {
        let mut n = Normal::new(self.full.atb.len());
        for &i in idx.iter().filter(|i| self.member[**i]) {
            // the fit's weights are n / sigma^2 per axis: the rank does not see sigma
            n.add_sparse(&self.row(&obs[i], t0), 0.0, obs[i].n as f64);
        }
        n
    }
}

/// Temperature clusters as the fit finds them (sorted; a new one starts more than 2 C
/// above the first of the current one): per observation, its cluster.
fn clusters(obs: &[Obs]) -> (Vec<usize>, usize) {
    let mut idx: Vec<usize> = (0..obs.len()).collect();
    idx.sort_by(|a, b| obs[*a].temp_c.total_cmp(&obs[*b].temp_c));
    let mut of = vec![0; obs.len()];
    let (mut c, mut first) = (0usize, f64::NAN);
    for (r, i) in idx.iter().enumerate() {
        let t = obs[*i].temp_c;
        if r > 0 && t - first > 2.0 {
            c += 1;
        }
        if r == 0 || t - first > 2.0 {
            first = t;
        }
        of[*i] = c;
    }
    (of, if obs.is_empty() { 0 } else { c + 1 })
}

/// The designs the full data determine: each temperature's `[a, 1]` where its positions
/// determine it, and every candidate of `fits` per axis.
fn kept<'b>(
    obs: &[Obs],
    fits: &'b [(Basis, ModelFit)],
    setting: &Setting,
    k: usize,
) -> Vec<Kept<'b>> {
    let all: Vec<usize> = (0..obs.len()).collect();
    let mut out = Vec::new();
    let (of, n_clusters) = clusters(obs);
    for c in 0..n_clusters {
        let mut d = Kept {
            basis: None,
            axis: 0,
            keep: Vec::new(),
            with_k2: false,
            member: of.iter().map(|x| *x == c).collect(),
            full: Normal::new(4),
            held: vec![Normal::new(4); k],
        };
        d.full = d.normal_of(obs, &all, setting.t0_c);
        if d.full.is_determined() {
            out.push(d);
        }
    }
    for (b, fit) in fits {
        for axis in 0..3 {
            let keep = kept_columns(setting.frame, axis);
            let with_k2 = fit.k2[axis].is_some();
            let p = keep.len() * b.len() + usize::from(with_k2);
            let mut d = Kept {
                basis: Some(b),
                axis,
                keep,
                with_k2,
                member: vec![true; obs.len()],
                full: Normal::new(p),
                held: vec![Normal::new(p); k],
            };
            d.full = d.normal_of(obs, &all, setting.t0_c);
            out.push(d);
        }
    }
    out
}

/// The fold design for `obs` in `k` folds such that every candidate of `fits` (each
/// fitted on all of `obs`) stays determined in every training fold (see the module doc).
pub fn design(obs: &[Obs], fits: &[(Basis, ModelFit)], setting: &Setting, k: usize) -> FoldDesign {
    let k = k.max(1);
    let mut dwells: Vec<usize> = obs.iter().map(|o| o.dwell).collect();
    dwells.sort_unstable();
    dwells.dedup();
    let mut designs = kept(obs, fits, setting, k);
    let mut fold = Vec::with_capacity(dwells.len());
    // per fold, the observations it holds out so far (for the coverage of polynomials)
    let mut out_of: Vec<Vec<bool>> = vec![vec![false; obs.len()]; k];
    let mut next = 0usize;
    for d in dwells {
        let rows: Vec<usize> = (0..obs.len()).filter(|i| obs[*i].dwell == d).collect();
        let own: Vec<Normal> = designs
            .iter()
            .map(|x| x.normal_of(obs, &rows, setting.t0_c))
            .collect();
        let fits_in = |f: usize, designs: &[Kept], out_of: &[Vec<bool>]| {
            let determined = designs
                .iter()
                .zip(&own)
                .all(|(x, n)| x.full.minus(&x.held[f]).minus(n).is_determined());
            determined && {
                let temps: Vec<f64> = (0..obs.len())
                    .filter(|i| !out_of[f][*i] && obs[*i].dwell != d)
                    .map(|i| obs[i].temp_c)
                    .collect();
                fits.iter().all(|(b, _)| check_coverage(b, &temps).is_ok())
            }
        };
        let slot = (0..k)
            .map(|t| (next + t) % k)
            .find(|f| fits_in(*f, &designs, &out_of));
        if let Some(f) = slot {
            for (x, n) in designs.iter_mut().zip(&own) {
                x.held[f] = x.held[f].plus(n);
            }
            for i in &rows {
                out_of[f][*i] = true;
            }
            next = f + 1;
        }
        fold.push((d, slot));
    }
    FoldDesign { k, fold }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::noise::Noise;
    use crate::fit::select::candidates;
    use crate::fit::temperature::{fit_joint, Frame};
    use std::path::Path;

    /// Six positions (+-x, +-y, +-z) at four temperatures, a unit with linear thermal
    /// slopes; `drop` is left out (position, temperature index).
    fn obs(drop: Option<(usize, usize)>) -> Vec<Obs> {
        let dirs = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let mut out = Vec::new();
        for (ti, t) in [-30.0, 5.0, 25.0, 60.0].into_iter().enumerate() {
            for (p, a) in dirs.iter().enumerate() {
                if drop == Some((p, ti)) {
                    continue;
                }
                let dt: f64 = t - 25.0;
                let u = std::array::from_fn(|i| {
                    a[i] * (1.0 + 1e-4 * dt) + 1e-3 * (i as f64 + 1.0) + 1e-7 * dt * dt
                });
                out.push(Obs {
                    position: p,
                    a: *a,
                    temp_c: t,
                    u,
                    n: 60,
                    dwell: out.len(),
                    t_s: out.len() as f64 * 70.0,
                    estimated: false,
                });
            }
        }
        out
    }

    #[test]
    fn with_a_dwell_missing_every_training_fold_determines_every_candidate() {
        let noise = Noise {
            sigma: [2e-5; 3],
            dof: 1000,
        };
        let setting = Setting {
            noise: &noise,
            t0_c: 25.0,
            frame: Frame::Given,
            path: Path::new(""),
        };
        // +y missing at 5 C: -y there is all that determines the y column at 5 C
        let o = obs(Some((2, 1)));
        let temps: Vec<f64> = o.iter().map(|x| x.temp_c).collect();
        let fits: Vec<(Basis, ModelFit)> = candidates(&temps)
            .into_iter()
            .filter_map(|b| fit_joint(&o, &b, &setting).ok().map(|f| (b, f)))
            .collect();
        // the pwl through all four temperatures and the cubic among them
        assert_eq!(fits.len(), candidates(&temps).len());
        let folds = design(&o, &fits, &setting, 5);
        let minus_y_at_5 = o
            .iter()
            .find(|x| x.position == 3 && x.temp_c == 5.0)
            .map(|x| x.dwell);
        // it, and (the folds dealt greedily) at most one more, are never held out
        let never = folds.never_held_out();
        assert!(
            minus_y_at_5.is_some_and(|d| never.contains(&d)) && never.len() <= 2,
            "{never:?}"
        );
        assert_eq!(folds.held_out() + never.len(), o.len());
        // every candidate is fitted in every training fold (a design by rank alone holds
        // out -y at 5 C in some fold, and the pwl there has no y column at 5 C)
        for f in 0..folds.k {
            let train: Vec<Obs> = o
                .iter()
                .filter(|x| folds.fold_of(x.dwell) != Some(f))
                .cloned()
                .collect();
            assert!(train.len() < o.len(), "fold {f} holds out nothing");
            for (b, _) in &fits {
                assert!(
                    fit_joint(&train, b, &setting).is_ok(),
                    "fold {f}: {} undetermined",
                    b.describe()
                );
            }
        }
        // with nothing missing, every dwell is held out once
        let full = obs(None);
        let fits: Vec<(Basis, ModelFit)> = candidates(&temps)
            .into_iter()
            .filter_map(|b| fit_joint(&full, &b, &setting).ok().map(|f| (b, f)))
            .collect();
        let folds = design(&full, &fits, &setting, 5);
        assert_eq!(
            (folds.held_out(), folds.never_held_out().len()),
            (full.len(), 0)
        );
    }
}
