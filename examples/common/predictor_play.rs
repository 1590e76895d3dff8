//! The error of a `drive_test` bundle's declared line with a play of each size in one coupling,
//! simulated over the whole record and as the one-step-ahead predictor (`plant::predictor`),
//! each output high-passed and weighted as `rigtwin diagnose` does (docs/validation.md, step 14).
//! Shared by `examples/predictor_play.rs` and `tests/predictor.rs`.

use plant::predictor::Noise;
use plant::{Backlash, Effect, Quantity};

/// An encoder's speed noise in the survey (`scripts/survey.py`'s `measured`): white and
/// coloured 2 mrad/s each, 1 mrad/s quantisation, rad/s.
pub const ENCODER_SD: f64 = 0.002_843;

/// Per play (`factor` × `play` in `coupling`, 0-based): (factor, simulation's error,
/// predictor's error). The predictor's process noise is `input_sd` on each input and
/// `disturbance_sd` on every body; its measurement noise [`ENCODER_SD`] for a speed, `input_sd`
/// for a torque (the survey's).
pub fn play_errors(
    bundle: &std::path::Path,
    coupling: usize,
    play: f64,
    input_sd: f64,
    disturbance_sd: f64,
    factors: &[f64],
) -> Result<Vec<(f64, f64, f64)>, String> {
    let b = rigtwin::bundle::load_drive_test(bundle).map_err(|e| e.to_string())?;
    let outputs: Vec<(Quantity, usize)> =
        b.outputs.iter().map(|o| (o.quantity.unwrap_or(Quantity::Speed), o.at)).collect();
    let (len, dt) = (b.input_data[0].len(), b.dt_s);
    let corner = ident::diagnose::high_pass_corner_hz(len, dt, ident::diagnose::drive::HIGH_PASS_MIN_HZ);
    let high_passed = |mut v: Vec<f64>| {
        ident::signal::filtfilt_high_pass_in_place(&mut v, dt, corner);
        v
    };
    let measured: Vec<Vec<f64>> = b.output_data.iter().map(|y| high_passed(y.clone())).collect();
    let weights: Vec<f64> = measured
        .iter()
        .map(|m| 1.0 / (m.iter().map(|v| v * v).sum::<f64>().sqrt() * (measured.len() as f64).sqrt()))
        .collect();
    let error = |flat: &[f64]| -> f64 {
        let mut sum = 0.0;
        for (o, (m, w)) in measured.iter().zip(&weights).enumerate() {
            let p = high_passed(flat[o * len..(o + 1) * len].to_vec());
            sum += p.iter().zip(m).map(|(p, m)| ((p - m) * w).powi(2)).sum::<f64>();
        }
        sum.sqrt()
    };
    let noise = Noise {
        inputs_sd: vec![input_sd; b.input_data.len()],
        disturbance_sd,
        outputs_sd: outputs.iter().map(|o| if o.0 == Quantity::Speed { ENCODER_SD } else { input_sd }).collect(),
    };
    // the first body's mean speed over the quiet start (the survey's first output)
    let quiet = 100.min(len);
    let speed0 = b.output_data[0][..quiet].iter().sum::<f64>() / quiet as f64;
    let mut rows = Vec::new();
    for &factor in factors {
        let mut m = b.model.clone();
        if factor > 0.0 {
            m.effects.push(Effect::Backlash(Backlash { coupling, backlash: factor * play }));
        }
        let simulated = m.simulate_flat(&b.input_data, dt, speed0, &outputs).map_err(|e| e.to_string())?;
        let predicted =
            m.predict_flat(&b.input_data, dt, speed0, &outputs, &b.output_data, &noise).map_err(|e| e.to_string())?;
        rows.push((factor, error(&simulated), error(&predicted)));
    }
    Ok(rows)
}
