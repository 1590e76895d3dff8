//! Cost of one 60 s, 1 kHz simulation of the rig: linear, with side-shaft play (the backlash
//! candidate's unit of work), with friction at the load machines, and with both:
//! `cargo run --release -p ident --example sim_cost`.
use plant::rig::DriveEffects;
use std::time::Instant;
fn main() {
    let rig = plant::paper::damped_params();
    let u: Vec<f64> = (0..60_000).map(|k| 5.0 + 8.0 * (k as f64 * 0.01).sin()).collect();
    for (name, e) in [
        ("linear", DriveEffects::default()),
        ("backlash", DriveEffects { backlash_rad: 0.003, ..Default::default() }),
        (
            "friction",
            DriveEffects {
                coulomb_friction_nm: [1.0, 0.0, 1.0],
                friction_smoothing_radps: 0.002,
                ..Default::default()
            },
        ),
        (
            "backlash + friction",
            DriveEffects {
                backlash_rad: 0.003,
                coulomb_friction_nm: [1.0, 0.0, 1.0],
                friction_smoothing_radps: 0.002,
                ..Default::default()
            },
        ),
    ] {
        let t0 = Instant::now();
        let n = 10;
        for _ in 0..n {
            std::hint::black_box(plant::record_speeds(&rig, plant::Variant::V1, &e, &u, 1e-3, 0.0).unwrap());
        }
        println!("{name}: {:.1} ms per 60 s simulation", t0.elapsed().as_secs_f64() * 1e3 / n as f64);
    }
}
