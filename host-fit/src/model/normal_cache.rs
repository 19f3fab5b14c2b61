//! The normal equations of a design's baseline columns (K and U0 times the temperature
//! basis), accumulated once per data and baseline and reused by every candidate fit that
//! shares them: the diagnosis tries dozens of effects on one baseline, and the baseline's
//! block was most of each fit's work.
//!
//! A cached block is only ever used for the very values it was accumulated from: the
//! key holds the baseline's definition and a fingerprint of every value its columns read
//! (each window's chunk, temperature, force and outputs, every row's weight, T0), so a
//! caller that changes the data's windows or weights gets a new block, never a stale one.
use crate::model::basis::Basis;
use crate::model::lsq::Normal;
use crate::model::observations::DObs;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex, PoisonError};

/// Blocks kept per data (the baselines one diagnosis compares: its basis and a few
/// others).
const KEPT: usize = 4;

/// What a block was accumulated from. (This module reads the windows, not the
/// diagnosis's data or design, which hold the cache: no import in a circle.)
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Key {
    /// The baseline's definition: basis, offsets' basis, cross terms.
    baseline: Vec<u64>,
    /// The values its columns read.
    fingerprint: u64,
}

impl Key {
    /// The key of a baseline (cross terms or not, the K rows' and the offsets' bases)
    /// on windows `obs` with row weights `w` about `t0`, read at the windows' own
    /// temperatures (no thermal lag).
    pub fn of(
        cross: bool,
        basis: &Basis,
        offsets: &Basis,
        t0: f64,
        obs: &[DObs],
        w: &[f64],
    ) -> Key {
        let mut baseline = vec![u64::from(cross)];
        for b in [basis, offsets] {
            match b {
                Basis::Poly { order } => baseline.extend([0, *order as u64]),
                Basis::Pwl { breakpoints } => {
                    baseline.extend([1, breakpoints.len() as u64]);
                    baseline.extend(breakpoints.iter().map(|v| v.to_bits()));
                }
            }
        }
        let mut h = std::collections::hash_map::DefaultHasher::new();
        t0.to_bits().hash(&mut h);
        obs.len().hash(&mut h);
        for o in obs {
            o.chunk.hash(&mut h);
            o.temp_c.to_bits().hash(&mut h);
            o.a.map(f64::to_bits).hash(&mut h);
            o.u.map(f64::to_bits).hash(&mut h);
        }
        w.len().hash(&mut h);
        for v in w {
            v.to_bits().hash(&mut h);
        }
        Key {
            baseline,
            fingerprint: h.finish(),
        }
    }
}

/// Per chunk of held-out time, the normal equations of the first `columns` columns.
#[derive(Debug)]
pub struct Blocks {
    /// How many leading columns the blocks hold.
    pub columns: usize,
    /// One per chunk.
    pub chunks: Vec<Normal>,
}

impl Blocks {
    /// Accumulate the leading `columns` columns of `rows` (each in ascending column
    /// order), row `r` in chunk `chunk(r)` with right-hand side `b[r]` and weight `w[r]`.
    pub fn accumulate(
        rows: &[Vec<(usize, f64)>],
        columns: usize,
        n_chunks: usize,
        chunk: impl Fn(usize) -> usize,
        b: &[f64],
        w: &[f64],
    ) -> Blocks {
        let mut chunks: Vec<Normal> = (0..n_chunks).map(|_| Normal::new(columns)).collect();
        for (r, row) in rows.iter().enumerate() {
            let lead = row.partition_point(|e| e.0 < columns);
            chunks[chunk(r)].add_sparse(&row[..lead], b[r], w[r]);
        }
        Blocks { columns, chunks }
    }
}

/// The blocks of one data, shared by the threads fitting on it.
#[derive(Default)]
pub struct NormalCache {
    entries: Mutex<Vec<(Key, Arc<Blocks>)>>,
}

impl NormalCache {
    /// The blocks for `key`, accumulated by `make` the first time.
    pub fn get_or(&self, key: Key, make: impl FnOnce() -> Blocks) -> Arc<Blocks> {
        let lock = || self.entries.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some((_, hit)) = lock().iter().find(|(k, _)| *k == key) {
            return Arc::clone(hit);
        }
        // accumulated outside the lock: another thread may do the same meanwhile, and
        // both get equal blocks
        let made = Arc::new(make());
        let mut entries = lock();
        if entries.len() >= KEPT {
            entries.remove(0);
        }
        entries.push((key, Arc::clone(&made)));
        made
    }
}

/// A copy of the data starts with no blocks (they are found again when needed).
impl Clone for NormalCache {
    fn clone(&self) -> Self {
        NormalCache::default()
    }
}

impl std::fmt::Debug for NormalCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self
            .entries
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .len();
        write!(f, "NormalCache({n} baselines)")
    }
}
