//! Host costs against recording length: reading, identification + temperature fit,
//! diagnosis. The recordings are the blind-test profile with 3, 5 and 9 stops.
// criterion's macros define undocumented functions
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::fit::pipeline::{fit_recording, Identification, ModelChoice, ModelKind};
use host_fit::simulate::simulate;
use std::path::Path;

fn recording(stops: usize) -> String {
    let mut cfg = host_fit::blind::cases::profile(false);
    let temps = [20.0, -20.0, 10.0, 40.0, 10.0, 30.0, 0.0, 35.0, 15.0];
    cfg.schedule.stops = host_fit::blind::cases::stops(&temps[..stops], &cfg.schedule.positions);
    simulate(&cfg, |_| {}).unwrap().csv
}

fn host(c: &mut Criterion) {
    let mut g = c.benchmark_group("host");
    g.sample_size(10)
        .measurement_time(std::time::Duration::from_secs(3));
    for stops in [3usize, 5, 9] {
        let csv = recording(stops);
        let rows = csv.lines().count() as u64;
        g.throughput(Throughput::Elements(rows));
        g.bench_with_input(BenchmarkId::new("read", rows), &csv, |b, csv| {
            b.iter(|| {
                Recording::from_reader(Path::new("r.csv"), csv.as_bytes(), Positions::default())
                    .unwrap()
            })
        });
        let rec = Recording::from_reader(Path::new("r.csv"), csv.as_bytes(), Positions::default())
            .unwrap();
        let pwl = ModelChoice {
            kind: ModelKind::Pwl,
            order: None,
            breakpoints: None,
        };
        g.bench_with_input(BenchmarkId::new("fit", rows), &rec, |b, rec| {
            b.iter(|| fit_recording(rec, &pwl, Identification::Joint).unwrap())
        });
        g.bench_with_input(BenchmarkId::new("diagnose", rows), &rec, |b, rec| {
            b.iter(|| host_fit::diagnose::diagnose(rec).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, host);
criterion_main!(benches);
