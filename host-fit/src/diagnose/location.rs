//! Where a residual (or an effect's contribution) stands out from the floor: grouped by
//! position, temperature, time, temperature rate and heating/cooling direction, per axis.
use crate::model::basis::temperature_clusters;
use crate::model::data::Data;
use firmware_core::model::AXES;
use serde::Serialize;

/// How windows are grouped to locate a residual.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str")]
#[strum(serialize_all = "lowercase")]
pub enum Grouping {
    /// By position.
    Position,
    /// By the stop temperature nearest the window's.
    Temperature,
    /// By an eighth of the recording's time.
    Time,
    /// Heating, cooling or steady.
    #[strum(serialize = "dT/dt")]
    Rate,
    /// After heating, after cooling, or before the first change.
    Direction,
}

impl Grouping {
    /// The contract's name (Display pads and aligns it as a string).
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

/// One located group: its values in floor units.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Hotspot {
    /// Grouping (position, temperature, time, dT/dt, direction).
    pub group: Grouping,
    /// The group's value.
    pub value: String,
    /// Axis.
    pub axis: String,
    /// RMS in floor units (1 = noise).
    pub rms_sigma: f64,
    /// Mean of the values, output units.
    pub mean: f64,
    /// Share of the whole sum of squares that sits in this group.
    pub share: f64,
    /// Observations in the group.
    pub count: usize,
}

/// One group of windows.
struct Group {
    by: Grouping,
    value: String,
    windows: Vec<usize>,
}

/// The groups every observation belongs to.
fn groups(data: &Data) -> Vec<Group> {
    let mut groups: Vec<Group> = Vec::new();
    let mut add = |by: Grouping, value: String, idx: usize| match groups
        .iter_mut()
        .find(|x| x.by == by && x.value == value)
    {
        Some(x) => x.windows.push(idx),
        None => groups.push(Group {
            by,
            value,
            windows: vec![idx],
        }),
    };
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    let clusters = temperature_clusters(&temps);
    let (t_lo, t_hi) = data
        .obs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), o| {
            (a.min(o.t_s), b.max(o.t_s))
        });
    let span = (t_hi - t_lo).max(1.0);
    for (r, o) in data.obs.iter().enumerate() {
        add(
            Grouping::Position,
            data.rec.positions.name(o.position).to_string(),
            r,
        );
        let c = clusters
            .iter()
            .min_by(|a, b| (*a - o.temp_c).abs().total_cmp(&(*b - o.temp_c).abs()))
            .copied()
            .unwrap_or(0.0);
        add(Grouping::Temperature, format!("{c:.0} C"), r);
        let bin = (((o.t_s - t_lo) / span) * 8.0).floor().min(7.0);
        let h = |b: f64| (t_lo + b * span / 8.0) / 3600.0;
        add(
            Grouping::Time,
            format!("{:.1}-{:.1} h", h(bin), h(bin + 1.0)),
            r,
        );
        let (rate, steady) = (data.rate[r], data.rules.steady_rate_c_per_s);
        let rate_group = if rate > steady {
            format!("heating >{steady} C/s")
        } else if rate < -steady {
            format!("cooling >{steady} C/s")
        } else {
            "steady".to_string()
        };
        add(Grouping::Rate, rate_group, r);
        let (d, m) = (data.dir[r], data.rules.direction_majority);
        let dir = if d > m {
            "after heating"
        } else if d < -m {
            "after cooling"
        } else {
            "before the first change"
        };
        add(Grouping::Direction, dir.to_string(), r);
    }
    groups
}

/// Every group where `z` (per observation and axis, floor units) has an RMS above
/// `min_rms` and at least [`crate::model::rules::Rules::located_share`] of the sum of
/// squares, worst first; `raw` gives the means in output units. (A group of two windows
/// can be extreme and still not be where the mismatch is.)
pub fn locate(data: &Data, z: &[[f64; 3]], raw: &[[f64; 3]], min_rms: f64) -> Vec<Hotspot> {
    let total: f64 = z
        .iter()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    for Group {
        by,
        value,
        windows: idx,
    } in groups(data)
    {
        for i in 0..3 {
            let ss: f64 = idx.iter().map(|&r| z[r][i] * z[r][i]).sum();
            let rms = (ss / idx.len() as f64).sqrt();
            if rms > min_rms && ss / total >= data.rules.located_share {
                out.push(Hotspot {
                    group: by,
                    value: value.clone(),
                    axis: AXES[i].into(),
                    rms_sigma: rms,
                    mean: idx.iter().map(|&r| raw[r][i]).sum::<f64>() / idx.len() as f64,
                    share: ss / total,
                    count: idx.len(),
                });
            }
        }
    }
    out.sort_by(|a, b| b.rms_sigma.total_cmp(&a.rms_sigma));
    out
}

/// The residual rows (`3 * window + axis`) of the located group `h`: where a re-search
/// looks for what the model still misses.
pub fn rows_of(data: &Data, h: &Hotspot) -> Vec<usize> {
    let Some(axis) = AXES.iter().position(|a| *a == h.axis) else {
        return Vec::new();
    };
    groups(data)
        .into_iter()
        .find(|g| g.by == h.group && g.value == h.value)
        .map(|g| g.windows.iter().map(|&r| 3 * r + axis).collect())
        .unwrap_or_default()
}
