//! The whole `drive_test` diagnosis of a real-sized record (issue 32, item 7): an 8-body line
//! with two gear stages, 2 inputs and 7 outputs, 13 s at 1 kHz (`examples/common/line_record.rs`).
//! The target: ≤ 10 s median on the 2-core machine.

#[path = "../examples/common/line_record.rs"]
mod common;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use ident::diagnose::drive::{diagnose, DriveRecord};

fn bench(c: &mut Criterion) {
    let model = common::declared();
    let (inputs, y) = common::record();
    let rec = DriveRecord { model: &model, inputs: &inputs, outputs: &common::OUTPUTS, measured: &y, dt_s: 1e-3 };
    let d = diagnose(rec, &|_| {}).expect("the record is diagnosed");
    eprintln!(
        "answer: {} {:?} {:?}, error {:.4} -> {:.4}",
        d.effect, d.at, d.parameters, d.error_before, d.error_after
    );
    c.bench_function("diagnose_drive_test_13s_8_bodies_2_gear_stages_2_inputs_7_outputs", |b| {
        b.iter(|| diagnose(rec, &|_| {}).unwrap())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(Duration::from_secs(30));
    targets = bench
}
criterion_main!(benches);
