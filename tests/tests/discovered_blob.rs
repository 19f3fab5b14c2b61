//! A term no catalogue names, found in the data and compensated on the MCU's code path:
//! a twin unit with a cubic response K3 on y (`a_y^3`) on a design that identifies it
//! (TP1..TP6 and the 12 edge diagonals), diagnosed; the finding names `a_y^3` on y with
//! its coefficient near the truth, `diagnose`'s blob carries it in its term table
//! (format 5), and firmware-core, reading that blob, compensates the edge positions
//! better than the same blob without the term does.
use firmware_core::blob::Blob;
use firmware_core::compensate::{Compensator, Method};
use host_fit::blind::designs::{positions_of, Design, PositionSet, Power};
use host_fit::blob::{build_blob, build_blob_with_terms};
use host_fit::data::recording::Recording;
use host_fit::diagnose::search::Termination;
use host_fit::diagnose::{diagnose, EffectId};
use host_fit::simulate::{simulate, PerAxis, SimConfig};
use host_fit::terms::{Factor, Term};
use std::path::Path;

/// The K3 coefficient on y, V/g^3 (the twin's scale factor is about 1 V/g): 0.3 mg of
/// the 1-g output at the axes, 0.1 mg at the diagonals.
const K3_Y: f64 = 3e-4;

fn unit() -> SimConfig {
    let mut c = SimConfig {
        seed: 7,
        ..SimConfig::default()
    };
    Design {
        positions: PositionSet::Edges,
        power: Power::Steady,
        turning: false,
    }
    .apply(&mut c);
    c.effects.nonlinearity_k3 = Some(PerAxis {
        value: [0.0, K3_Y, 0.0],
    });
    c
}

/// The worst over the edge diagonals of the mean of |a| - 1 (g) over each diagonal's
/// rows (the rows' own noise averaged out), through firmware-core with the blob's tables
/// and terms.
fn worst_edge_error(rec: &Recording, blob: &Blob) -> f64 {
    let mut comp = Compensator::with_terms(
        &blob.calibration,
        blob.terms.as_slice(),
        Method::CorrectConstants,
        1.0,
    )
    .unwrap();
    let mut sums: std::collections::BTreeMap<usize, (f64, usize)> = Default::default();
    for r in &rec.rows {
        let Some(p) = r.position else { continue };
        if !rec.positions.name(p).starts_with('E') {
            continue;
        }
        let u = r.u.map(|v| v as f32);
        let a = comp.compensate(u, r.temp_c as f32).accel;
        let g = a.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>().sqrt();
        let e = sums.entry(p).or_default();
        e.0 += g - 1.0;
        e.1 += 1;
    }
    assert_eq!(sums.len(), 12, "the 12 edge diagonals");
    sums.values()
        .map(|(s, n)| (s / *n as f64).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_cubic_response_is_found_flashed_and_compensated_by_the_firmware() {
    let cfg = unit();
    let sim = simulate(&cfg, |_| {}).unwrap();
    let rec = Recording::from_reader(Path::new("k3.csv"), sim.csv.as_bytes(), positions_of(&cfg))
        .unwrap();
    let d = diagnose(&rec).unwrap();
    let found: Vec<_> = d
        .findings
        .iter()
        .filter(|f| f.effect == EffectId::Discovered)
        .collect();
    assert_eq!(found.len(), 1, "{}", d.contract().text());
    let cube = Term::new([Factor::Ay; 3]).unwrap();
    assert_eq!(found[0].term.as_ref(), Some(&cube), "a_y^3");
    // the catalogue's search left a rest it could not name; the library's phase found
    // the term and ended with the rest at the floor
    assert_ne!(
        d.search_ended.catalogue,
        Termination::AtFloor,
        "{:?}",
        d.search_ended
    );
    assert_eq!(
        d.search_ended.library,
        Termination::AtFloor,
        "{:?}",
        d.search_ended
    );
    assert_eq!(found[0].axes, ["y"]);
    assert!(
        d.findings.iter().all(|f| f.effect == EffectId::Discovered),
        "no catalogue name: {}",
        d.contract().text()
    );
    let terms = d.terms().unwrap();
    assert_eq!(terms.len(), 1);
    assert_eq!(terms[0].term.to_string(), "a_y^3");
    let c = terms[0].coefficient;
    assert!(
        (c - K3_Y).abs() < 0.1 * K3_Y,
        "coefficient {c:e}, truth {K3_Y:e}"
    );
    let cal = d.calibration(rec.t0_c).unwrap();
    let (with, bytes, (dep, _)) =
        build_blob_with_terms("K3-1", &rec.output_unit, &cal, &terms).unwrap();
    // format 5: the table of discovered terms, read back by the firmware's decoder
    assert_eq!(u16::from_le_bytes([bytes[4], bytes[5]]), 5);
    assert!(dep <= host_fit::model::precision::F32_BOUND_G);
    let read = Blob::decode(&bytes).unwrap();
    assert_eq!(read.terms.len(), 1);
    let (without, plain, _) = build_blob("K3-1", &rec.output_unit, &cal).unwrap();
    assert_eq!(u16::from_le_bytes([plain[4], plain[5]]), 4);
    let (e_with, e_without) = (
        worst_edge_error(&rec, &read),
        worst_edge_error(&rec, &without),
    );
    assert_eq!(worst_edge_error(&rec, &with), e_with);
    // without the term the scale factor takes K3 at the axes (a_y = 1); at a diagonal
    // (a_y = 1/sqrt 2) |a| is then off by K3 (a_y - a_y^3) a_y = 0.075 mg: the term must
    // take off at least half of that
    let a = std::f64::consts::FRAC_1_SQRT_2;
    let size = K3_Y * (a - a.powi(3)) * a;
    assert!(
        e_with < e_without - 0.5 * size,
        "with the term {e_with:e} g, without {e_without:e} g (the term's size {size:e} g)"
    );
}
