//! Cost of one simulation of a `drive_test` line with play (the unit of work of a play's
//! screen, which grids the play over five decades): the three-body line of
//! `common/drive_record.rs`, 60 s at 1 kHz, play at either coupling from 1e-5 to 1e-1 rad,
//! alone and beside a friction at the load; with the samples whose whole step left its piece
//! and the RK4 sub-steps they took. `cargo run --release -p ident --example play_sim_cost`;
//! `-- --bench-gear` runs `../shared/data/bench_gear`'s stiffer line (30 s at 1 kHz) instead.

#[path = "common/drive_record.rs"]
mod common;
use std::time::Instant;

use plant::drive::{Dynamics, HeldInputs};
use plant::{Backlash, CoulombFriction, Effect};

fn main() {
    let bench = std::env::args().any(|a| a == "--bench-gear");
    let (u, dt, declared) = if bench { bench_gear() } else { (common::record(0.3).0, 1e-3, common::declared()) };
    let friction = Effect::CoulombFriction(CoulombFriction { body: 2, friction: 0.3, smoothing_speed: 0.01 });
    for with_friction in [false, true] {
        for coupling in [0, 1] {
            for play in [1e-5, 1e-4, 1e-3, 1e-2, 1e-1] {
                let mut m = declared.clone();
                m.effects = vec![Effect::Backlash(Backlash { coupling, backlash: play })];
                if with_friction {
                    m.effects.insert(0, friction);
                }
                let t0 = Instant::now();
                let y = m.simulate(std::slice::from_ref(&u), dt, 0.0, &common::OUTPUTS);
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                let d = Dynamics::new(&m).unwrap();
                let mut rk = d.integrator();
                let exact = d.exact_steps(&[dt]);
                let mut x = d.initial_state(0.0, &[u[0]]);
                let (mut split, mut fine) = (0usize, 0usize);
                let mut piece = None;
                for &uk in &u {
                    let maps = exact.as_ref().and_then(|e| e.first());
                    let (taken, p) = rk.advance_from(&mut HeldInputs { d: &d, u: &[uk], maps }, &mut x, dt, piece);
                    piece = p;
                    split += usize::from(taken > 0);
                    fine += taken;
                }
                println!(
                    "{}play {play:.0e} rad at coupling {}: {ms:.1} ms{}, {split} of {} samples sub-stepped, {fine} fine steps",
                    if with_friction { "friction + " } else { "" },
                    coupling + 1,
                    if y.is_ok() { "" } else { " (failed)" },
                    u.len()
                );
            }
        }
    }
}

/// `../shared/data/bench_gear`'s input and declared line, read as `rigtwin diagnose` reads them.
fn bench_gear() -> (Vec<f64>, f64, plant::DriveModel) {
    let bundle = std::path::Path::new("../shared/data/bench_gear.toml");
    let m = modelfile::drive::load_drive_model(bundle).unwrap_or_else(|e| panic!("{e}"));
    let text = std::fs::read_to_string("../shared/data/bench_gear.csv").expect("../shared/data/bench_gear.csv");
    let u = text.lines().skip(1).map(|l| l.split(',').nth(1).unwrap().parse().unwrap()).collect();
    (u, 1e-3, m)
}
