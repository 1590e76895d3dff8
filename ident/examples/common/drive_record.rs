//! The 60 s, 1 kHz `drive_test` record of a three-body line that the drive diagnosis timing
//! example and the criterion bench diagnose: motor – shaft – hub – 4:1 gear stage – load,
//! driven at the motor by a multisine (0.2–40 Hz) with a slow component that reverses the
//! speeds; three outputs (motor speed, load speed, the shaft's torque sensor); the truth has
//! Coulomb friction at the load, simulated with 10 RK4 sub-steps per sample and tanh friction
//! (not the diagnosis's path), 0.5 % noise.

use plant::{Coupling, Domain, DriveModel, Line, LineBody, Quantity};

/// The declared model: the line without the friction.
pub fn declared() -> DriveModel {
    DriveModel {
        line: Line {
            domain: Domain::Rotational,
            bodies: vec![
                LineBody { name: "motor".into(), inertia: 0.02, drag: 0.002 },
                LineBody { name: "hub".into(), inertia: 0.01, drag: 0.0 },
                LineBody { name: "load".into(), inertia: 0.3, drag: 0.01 },
            ],
            couplings: vec![Coupling::new(400.0, 0.2, 1.0), Coupling::new(3000.0, 0.5, 4.0)],
        },
        inputs: vec![0],
        effects: vec![],
    }
}

/// The outputs: motor speed, load speed, the shaft's torque.
pub const OUTPUTS: [(Quantity, usize); 3] = [(Quantity::Speed, 0), (Quantity::Speed, 2), (Quantity::CouplingForce, 0)];

/// (input torque, measured outputs) of the record: friction `friction_nm` at the load.
pub fn record(friction_nm: f64) -> (Vec<f64>, Vec<Vec<f64>>) {
    let (n, dt, sub) = (60_000usize, 1e-3, 10usize);
    let m = declared();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let lines: Vec<(f64, f64)> =
        (0..30).map(|i| (0.2 * 200f64.powf(i as f64 / 29.0), std::f64::consts::TAU * uniform())).collect();
    let u: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            0.8 * (2.0 * std::f64::consts::PI * 0.1 * t).sin()
                + lines.iter().map(|(f, p)| 0.12 * (2.0 * std::f64::consts::PI * f * t + p).sin()).sum::<f64>()
        })
        .collect();
    // the truth: x = [q0, q1, q2, w0, w1, w2], friction F_c tanh(w/1e-3) at the load
    let b = &m.line.bodies;
    let c = &m.line.couplings;
    let f = |x: &[f64; 6], torque: f64| -> [f64; 6] {
        let t1 = c[0].stiffness * (x[0] - x[1]) + c[0].damping * (x[3] - x[4]);
        let r = c[1].ratio;
        let t2 = c[1].stiffness * (x[1] / r - x[2]) + c[1].damping * (x[4] / r - x[5]);
        let fr = friction_nm * (x[5] / 1e-3).tanh();
        [
            x[3],
            x[4],
            x[5],
            (torque - t1 - b[0].drag * x[3]) / b[0].inertia,
            (t1 - t2 / r - b[1].drag * x[4]) / b[1].inertia,
            (t2 - fr - b[2].drag * x[5]) / b[2].inertia,
        ]
    };
    let mut x = [0.0; 6];
    let h = dt / sub as f64;
    let mut y: Vec<Vec<f64>> = (0..3).map(|_| Vec::with_capacity(n)).collect();
    for &uk in &u {
        let t1 = c[0].stiffness * (x[0] - x[1]) + c[0].damping * (x[3] - x[4]);
        for (o, v) in y.iter_mut().zip([x[3], x[5], t1]) {
            o.push(v);
        }
        for _ in 0..sub {
            let add = |a: &[f64; 6], k: &[f64; 6], s: f64| std::array::from_fn(|i| a[i] + s * k[i]);
            let k1 = f(&x, uk);
            let k2 = f(&add(&x, &k1, 0.5 * h), uk);
            let k3 = f(&add(&x, &k2, 0.5 * h), uk);
            let k4 = f(&add(&x, &k3, h), uk);
            x = std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        }
    }
    // 0.5 % of each output's RMS as uniform noise of the same RMS
    for o in &mut y {
        let rms = (o.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        for v in o.iter_mut() {
            *v += 0.005 * rms * 3f64.sqrt() * (2.0 * uniform() - 1.0);
        }
    }
    (u, y)
}
