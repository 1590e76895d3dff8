//! A real-sized `drive_test` record (issue 32, item 7): an 8-body line with two gear stages —
//! motor, coupling hub, first pinion, first wheel (3:1), second pinion, second wheel (2.5:1),
//! flange, load — driven by the motor's torque and braked by a load machine (2 inputs), with 5
//! encoder speeds and 2 shaft torques (7 outputs), 13 s at 1 kHz. The speeds never reverse (a
//! mean torque against the drags), as on the real line the issue describes. The truth has a
//! 2 ms dead time of the motor torque; the record is simulated by `plant`'s own integrator (a
//! timing record, not a test of the answer), with noise (0.01 rad/s on the speeds, 0.5 % of the torques' standard deviation).

use plant::{Coupling, Domain, DriveModel, Effect, Line, LineBody, Quantity, TimeDelay};

/// The declared model: the line without the dead time.
pub fn declared() -> DriveModel {
    let body = |name: &str, inertia: f64, drag: f64| LineBody { name: name.into(), inertia, drag };
    DriveModel {
        line: Line {
            domain: Domain::Rotational,
            bodies: vec![
                body("motor", 0.05, 0.004),
                body("hub", 0.01, 0.0),
                body("pinion_1", 0.004, 0.0),
                body("wheel_1", 0.02, 0.002),
                body("pinion_2", 0.006, 0.0),
                body("wheel_2", 0.03, 0.003),
                body("flange", 0.02, 0.0),
                body("load", 0.8, 0.05),
            ],
            couplings: vec![
                Coupling::new(2000.0, 0.4, 1.0),
                Coupling::new(5000.0, 0.5, 1.0),
                Coupling::new(1.0e5, 5.0, 3.0),
                Coupling::new(8000.0, 0.8, 1.0),
                Coupling::new(2.0e5, 10.0, 2.5),
                Coupling::new(20_000.0, 2.0, 1.0),
                Coupling::new(15_000.0, 1.5, 1.0),
            ],
        },
        inputs: vec![0, 7],
        effects: vec![],
    }
}

/// The outputs: speeds of the motor, first pinion, first wheel, second wheel and load; the
/// torques of the motor shaft and the load shaft.
pub const OUTPUTS: [(Quantity, usize); 7] = [
    (Quantity::Speed, 0),
    (Quantity::Speed, 2),
    (Quantity::Speed, 3),
    (Quantity::Speed, 5),
    (Quantity::Speed, 7),
    (Quantity::CouplingForce, 0),
    (Quantity::CouplingForce, 6),
];

/// (inputs [motor torque, load torque], measured outputs) of the record.
pub fn record() -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let (n, dt) = (13_000usize, 1e-3);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let lines: Vec<(f64, f64)> =
        (0..40).map(|i| (0.3 * 300f64.powf(i as f64 / 39.0), std::f64::consts::TAU * uniform())).collect();
    let brake: Vec<(f64, f64)> =
        (0..10).map(|i| (0.2 * 50f64.powf(i as f64 / 9.0), std::f64::consts::TAU * uniform())).collect();
    let tau = std::f64::consts::TAU;
    let motor: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            6.0 + lines.iter().map(|(f, p)| 0.25 * (tau * f * t + p).sin()).sum::<f64>()
        })
        .collect();
    let load: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            -2.0 + brake.iter().map(|(f, p)| 0.3 * (tau * f * t + p).sin()).sum::<f64>()
        })
        .collect();
    let inputs = vec![motor, load];
    let mut truth = declared();
    truth.effects.push(Effect::TimeDelay(TimeDelay { input: 0, delay_s: 0.002 }));
    let mut y = truth.simulate(&inputs, dt, 20.0, &OUTPUTS).expect("the line simulates");
    for (o, (quantity, _)) in y.iter_mut().zip(OUTPUTS) {
        // encoders: 0.01 rad/s; torque sensors: 0.5 % of the signal's standard deviation
        let mean = o.iter().sum::<f64>() / o.len() as f64;
        let spread = (o.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / o.len() as f64).sqrt();
        let sigma = if quantity == Quantity::Speed { 0.01 } else { 0.005 * spread };
        for v in o.iter_mut() {
            *v += sigma * (2.0 * uniform() - 1.0) * 3f64.sqrt();
        }
    }
    (inputs, y)
}
