//! The prediction model with input dead times against an independent integration: the
//! continuous plant (not its observable reduction) integrated by RK4 with 200 sub-steps per
//! sample, the delayed input looked up at each sub-step's time.

use mpc::closed_loop::rig_plant;
use mpc::model::PredictionModel;
use nalgebra::DVector;
use plant::rig::Variant;

/// Deterministic inputs in [−50, 50] Nm, one per sample and input.
fn inputs(samples: usize, m: usize) -> Vec<Vec<f64>> {
    let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
    (0..samples)
        .map(|_| {
            (0..m)
                .map(|_| {
                    s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 100.0
                })
                .collect()
        })
        .collect()
}

#[test]
fn dead_times_are_exact_for_held_inputs() {
    let plant = rig_plant(&plant::paper::damped_params(), Variant::V1).unwrap();
    let dt = 1e-3;
    let samples = 120;
    let u = inputs(samples, 3);
    // a fraction of a sample, whole samples plus a fraction, and whole samples exactly; the
    // fractions are multiples of the reference integrator's sub-step (5 µs)
    for delays in [[0.0, 0.6e-3, 0.0], [0.0, 2.4e-3, 1.1e-3], [3e-3, 0.0, 0.0]] {
        let model = PredictionModel::with_input_delays(&plant, dt, &delays).unwrap();
        let mut z = DVector::zeros(model.nstates());
        let mut predicted = Vec::new();
        for uk in &u {
            predicted.push(&model.c * &z);
            z = &model.a * &z + &model.b * DVector::from_column_slice(uk);
        }
        // reference: RK4 on ẋ = A x + B u(t − τ) with 200 sub-steps per sample
        let sub = 200;
        let h = dt / sub as f64;
        let n = plant.nstates();
        let mut x = DVector::zeros(n);
        let delayed = |t: f64| -> DVector<f64> {
            DVector::from_fn(3, |j, _| {
                let s = t - delays[j];
                // the value held over the sample containing s (0 before the record)
                if s < -1e-12 {
                    0.0
                } else {
                    u[((s + 1e-12) / dt).floor() as usize][j]
                }
            })
        };
        let f = |x: &DVector<f64>, uu: &DVector<f64>| &plant.a * x + &plant.b * uu;
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for (k, pk) in predicted.iter().enumerate() {
            let y = &plant.c * &x;
            scale = scale.max(y.amax());
            worst = worst.max((&y - pk).amax());
            for i in 0..sub {
                // the input is constant over each sub-step (its breakpoints lie on the grid)
                let uu = delayed(k as f64 * dt + (i as f64 + 0.5) * h);
                let k1 = f(&x, &uu);
                let k2 = f(&(&x + &k1 * (0.5 * h)), &uu);
                let k3 = f(&(&x + &k2 * (0.5 * h)), &uu);
                let k4 = f(&(&x + &k3 * h), &uu);
                x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
            }
        }
        // RK4 at h·ω ≈ 4e-4 for the fastest mode: its error is ~1e-14 per step, far below 1e-9
        assert!(scale > 1.0, "the test signal must move the outputs");
        assert!(worst < 1e-9 * scale, "delays {delays:?}: prediction off by {worst:e} (scale {scale:e})");
        // whole samples and fractions: buffer lengths ⌈τ/dt⌉
        let expected: usize = delays.iter().map(|d| (d / dt - 1e-9).ceil().max(0.0) as usize).sum();
        assert_eq!(model.buffer_inputs.len(), expected, "{delays:?}");
    }
}
