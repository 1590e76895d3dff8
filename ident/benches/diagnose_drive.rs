//! A 60 s, 1 kHz `drive_test` record of a three-body line (motor – shaft – hub – 4:1 gear –
//! load) with three outputs diagnosed with the whole vocabulary (friction at each body, play in
//! each coupling, dead time and lag of the input, damping, none); the truth has friction at the
//! load (issue 14: ≤ 3 s median on the 2-core machine).

#[path = "../examples/common/drive_record.rs"]
mod common;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use ident::diagnose::drive::{diagnose, DriveRecord};

fn bench(c: &mut Criterion) {
    let model = common::declared();
    let (u, y) = common::record(0.3);
    let inputs = [u];
    let rec = DriveRecord { model: &model, inputs: &inputs, outputs: &common::OUTPUTS, measured: &y, dt_s: 1e-3 };
    c.bench_function("diagnose_drive_test_60s_3_bodies_3_outputs", |b| b.iter(|| diagnose(rec, &|_| {}).unwrap()));
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(Duration::from_secs(15));
    targets = bench
}
criterion_main!(benches);
