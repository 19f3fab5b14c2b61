//! The sparse search over the library of discovered terms ([`crate::model::library`]),
//! in the spirit of SINDy (Brunton et al. 2016) with the stability of ensembles (Fasel
//! et al. 2022; stability selection, Meinshausen and Buhlmann 2010): every library column
//! is projected against the current model's columns in the floor's weights (what the
//! model already expresses is not the term's), screened by the chi-square it alone would
//! remove, then chosen by forward selection (the orthogonalised error reduction of FROLS)
//! on bootstrap resamples of the held-out time chunks. A term chosen in most resamples is
//! proposed to the search, which judges it in full by the same rules as a catalogue
//! effect (held-out chunks, both halves, the information criterion, adequacy); columns the
//! design cannot tell from the model's, or from each other, are reported, with the
//! positions that would identify them.
//!
//! Everything is computed from per-chunk sufficient statistics of the current model's
//! residual `r` (never from `y` itself, whose size would cancel the small differences
//! away): per chunk the model's normal matrix `N = X^T W X`, `X^T W r`, and per screened
//! candidate `c`: `X^T W c`, `c^T W r`, `c^T W c'`. A resample is their sum weighted by how
//! often it drew each chunk.
use crate::model::data::Data;
use crate::model::design::Row;
use crate::model::library::{self, Candidate, LibTerm, Series, TimedKey, DECAY_GRID_S};
use crate::model::lsq::Normal;
use crate::model::orders::Orders;
use crate::model::solve::Fit;
use crate::rng::Rng;
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;

/// A term the sparse search proposes to the diagnosis's judges.
#[derive(Debug, Clone)]
pub struct Proposal {
    /// The term and its axis (a decay at its best grid point).
    pub candidate: Candidate,
    /// The chi-square (floor units) it removes alone from the current model's residual.
    pub drop: f64,
    /// The share of bootstrap resamples of the time chunks whose forward selection chose
    /// it (its family: a decay at any time constant).
    pub inclusion: f64,
    /// Other terms whose columns the design cannot tell from this one's (after the
    /// model's columns are projected out): a set, not a choice.
    pub equivalents: Vec<Candidate>,
}

/// A term the design cannot identify: its column vanishes, or is one of the model's.
#[derive(Debug, Clone, PartialEq)]
pub struct Unidentifiable {
    /// The term's force part (its products with time-varying factors go with it).
    pub term: String,
    /// The positions that would identify it, in words.
    pub positions: String,
}

/// What the sparse search found on the current model's residual.
#[derive(Debug, Clone, Default)]
pub struct Discovery {
    /// Proposals, the largest chi-square drop first.
    pub proposals: Vec<Proposal>,
    /// Force parts the design cannot identify.
    pub unidentifiable: Vec<Unidentifiable>,
    /// Library columns tried (decays at every grid point).
    pub tried: usize,
}

/// A library column whose statistics are kept for the resamples.
struct Screened {
    cand: Candidate,
    /// Chi-square removed alone on the whole recording.
    drop: f64,
    /// Per chunk: `X^T W c`.
    v: Vec<DVector<f64>>,
    /// Per chunk: `c^T W r`.
    g: Vec<f64>,
    /// Column values per window.
    values: Vec<f64>,
    /// Structural unknowns (a decay's time constant).
    structural: usize,
}

/// The current model's design and residual, per chunk.
struct Model {
    rows: Vec<Row>,
    p: usize,
    /// Residual per row (output units).
    r: Vec<f64>,
    /// Per chunk: `X^T W X`, `X^T W r`, `r^T W r`.
    n: Vec<Normal>,
    h: Vec<DVector<f64>>,
    rr: Vec<f64>,
}

impl Model {
    fn of(data: &Data, current: &Fit) -> Model {
        let d = data.design(&current.spec, Some(&current.k_at));
        let p = d.labels.len();
        let r: Vec<f64> = current.resid.iter().flatten().copied().collect();
        let chunks = data.n_chunks();
        let mut n: Vec<Normal> = (0..chunks).map(|_| Normal::new(p)).collect();
        let mut h = vec![DVector::zeros(p); chunks];
        let mut rr = vec![0.0; chunks];
        for (row, cols) in d.rows.iter().enumerate() {
            let ch = data.obs[row / 3].chunk;
            let w = data.w[row];
            n[ch].add_sparse(cols, 0.0, w);
            for &(j, v) in cols {
                h[ch][j] += w * v * r[row];
            }
            rr[ch] += w * r[row] * r[row];
        }
        Model {
            rows: d.rows,
            p,
            r,
            n,
            h,
            rr,
        }
    }

