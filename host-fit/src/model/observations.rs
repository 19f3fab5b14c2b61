//! The diagnosis's observations: windows of every dwell of a known position (spikes
//! left out), and the contiguous time chunks that make its held-out folds.
use crate::data::recording::Recording;
use crate::data::stops::windows;
use crate::model::rules::Rules;

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
/// the same temperatures, so a held-out chunk tests the effects, not extrapolation). A
/// chunk also ends before it would hold more than half of the recording's positions:
/// a chunk that held every position of one stop would leave the coefficients at that
/// stop's temperature to extrapolation, and no effect at the positions could be tested
/// there.
fn assign_chunks(obs: &mut [DObs], rules: &Rules) {
    let n = obs.len();
    let chunks = (n / rules.chunk_windows)
        .max(rules.min_chunks)
        .min(n.max(1));
    let size = n.div_ceil(chunks.max(1));
    let mut positions: Vec<usize> = obs.iter().map(|o| o.position).collect();
    positions.sort_unstable();
    positions.dedup();
    let most = (positions.len() / 2).max(1);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| obs[a].t_s.total_cmp(&obs[b].t_s));
    let (mut chunk, mut count, mut held) = (0, 0, Vec::new());
    for &i in &order {
        let p = obs[i].position;
        let new_position = !held.contains(&p);
        if count > 0 && (count >= size || (new_position && held.len() >= most)) {
            chunk += 1;
            count = 0;
            held.clear();
        }
        if !held.contains(&p) {
            held.push(p);
        }
        obs[i].chunk = chunk;
        count += 1;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn window(position: usize, t_s: f64) -> DObs {
        DObs {
            position,
            a: [0.0; 3],
            n: 10,
            start: 0,
            end: 10,
            dwell: 0,
            chunk: 0,
            temp_c: 20.0,
            t_s,
            u: [0.0; 3],
        }
    }

    /// Four stops of twelve positions (two windows each) with rest windows between: no
    /// chunk holds more than half of the 13 positions (with chunks of about 40 windows
    /// alone, one chunk held a whole stop's twelve), every chunk is contiguous in time,
    /// and there are at least `min_chunks` of them.
    #[test]
    fn no_chunk_holds_a_whole_stop() {
        let rest = 12;
        let mut obs = Vec::new();
        let mut t = 0.0;
        for _stop in 0..4 {
            for _ in 0..20 {
                obs.push(window(rest, t));
                t += 60.0;
            }
            for p in 0..12 {
                for _ in 0..2 {
                    obs.push(window(p, t));
                    t += 60.0;
                }
            }
        }
        // the order the windows come in is the dwells', not time's
        obs.reverse();
        let rules = Rules::default();
        assign_chunks(&mut obs, &rules);
        let n_chunks = obs.iter().map(|o| o.chunk + 1).max().unwrap();
        assert!(n_chunks >= rules.min_chunks, "{n_chunks}");
        for c in 0..n_chunks {
            let mut held: Vec<usize> = obs
                .iter()
                .filter(|o| o.chunk == c)
                .map(|o| o.position)
                .collect();
            held.sort_unstable();
            held.dedup();
            assert!(!held.is_empty() && held.len() <= 6, "chunk {c}: {held:?}");
        }
        let mut by_time: Vec<&DObs> = obs.iter().collect();
        by_time.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        for w in by_time.windows(2) {
            assert!(w[1].chunk == w[0].chunk || w[1].chunk == w[0].chunk + 1);
        }
    }
}
