//! The diagnosis's observations: windows of every dwell of a known position (spikes
//! left out), and the contiguous time chunks that make its held-out folds.
use crate::data::recording::Recording;
use crate::diagnose::rules::Rules;
use crate::fit::identify::windows;

/// One observation: the mean of a window of a dwell.
#[derive(Debug, Clone)]
pub struct DObs {
    /// Position index.
    pub position: usize,
    /// Specific force, g.
    pub a: [f64; 3],
    /// Samples averaged (spikes left out).
    pub n: usize,
    /// Row range `[start, end)`.
    pub start: usize,
    /// End of the row range.
    pub end: usize,
    /// Dwell index.
    pub dwell: usize,
    /// Contiguous time chunk (about [`Rules::chunk_windows`] observations each, in time
    /// order): the held-out blocks.
    pub chunk: usize,
    /// Mean sensor temperature, C.
    pub temp_c: f64,
    /// Mean time, s.
    pub t_s: f64,
    /// Mean outputs.
    pub u: [f64; 3],
}

/// Windows of every dwell of a known position: at most [`Rules::window_span_c`] of
/// temperature and [`Rules::window_max_s`] of time each, at least two per dwell of 4 or
/// more samples. `spikes` (sorted row indices) are left out of the means.
pub fn observations(rec: &Recording, spikes: &[usize], rules: &Rules) -> Vec<DObs> {
    let mut out = Vec::new();
    for (di, d) in rec.dwells.iter().enumerate() {
        let a = rec.positions.vector(d.position);
        let mut ws = windows(rec, d, rules.window_span_c, rules.window_max_s);
        if ws.len() == 1 && d.len() >= 4 {
            let mid = d.start + d.len() / 2;
            ws = vec![(d.start, mid), (mid, d.end)];
        }
        for (start, end) in ws {
            let rows: Vec<usize> = (start..end)
                .filter(|k| spikes.binary_search(k).is_err())
                .collect();
            if rows.is_empty() {
                continue;
            }
            let m = rows.len() as f64;
            let mean = |f: &dyn Fn(usize) -> f64| rows.iter().map(|&k| f(k)).sum::<f64>() / m;
            out.push(DObs {
                position: d.position,
                a,
                n: rows.len(),
                start,
                end,
                dwell: di,
                chunk: 0,
                temp_c: mean(&|k| rec.rows[k].temp_c),
                t_s: mean(&|k| rec.rows[k].t_s),
                u: std::array::from_fn(|i| mean(&|k| rec.rows[k].u[i])),
            });
        }
    }
    assign_chunks(&mut out, rules);
    out
}

/// Contiguous chunks of about [`Rules::chunk_windows`] observations in time order: each
/// is held out whole, predicted from all the others (short enough that the others span
/// the same temperatures, so a held-out chunk tests the effects, not extrapolation).
fn assign_chunks(obs: &mut [DObs], rules: &Rules) {
    let n = obs.len();
    let chunks = (n / rules.chunk_windows)
        .max(rules.min_chunks)
        .min(n.max(1));
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| obs[a].t_s.total_cmp(&obs[b].t_s));
    for (rank, &i) in order.iter().enumerate() {
        obs[i].chunk = rank * chunks / n.max(1);
    }
}

/// The mean of a per-row series over each observation's rows (spikes left out).
pub fn window_means(obs: &[DObs], series: &[f64], spikes: &[usize]) -> Vec<f64> {
    obs.iter()
        .map(|o| {
            let (s, c) = (o.start..o.end)
                .filter(|k| spikes.binary_search(k).is_err())
                .fold((0.0, 0usize), |(s, c), k| (s + series[k], c + 1));
            s / c.max(1) as f64
        })
        .collect()
}