    /// `X^T W c` per chunk, `c^T W r` per chunk, `c^T W c` over all, for column `c` on
    /// `axis`.
    fn stats(&self, data: &Data, axis: usize, c: &[f64]) -> (Vec<DVector<f64>>, Vec<f64>, f64) {
        let chunks = self.n.len();
        let mut v = vec![DVector::zeros(self.p); chunks];
        let mut g = vec![0.0; chunks];
        let mut cc = 0.0;
        for (o, &value) in c.iter().enumerate() {
            if value == 0.0 {
                continue;
            }
            let row = 3 * o + axis;
            let (ch, w) = (data.obs[o].chunk, data.w[row]);
            for &(j, x) in &self.rows[row] {
                v[ch][j] += w * x * value;
            }
            g[ch] += w * value * self.r[row];
            cc += w * value * value;
        }
        (v, g, cc)
    }
}

/// The weights of a resample: how often it drew each chunk (all ones: the recording).
fn sum_vec(parts: &[DVector<f64>], m: &[f64]) -> DVector<f64> {
    parts.iter().zip(m).fold(
        DVector::zeros(parts.first().map_or(0, |v| v.len())),
        |a, (v, k)| a + v * *k,
    )
}

fn sum_f(parts: &[f64], m: &[f64]) -> f64 {
    parts.iter().zip(m).map(|(v, k)| v * k).sum()
}

/// The chi-square the columns `set` remove together, given their residual projections
/// `g` and the Gram matrix `gram` of their projected columns: `g^T G^-1 g`.
fn joint_drop(set: &[usize], g: &[f64], gram: &DMatrix<f64>) -> f64 {
    if set.is_empty() {
        return 0.0;
    }
    let k = set.len();
    let gs = DVector::from_fn(k, |i, _| g[set[i]]);
    let gm = DMatrix::from_fn(k, k, |i, j| gram[(set[i], set[j])]);
    match gm.clone().cholesky() {
        Some(ch) => gs.dot(&ch.solve(&gs)),
        None => 0.0,
    }
}

/// Forward selection on one resample (chunk multiplicities `m`): the screened columns
/// chosen, in order, while each lowers the quasi-BIC by more than the margin.
fn select(
    data: &Data,
    model: &Model,
    screened: &[Screened],
    cross: &[Vec<f64>],
    m: &[f64],
) -> Vec<usize> {
    let rules = &data.rules;
    let nb = model
        .n
        .iter()
        .zip(m)
        .fold(Normal::new(model.p), |a, (n, k)| Normal {
            ata: a.ata + &n.ata * *k,
            atb: a.atb,
        });
    let Some(f) = nb.factorised() else {
        return Vec::new();
    };
    let hb = sum_vec(&model.h, m);
    let delta = f.solve(&hb);
    let chi2 = sum_f(&model.rr, m) - hb.dot(&delta);
    let k = screened.len();
    let vb: Vec<DVector<f64>> = screened.iter().map(|s| sum_vec(&s.v, m)).collect();
    let nv: Vec<DVector<f64>> = vb.iter().map(|v| f.solve(v)).collect();
    let g: Vec<f64> = (0..k)
        .map(|a| sum_f(&screened[a].g, m) - vb[a].dot(&delta))
        .collect();
    let gram = DMatrix::from_fn(k, k, |a, b| sum_f(&cross[a * k + b], m) - vb[a].dot(&nv[b]));
    let n_eff: f64 = data
        .obs
        .iter()
        .map(|o| 3.0 * m[o.chunk])
        .sum::<f64>()
        .max(2.0);
    let mut set: Vec<usize> = Vec::new();
    let mut base = 0.0;
    while set.len() < rules.discover_max_terms {
        let best = (0..k)
            .filter(|a| !set.contains(a) && gram[(*a, *a)] > 0.0)
            .map(|a| {
                let mut s = set.clone();
                s.push(a);
                (a, joint_drop(&s, &g, &gram))
            })
            .max_by(|x, y| x.1.total_cmp(&y.1));
        let Some((a, d)) = best else { break };
        let dof = (n_eff - (model.p + set.len() + 1) as f64).max(1.0);
        let phi = ((chi2 - d) / dof).max(1.0);
        let gain = (d - base) / phi - (1 + screened[a].structural) as f64 * n_eff.ln();
        if gain <= rules.q_margin {
            break;
        }
        set.push(a);
        base = d;
    }
    set
}

