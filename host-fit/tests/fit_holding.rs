//! `Data::fit_holding`: a refit with some parameters held at given values. Held at the
//! free fit's own optimum, every other parameter comes back where the free fit put it
//! (the least-squares optimum is the same point), to 1e-9 of each parameter's scale;
//! held elsewhere, the rest moves and the chi-square rises; and `Data::evaluate` at the
//! free fit's parameters gives back its chi-square.
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::model::basis::Basis;
use host_fit::model::design::Spec;
use host_fit::model::effects::Extra;
use host_fit::model::rules::Rules;
use host_fit::model::solve::Depth;
use host_fit::model::weights::{weighed, Purpose};
use host_fit::simulate::{simulate, PerAxis, SimConfig};
use std::path::Path;

#[test]
fn holding_a_fit_at_its_optimum_changes_nothing_and_elsewhere_costs() {
    let mut cfg = SimConfig {
        seed: 3,
        ..SimConfig::default()
    };
    cfg.effects.temp_rate = Some(PerAxis {
        value: [0.02, 0.0, -0.012],
    });
    let sim = simulate(&cfg, |_| {}).unwrap();
    let rec = Recording::from_reader(Path::new("h.csv"), sim.csv.as_bytes(), Positions::default())
        .unwrap();
    let w = weighed(&rec, Rules::default(), Purpose::Diagnosis).unwrap();
    let data = &w.data;
    let spec = Spec {
        basis: Basis::Poly { order: 3 },
        offset_order: None,
        cross: true,
        extras: vec![Extra::Rate {
            tau_s: 30.0,
            centred: false,
        }],
    };
    let free = data.fit(&spec, None, Depth::Full).unwrap();
    let rate: Vec<usize> = (0..free.labels.len())
        .filter(|&j| free.labels[j].extra() == Some(0))
        .collect();
    assert_eq!(rate.len(), 3, "{:?}", free.labels);

    let same = data.evaluate(&spec, Some(&free.k_at), &free.x).unwrap();
    assert!(
        (same.chi2 - free.chi2).abs() <= 1e-9 * free.chi2,
        "{} {}",
        same.chi2,
        free.chi2
    );

    let held = data
        .fit_holding(&spec, Some(&free.k_at), &free.x, &rate)
        .unwrap();
    for j in 0..free.x.len() {
        let scale = free.x[j].abs().max(1e-12);
        assert!(
            (held.x[j] - free.x[j]).abs() <= 1e-9 * scale.max(1e-3),
            "{}: held {} free {}",
            free.labels[j],
            held.x[j],
            free.x[j]
        );
    }

    // r held 10 % low: the rest moves, and the fit is worse than the free optimum
    let mut off = free.x.clone();
    for &j in &rate {
        off[j] *= 0.9;
    }
    let moved = data
        .fit_holding(&spec, Some(&free.k_at), &off, &rate)
        .unwrap();
    for &j in &rate {
        assert_eq!(moved.x[j], off[j]);
    }
    assert!(
        moved.chi2 > free.chi2 + 100.0,
        "{} vs {}",
        moved.chi2,
        free.chi2
    );
}
