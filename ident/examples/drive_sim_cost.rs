//! Cost of one simulation of a `drive_test` line with a friction, alone and beside an input's
//! lag or dead time (the unit of work of a second effect beside a friction): the three-body
//! line of `common/drive_record.rs`, 60 s at 1 kHz, friction 0.3 N·m at the load.
//! `cargo run --release -p ident --example drive_sim_cost`.

#[path = "common/drive_record.rs"]
mod common;
use std::time::Instant;

use plant::{ActuatorLag, CoulombFriction, Effect, TimeDelay};

fn main() {
    let (u, _) = common::record(0.3);
    let inputs = [u];
    let friction = Effect::CoulombFriction(CoulombFriction { body: 2, friction: 0.3, smoothing_speed: 0.01 });
    let cases: Vec<(String, Vec<Effect>)> = vec![
        ("friction".into(), vec![friction]),
        ("lag 0.3 ms".into(), vec![Effect::ActuatorLag(ActuatorLag { input: 0, time_constant_s: 3e-4 })]),
        ("dead time 2.5 ms".into(), vec![Effect::TimeDelay(TimeDelay { input: 0, delay_s: 2.5e-3 })]),
    ]
    .into_iter()
    .chain([3e-4, 3e-3, 3e-2].map(|tau| {
        (
            format!("friction + lag {:.1} ms", tau * 1e3),
            vec![friction, Effect::ActuatorLag(ActuatorLag { input: 0, time_constant_s: tau })],
        )
    }))
    .chain([5e-4, 2.5e-3].map(|d| {
        (
            format!("friction + dead time {:.1} ms", d * 1e3),
            vec![friction, Effect::TimeDelay(TimeDelay { input: 0, delay_s: d })],
        )
    }))
    .collect();
    for (name, effects) in cases {
        let mut m = common::declared();
        m.effects = effects;
        let t0 = Instant::now();
        let y = m.simulate(&inputs, 1e-3, 0.0, &common::OUTPUTS);
        println!("{name}: {:.1} ms{}", t0.elapsed().as_secs_f64() * 1e3, if y.is_ok() { "" } else { " (failed)" });
    }
}