/// The window means of every distinct time-varying part, computed once.
struct Timed<'s> {
    series: &'s Series,
    cache: HashMap<Vec<TimedKey>, Vec<f64>>,
}

impl Timed<'_> {
    fn column(&mut self, data: &Data, term: &LibTerm) -> Vec<f64> {
        // Keyed by value, not by the printed text: the text rounds a TAU.
        let key: Vec<_> = term.timed.iter().map(library::Timed::key).collect();
        let m = self
            .cache
            .entry(key)
            .or_insert_with(|| self.series.timed_means(data, &term.timed));
        data.obs
            .iter()
            .zip(m.iter())
            .map(|(o, v)| term.force(o.a) * v)
            .collect()
    }
}

/// A screened column on the whole recording: its chi-square drop alone, its projected
/// norm (`c^T W c` less what the model expresses), and the share of it left.
struct Alone {
    cand: Candidate,
    drop: f64,
    projected: f64,
    left: f64,
}

/// The screened candidates' columns and their per-chunk statistics.
fn screened(data: &Data, model: &Model, timed: &mut Timed, alone: &[Alone]) -> Vec<Screened> {
    alone
        .iter()
        .map(|a| {
            let values = timed.column(data, &a.cand.term);
            let (v, g, _) = model.stats(data, a.cand.axis, &values);
            Screened {
                structural: usize::from(a.cand.term.tau_s().is_some()),
                cand: a.cand.clone(),
                drop: a.drop,
                v,
                g,
                values,
            }
        })
        .collect()
}

/// Each screened candidate's share of the bootstrap resamples of the time chunks whose
/// forward selection chooses it ([`crate::model::rules::Rules::discover_bags`] resamples,
/// drawn from a fixed seed: the same data give the same proposals).
fn inclusions(data: &Data, model: &Model, screened: &[Screened]) -> Vec<f64> {
    let rules = &data.rules;
    let chunks = model.n.len();
    let cross = cross_products(data, screened, chunks);
    let mut rng = Rng::new(rules.discover_seed);
    let mut chosen = vec![0usize; screened.len()];
    for _ in 0..rules.discover_bags {
        let mut m = vec![0.0; chunks];
        for _ in 0..chunks {
            m[(rng.uniform() * chunks as f64) as usize % chunks] += 1.0;
        }
        for a in select(data, model, screened, &cross, &m) {
            chosen[a] += 1;
        }
    }
    let bags = rules.discover_bags.max(1) as f64;
    chosen.iter().map(|c| *c as f64 / bags).collect()
}

