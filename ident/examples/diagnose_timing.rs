//! One-shot timing of the torsional diagnosis on 60 s, 1 kHz records (the criterion bench
//! `cargo bench -p ident --features bench --bench diagnose` repeats them): `cargo run --release -p ident
//! --example diagnose_timing [-- NAME]` (only the cases whose name contains NAME).

#[path = "common/sweep.rs"]
mod common;
use common::sweep;
use std::time::Instant;

use ident::diagnose::torsional::diagnose;
use plant::rig::DriveEffects;
use plant::Variant;

fn main() {
    let rig = plant::paper::damped_params();
    let cases = [
        ("40 Nm, dead time", 40.0, DriveEffects { time_delay_s: 0.005, ..Default::default() }),
        (
            "0 Nm, dead time (play and friction excitable)",
            0.0,
            DriveEffects { time_delay_s: 0.005, ..Default::default() },
        ),
        (
            "5 Nm, dead time + play",
            5.0,
            DriveEffects { time_delay_s: 0.005, backlash_rad: 0.003, ..Default::default() },
        ),
        (
            "0 Nm, drive compliance + friction at M2 and M3",
            0.0,
            DriveEffects {
                compliance_stiffness_nm_per_rad: 1500.0,
                coulomb_friction_nm: [1.0, 0.0, 1.0],
                ..Default::default()
            },
        ),
    ];
    // an argument picks the cases whose name contains it (`-- compliance`)
    let pick = std::env::args().nth(1).unwrap_or_default();
    for (name, set_point, effects) in cases.into_iter().filter(|c| c.0.contains(&pick)) {
        let s = sweep(set_point, effects);
        let t0 = Instant::now();
        let d = diagnose(&s, &rig, Variant::V1, &|_| {}).unwrap();
        let found: Vec<&str> = d.effects.iter().map(|e| e.effect.as_str()).collect();
        println!(
            "{name}: {:.2} s, found {found:?}, error {:.4} → {:.4}",
            t0.elapsed().as_secs_f64(),
            d.error_before,
            d.error_after
        );
    }
}
