//! The baseline's polynomial orders (`baseline::Orders`): chamber ramps logged at the
//! rest position count as temperatures for the offsets' order, not for the K rows',
//! which need four positions each seen at that many temperatures, and the candidates
//! then hold the offsets one order up between the K rows' count and the next; a
//! recording of the dwells alone gives both the same count and the same candidates as
//! before; and a blob whose offsets carry an order above the K rows' holds that model
//! exactly (its polynomial table against the fit's own coefficients, which the table
//! grid reads through the design's `static_at`); under a broad `temp_curvature`, whose
//! fine basis replaces the offsets' polynomial, the model's text and orders say so.
use firmware_core::temperature::TempModel;
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::model::baseline;
use host_fit::model::effects::Extra;
use host_fit::model::flashed::Flashed;
use host_fit::model::orders::Orders;
use host_fit::model::rules::Rules;
use host_fit::model::solve::Depth;
use host_fit::model::weights::{weighed, Purpose};
use host_fit::simulate::{simulate, SimConfig};
use std::path::Path;

fn recording(cfg: &SimConfig) -> Recording {
    let sim = simulate(cfg, |_| {}).unwrap();
    Recording::from_reader(Path::new("o.csv"), sim.csv.as_bytes(), Positions::default()).unwrap()
}

/// The twin's five stops (-40 to 70 C), its ramps logged at the rest position.
fn twin(rest_unnamed: bool) -> SimConfig {
    let mut c = SimConfig {
        seed: 5,
        ..SimConfig::default()
    };
    c.logger.rest_rate_hz = 0.1;
    c.logger.rest_unnamed = rest_unnamed;
    c
}

#[test]
fn ramps_at_rest_raise_the_offsets_order_only() {
    let stops = twin(false).schedule.stops.len();
    assert_eq!(stops, 5, "the twin's stops");
    let rec = recording(&twin(false));
    let w = weighed(&rec, Rules::default(), Purpose::Diagnosis).unwrap();
    let o = Orders::of(&w.data);
    // the K rows: four positions at five temperatures each; the offsets: the ramps at
    // rest add temperatures up to the rules' cap
    assert_eq!(o.k, stops - 1, "{o:?}");
    assert_eq!(o.offsets, Rules::default().max_order, "{o:?}");
    assert_eq!(baseline::max_order(&w.data), o.offsets);
    // every candidate nested in the next: each order for all twelve, and between the K
    // rows' highest and the next, the offsets alone one order up
    let c = o.candidates();
    assert_eq!(
        c,
        vec![(0, 0), (1, 1), (2, 2), (3, 3), (4, 4), (4, 5), (5, 5)],
        "{o:?}"
    );
    assert!(c
        .windows(2)
        .all(|p| p[1].0 >= p[0].0 && p[1].1 >= p[0].1 && p[1].0 + p[1].1 > p[0].0 + p[0].1));

    // the dwells alone: the same temperatures for both
    let rec = recording(&twin(true));
    let w = weighed(&rec, Rules::default(), Purpose::Diagnosis).unwrap();
    let o = Orders::of(&w.data);
    assert_eq!(
        o,
        Orders {
            k: stops - 1,
            offsets: stops - 1
        }
    );
    assert_eq!(
        o.candidates(),
        (0..stops).map(|n| (n, n)).collect::<Vec<_>>()
    );
}

#[test]
fn an_offsets_order_above_the_k_rows_is_flashed_exactly() {
    let rec = recording(&twin(false));
    let w = weighed(&rec, Rules::default(), Purpose::Diagnosis).unwrap();
    let data = &w.data;
    let (base, _) = baseline::required(data).unwrap();
    // the shape the candidates give: the K rows' count, the offsets one order up
    let spec = base.spec.with_orders(4, 5);
    assert_eq!(spec.poly_orders(), Some(Orders { k: 4, offsets: 5 }));
    assert_eq!(spec.temperature_model(), "poly4, offsets poly5");
    // a broad temp_curvature's fine basis replaces the offsets' polynomial: the text and
    // the orders say what is fitted
    let fine = spec.with(Extra::Curvature(vec![-40.0, 0.0, 40.0, 70.0]));
    assert_eq!(fine.poly_orders(), Some(Orders { k: 4, offsets: 4 }));
    assert_eq!(fine.temperature_model(), "poly4");
    let f = data.fit(&spec, None, Depth::Full).unwrap();
    // the offsets' terms beyond the K rows' order are in the design, and nonzero
    assert!(f
        .labels
        .iter()
        .any(|l| format!("{l}").starts_with("u0") && format!("{l}").ends_with("#5")));
    let flashed = Flashed::of(data, &f, 1e-6);
    let (cal, _) = flashed.calibration(data.t0, None).unwrap();
    let TempModel::Poly { terms } = &cal.model else {
        panic!("not the polynomial itself: {:?}", cal.model);
    };
    assert_eq!(terms.len(), 6, "quintic offsets");
    // the K slots carry no quintic term; the offsets do
    let top = &terms[5];
    assert!(
        firmware_core::model::K_INDEX
            .iter()
            .flatten()
            .all(|s| top[*s] == 0.0),
        "{top:?}"
    );
    assert!(firmware_core::model::U0_INDEX
        .iter()
        .any(|s| top[*s] != 0.0));
    // the polynomial the blob carries is the fit's model at every grid temperature (the
    // table is the fit's coefficients through the design): to 1e-12 of each coefficient
    for (t, row) in &flashed.table {
        let got = cal.model.eval(data.t0, *t);
        for (g, want) in got.iter().zip(row) {
            assert!(
                (g - want).abs() <= 1e-12 * want.abs().max(1e-3),
                "at {t} C: {got:?} against {row:?}"
            );
        }
    }
}
