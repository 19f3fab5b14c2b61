//! The start of every fit on the engine: the floor measured inside the dwells, the
//! windows built, and each weighted by the floor (or, where the floor cannot be
//! measured, by the scatter the most general static model leaves); too few windows is
//! an error naming the file.
use crate::data::recording::Recording;
use crate::error::{ErrorKind, HostError, Result};
use crate::model::baseline;
use crate::model::basis::Basis;
use crate::model::data::Data;
use crate::model::design::Spec;
use crate::model::effects::Extra;
use crate::model::floor::{self, Floor};
use crate::model::rules::Rules;
use crate::model::solve::Depth;

/// What the windows are for (said when there are too few of them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Purpose {
    /// `diagnose`.
    Diagnosis,
    /// `fit`'s dynamic route.
    DynamicRoute,
}

impl Purpose {
    fn words(self) -> &'static str {
        match self {
            Purpose::Diagnosis => "to diagnose",
            Purpose::DynamicRoute => "for the dynamic route",
        }
    }
}

/// A recording's windows weighted by its floor.
#[derive(Debug, Clone)]
pub struct Weighed<'a> {
    /// The windows, their weights and the rules.
    pub data: Data<'a>,
    /// The measured floor.
    pub floor: Floor,
    /// Whether the floor was measured (else the static model's scatter stands in).
    pub measured: bool,
}

/// The floor of `rec`, its windows and their weights (see the module doc); an error when
/// there are fewer windows than [`Rules::min_windows`].
pub fn weighed(rec: &Recording, rules: Rules, purpose: Purpose) -> Result<Weighed<'_>> {
    let floor = floor::floor(rec, &rules);
    let mut data = Data::new(rec, &floor, rules);
    if data.obs.len() < rules.min_windows {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            &rec.path,
            format!(
                "{} static windows of known positions: too few {} (need {}, e.g. 6 positions)",
                data.obs.len(),
                purpose.words(),
                rules.min_windows
            ),
        ));
    }
    let measured = weigh(&mut data, &floor);
    Ok(Weighed {
        data,
        floor,
        measured,
    })
}

/// Weights from the floor, or (floor not measurable) from the scatter per axis that the
/// most general static model leaves (the baseline with every static catalogue term the
/// positions determine: what none of the candidates could explain is the floor).
/// Whether the floor was measured.
pub fn weigh(data: &mut Data, floor: &Floor) -> bool {
    // a floor of zero (samples that repeat exactly, no grid found) weighs nothing
    let measured = floor
        .axes
        .iter()
        .all(|a| a.var_of_mean(1.0).is_some_and(|v| v > 0.0 && v.is_finite()));
    if measured {
        // a quantised axis below its step repeats one rounding error wherever the
        // position reads the same level: its windows of one position are one piece of
        // information, not many (else that error, fixed per position, looks like a
        // fixture error)
        let mut per_position = std::collections::HashMap::new();
        for o in &data.obs {
            *per_position.entry(o.position).or_insert(0usize) += 1;
        }
        data.w = data
            .obs
            .iter()
            .flat_map(|o| {
                let shared = per_position[&o.position] as f64;
                (0..3).map(move |i| {
                    let a = &floor.axes[i];
                    let v = a.var_of_mean(o.n as f64).unwrap_or(1.0);
                    1.0 / if a.quantum.is_some() { v * shared } else { v }
                })
            })
            .collect();
        return true;
    }
    data.w = vec![1.0; data.n_rows()];
    if let Some((b, _)) = baseline::baseline(data) {
        let general = [vec![Extra::K2, Extra::Asymmetry], vec![Extra::K2], vec![]]
            .into_iter()
            .find_map(|extras| {
                let spec = Spec {
                    extras,
                    basis: Basis::Poly {
                        order: baseline::max_order(data),
                    },
                    offset_order: None,
                    ..b.spec.clone()
                };
                data.fit(&spec, None, Depth::Profile)
            })
            .unwrap_or(b);
        let per_axis: [f64; 3] = std::array::from_fn(|i| {
            let ss: f64 = general.resid.iter().map(|r| r[i] * r[i]).sum();
            let dof = data.obs.len().saturating_sub(general.k.div_ceil(3));
            (ss / dof.max(1) as f64).max(1e-300)
        });
        data.w = (0..data.n_rows()).map(|r| 1.0 / per_axis[r % 3]).collect();
    }
    false
}
