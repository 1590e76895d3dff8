//! The 60 s, 1 kHz sweep (1 → 30 Hz, ±8 Nm about a set point) of the paper's rig with drive
//! effects that the diagnosis timing example and the criterion bench diagnose, its speeds with
//! 2 mrad/s of white sensor noise (as `tests/diagnose_several.rs`' records: a real record is
//! never exact, and a noise-free one would keep the selection going on round-off).

use ident::Sweep;
use plant::rig::DriveEffects;
use plant::Variant;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// The sweep of the damped paper rig (V1) with `effects` about `set_point` Nm.
pub fn sweep(set_point: f64, effects: DriveEffects) -> Sweep {
    let rig = plant::paper::damped_params();
    let (n, dt) = (60_000, 1e-3);
    let torque: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            set_point + 8.0 * (2.0 * std::f64::consts::PI * (t + 0.5 * 29.0 / 60.0 * t * t)).sin()
        })
        .collect();
    let (mut w2, mut w3) =
        plant::record_speeds(&rig, Variant::V1, &effects, &torque, dt, set_point).expect("the sweep simulates");
    let mut rng = StdRng::seed_from_u64(1);
    let noise = Normal::new(0.0, 0.002).expect("a normal distribution");
    for w in w2.iter_mut().chain(w3.iter_mut()) {
        *w += noise.sample(&mut rng);
    }
    Sweep { dt_s: dt, torque_nm: torque, speed_m2_radps: w2, speed_m3_radps: w3 }
}
