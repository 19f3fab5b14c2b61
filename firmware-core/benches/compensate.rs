//! Per-sample cost of the compensator, the temperature update, and blob decoding.
// criterion's macros define undocumented functions
#![allow(missing_docs)]

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use firmware_core::blob::{example_blob, example_blob_bytes, example_physics, Blob};
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::temperature::{Calibration, TempModel};

fn per_sample(c: &mut Criterion) {
    let blob = example_blob();
    let mut with_phys = blob.calibration.clone();
    with_phys.physics = Some(example_physics());
    let u = [0.0045f32, -0.0044, -0.5521];
    let mut g = c.benchmark_group("sample");
    for (name, cal, m) in [
        ("method1", &blob.calibration, Method::CorrectConstants),
        (
            "method2_full",
            &blob.calibration,
            Method::CorrectResult(ErrorModel::Full),
        ),
        (
            "method2_simplified",
            &blob.calibration,
            Method::CorrectResult(ErrorModel::Simplified),
        ),
        ("method1_physics", &with_phys, Method::CorrectConstants),
        (
            "method2_full_physics",
            &with_phys,
            Method::CorrectResult(ErrorModel::Full),
        ),
    ] {
        let mut comp = Compensator::new(cal, m, 0.01).unwrap();
        comp.compensate(u, 21.0);
        g.bench_function(name, |b| {
            b.iter(|| comp.compensate(black_box(u), black_box(21.0)))
        });
    }
    g.finish();
}

fn table(poly: Option<usize>, pwl: Option<usize>) -> Calibration<f32> {
    let mut cal = example_blob().calibration;
    let t0 = cal.at_t0();
    cal.update_step_c = 0.0;
    cal.model = match (poly, pwl) {
        (Some(order), _) => TempModel::Poly {
            terms: (0..=order)
                .map(|k| if k == 0 { t0 } else { [1e-6 / k as f32; 12] })
                .collect(),
        },
        (_, Some(n)) => TempModel::Pwl {
            breakpoints: (0..n)
                .map(|k| -40.0 + 110.0 * k as f32 / (n - 1) as f32)
                .collect(),
            values: (0..n)
                .map(|k| t0.map(|v| v * (1.0 + 1e-5 * k as f32)))
                .collect(),
        },
        _ => cal.model,
    };
    cal
}

fn update(c: &mut Criterion) {
    let u = [0.0045f32, -0.0044, -0.5521];
    let mut g = c.benchmark_group("update");
    let cases: Vec<(String, Calibration<f32>)> = (1..=5)
        .map(|o| (format!("poly{o}"), table(Some(o), None)))
        .chain(
            [2usize, 4, 8, 16]
                .iter()
                .map(|n| (format!("pwl{n}"), table(None, Some(*n)))),
        )
        .collect();
    for (name, cal) in &cases {
        let mut comp = Compensator::new(cal, Method::CorrectConstants, 0.01).unwrap();
        let mut k = 0u32;
        // the temperature moves on every call: an update (12 models + the inverse) each time
        g.bench_function(name.as_str(), |b| {
            b.iter(|| {
                k = k.wrapping_add(1);
                let t = if k & 1 == 0 { -12.5 } else { 33.0 };
                comp.compensate(black_box(u), black_box(t))
            })
        });
    }
    g.finish();
}

fn decode(c: &mut Criterion) {
    let bytes = example_blob_bytes();
    c.bench_function("decode/pwl3", |b| {
        b.iter(|| Blob::decode(black_box(&bytes)).unwrap())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = per_sample, update, decode
}
criterion_main!(benches);