/// The sparse search on `current`'s residual (see the module doc); `orders` are the
/// baseline's temperature orders, the K rows' and the offsets' (what the baseline
/// already expresses), `reach` what the recording can judge.
pub fn discover(data: &Data, current: &Fit, orders: Orders, reach: library::Reach) -> Discovery {
    let rules = &data.rules;
    let model = Model::of(data, current);
    let chunks = model.n.len();
    let ones = vec![1.0; chunks];
    let total = model.n.iter().fold(Normal::new(model.p), |a, n| a.plus(n));
    let Some(f) = total.factorised() else {
        return Discovery::default();
    };
    let series = Series::new(data);
    let mut timed = Timed {
        series: &series,
        cache: HashMap::new(),
    };
    let mut alone: Vec<Alone> = Vec::new();
    let mut unidentifiable: Vec<Unidentifiable> = Vec::new();
    let mut tried = 0usize;
    for cand in library::library(data, orders, reach) {
        // decays that settle within the recording (longer ones are drifts, `t`)
        let limit = crate::model::profile::settling_limit_s(data);
        let taus: Vec<Option<f64>> = match cand.term.tau_s() {
            Some(_) => DECAY_GRID_S
                .iter()
                .filter(|t| **t < limit)
                .map(|t| Some(*t))
                .collect(),
            None => vec![None],
        };
        let mut best: Option<Alone> = None;
        let mut identified = false;
        for tau in taus {
            let term = tau.map_or_else(|| cand.term.clone(), |t| cand.term.with_tau(t));
            let c = timed.column(data, &term);
            tried += 1;
            let (v, g, cc) = model.stats(data, cand.axis, &c);
            if cc <= 0.0 {
                continue;
            }
            let vt = sum_vec(&v, &ones);
            let projected = cc - vt.dot(&f.solve(&vt));
            let left = projected / cc;
            if left < rules.identifiable_share {
                continue;
            }
            identified = true;
            let g = sum_f(&g, &ones);
            let drop = g * g / projected;
            if best.as_ref().is_none_or(|b| drop > b.drop) {
                best = Some(Alone {
                    cand: Candidate {
                        term,
                        axis: cand.axis,
                    },
                    drop,
                    projected,
                    left,
                });
            }
        }
        if !identified && cand.term.timed.is_empty() {
            let force = cand.term.to_string();
            if !unidentifiable.iter().any(|u| u.term == force) {
                unidentifiable.push(Unidentifiable {
                    positions: cand.term.identifying_positions().to_string(),
                    term: force,
                });
            }
        }
        alone.extend(best);
    }
    let n = data.n_rows() as f64;
    let dof = (n - current.params() as f64 - 1.0).max(1.0);
    let gain = |a: &Alone| {
        let phi = ((current.chi2 - a.drop) / dof).max(1.0);
        a.drop / phi - (1 + usize::from(a.cand.term.tau_s().is_some())) as f64 * n.ln()
    };
    alone.retain(|a| gain(a) > rules.q_margin);
    alone.sort_by(|a, b| b.drop.total_cmp(&a.drop));
    alone.truncate(rules.discover_screened);
    let screened = screened(data, &model, &mut timed, &alone);
    let inclusion = inclusions(data, &model, &screened);
    let mut proposals: Vec<Proposal> = screened
        .iter()
        .zip(inclusion)
        // the bare trend only rivals a scale drift: never proposed as physics
        .filter(|(s, share)| *share >= rules.discover_inclusion && !library::is_trend(&s.cand.term))
        .map(|(s, share)| Proposal {
            candidate: s.cand.clone(),
            drop: s.drop,
            inclusion: share,
            equivalents: Vec::new(),
        })
        .collect();
    for p in &mut proposals {
        p.equivalents = equivalents(data, &model, &f, &mut timed, &p.candidate, &alone);
    }
    log::debug!(
        "  library: {tried} columns, {} screened, proposals {:?}",
        screened.len(),
        proposals
            .iter()
            .map(|p| format!("{} ({:.2})", p.candidate, p.inclusion))
            .collect::<Vec<_>>()
    );
    Discovery {
        proposals,
        unidentifiable,
        tried,
    }
}

/// Per pair of screened columns and per chunk, `c_a^T W c_b` (zero across axes).
fn cross_products(data: &Data, screened: &[Screened], chunks: usize) -> Vec<Vec<f64>> {
    let k = screened.len();
    let mut out = vec![vec![0.0; chunks]; k * k];
    for a in 0..k {
        for b in a..k {
            let axis = screened[a].cand.axis;
            if screened[b].cand.axis != axis {
                continue;
            }
            let mut per = vec![0.0; chunks];
            for (o, ob) in data.obs.iter().enumerate() {
                let w = data.w[3 * o + axis];
                per[ob.chunk] += w * screened[a].values[o] * screened[b].values[o];
            }
            out[a * k + b] = per.clone();
            out[b * k + a] = per;
        }
    }
    out
}

/// The screened terms on `cand`'s axis whose projected columns are the same as its own
/// (correlation above [`crate::diagnose::rules::Rules::equivalent_correlation`]), other
/// families only.
fn equivalents(
    data: &Data,
    model: &Model,
    f: &crate::model::lsq::Factorised,
    timed: &mut Timed,
    cand: &Candidate,
    alone: &[Alone],
) -> Vec<Candidate> {
    let ones = vec![1.0; model.n.len()];
    let ca = timed.column(data, &cand.term);
    let (va, _, _) = model.stats(data, cand.axis, &ca);
    let va = sum_vec(&va, &ones);
    let na = f.solve(&va);
    let Some(own) = alone.iter().find(|a| a.cand == *cand) else {
        return Vec::new();
    };
    let family = cand.term.family();
    alone
        .iter()
        .filter(|b| b.cand.axis == cand.axis && b.cand.term.family() != family)
        .filter(|b| {
            let cb = timed.column(data, &b.cand.term);
            let (vb, _, _) = model.stats(data, cand.axis, &cb);
            let vb = sum_vec(&vb, &ones);
            let raw: f64 = (0..data.obs.len())
                .map(|o| data.w[3 * o + cand.axis] * ca[o] * cb[o])
                .sum();
            let proj = raw - vb.dot(&na);
            let corr = proj / (own.projected * b.projected).sqrt();
            if corr.abs() > 0.9 {
                log::debug!("  {} ~ {}: projected correlation {corr:.5}", cand, b.cand);
            }
            corr.abs() >= data.rules.equivalent_correlation && own.left > 0.0
        })
        .map(|b| b.cand.clone())
        .collect()
}
