//! A 60 s, 1 kHz sweep (1 → 30 Hz, ±8 Nm) diagnosed with the whole torsional vocabulary by
//! forward selection: about a 40 Nm set point with a dead time (at resonance the shaft torque
//! crosses zero, so the play is profiled too), about 0 Nm (play and friction excitable), and a
//! dead time with side-shaft play about 5 Nm (a two-effect search).

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use ident::diagnose::torsional::diagnose;
use ident::Sweep;
use plant::effects::{DriveEffects, Powertrain};
use plant::Variant;

fn sweep(set_point: f64, effects: DriveEffects) -> Sweep {
    let rig = plant::paper::damped_params();
    let n = 60_000;
    let dt = 1e-3;
    let torque: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            set_point + 8.0 * (2.0 * std::f64::consts::PI * (t + 0.5 * 29.0 / 60.0 * t * t)).sin()
        })
        .collect();
    let truth = Powertrain::new(&rig, Variant::V1, &effects).unwrap();
    let (w2, w3) = truth.simulate(&torque, dt, set_point).unwrap();
    Sweep { dt_s: dt, torque_nm: torque, speed_m2_radps: w2, speed_m3_radps: w3 }
}

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
