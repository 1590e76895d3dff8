//! A 60 s, 1 kHz sweep (1 → 30 Hz, ±8 Nm) diagnosed with the whole torsional vocabulary by
//! forward selection: about a 40 Nm set point with a dead time (at resonance the shaft torque
//! crosses zero, so the play is profiled too), about 0 Nm (play and friction excitable), and a
//! dead time with side-shaft play about 5 Nm (a two-effect search).

#[path = "../examples/common/sweep.rs"]
mod common;
use common::sweep;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use ident::diagnose::torsional::diagnose;
use plant::rig::DriveEffects;
use plant::Variant;

fn bench(c: &mut Criterion) {
    let rig = plant::paper::damped_params();
    let mut group = c.benchmark_group("diagnose_60s_sweep");
    let delay = DriveEffects { time_delay_s: 0.005, ..Default::default() };
    let delay_and_play = DriveEffects { time_delay_s: 0.005, backlash_rad: 0.003, ..Default::default() };
    for (name, set_point, effects) in [
        ("set_point_40Nm", 40.0, delay),
        ("set_point_0Nm_with_backlash", 0.0, delay),
        ("set_point_5Nm_delay_and_play", 5.0, delay_and_play),
    ] {
        let s = sweep(set_point, effects);
        group.bench_function(name, |b| b.iter(|| diagnose(&s, &rig, Variant::V1, &|_| {}).unwrap()));
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(Duration::from_secs(20));
    targets = bench
}
criterion_main!(benches);
