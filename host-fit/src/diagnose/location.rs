//! Where the residual exceeds the noise: grouped by position, temperature, time,
//! temperature rate and heating/cooling direction, per axis.
use crate::diagnose::design::{Data, Fit};
use crate::fit::temperature::temperature_clusters;
use firmware_core::model::AXES;
use serde::Serialize;

/// One located mismatch: a group of observations whose residual exceeds the noise.
#[derive(Debug, Clone, Serialize)]
pub struct Hotspot {
    /// Grouping (axis, position, temperature, time, dT/dt, direction).
    pub group: String,
    /// The group's value.
    pub value: String,
    /// Axis.
    pub axis: String,
    /// RMS of the normalised residual (1 = noise).
    pub rms_sigma: f64,
    /// Mean residual, output units.
    pub mean: f64,
    /// Observations in the group.
    pub count: usize,
}

/// Every group of observations whose baseline residual exceeds twice the noise (RMS in
/// noise units), worst first.
pub fn locate(data: &Data, fit: &Fit) -> Vec<Hotspot> {
    let mut groups: Vec<(String, String, Vec<usize>)> = Vec::new();
    let mut add =
        |g: &str, v: String, idx: usize| match groups.iter_mut().find(|x| x.0 == g && x.1 == v) {
            Some(x) => x.2.push(idx),
            None => groups.push((g.to_string(), v, vec![idx])),
        };
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    let clusters = temperature_clusters(&temps);
    let t_end = data.obs.iter().map(|o| o.t_s).fold(0.0, f64::max).max(1.0);
    for (r, o) in data.obs.iter().enumerate() {
        add(
            "position",
            data.rec.positions.name(o.position).to_string(),
            r,
        );
        let c = clusters
            .iter()
            .min_by(|a, b| (*a - o.temp_c).abs().total_cmp(&(*b - o.temp_c).abs()))
            .copied()
            .unwrap_or(0.0);
        add("temperature", format!("{c:.0} C"), r);
        let bin = ((o.t_s / t_end) * 8.0).floor().min(7.0);
        add(
            "time",
            format!(
                "{:.1}-{:.1} h",
                bin * t_end / 8.0 / 3600.0,
                (bin + 1.0) * t_end / 8.0 / 3600.0
            ),
            r,
        );
        add(
            "dT/dt",
            if o.dtdt.abs() > 0.002 {
                if o.dtdt > 0.0 {
                    "heating >0.002 C/s"
                } else {
                    "cooling >0.002 C/s"
                }
            } else {
                "steady"
            }
            .to_string(),
            r,
        );
        add(
            "direction",
            match o.dir {
                d if d > 0.5 => "after heating",
                d if d < -0.5 => "after cooling",
                _ => "unknown",
            }
            .to_string(),
            r,
        );
    }
    let mut out = Vec::new();
    for (g, v, idx) in groups {
        for i in 0..3 {
            let z: Vec<f64> = idx
                .iter()
                .map(|&r| fit.resid[r][i] * (data.obs[r].n as f64).sqrt() / data.noise.sigma[i])
                .collect();
            let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
            let mean = idx.iter().map(|&r| fit.resid[r][i]).sum::<f64>() / idx.len() as f64;
            if rms > 2.0 {
                out.push(Hotspot {
                    group: g.clone(),
                    value: v.clone(),
                    axis: AXES[i].into(),
                    rms_sigma: rms,
                    mean,
                    count: idx.len(),
                });
            }
        }
    }
    out.sort_by(|a, b| b.rms_sigma.total_cmp(&a.rms_sigma));
    out
}
