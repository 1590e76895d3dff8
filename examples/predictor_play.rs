//! The error of rigtwin's own model with a play of each size in one coupling of a `drive_test`
//! bundle's declared line, simulated over the whole record and as the one-step-ahead predictor
//! (`plant::predictor`; docs/validation.md, step 14), each output high-passed and weighted as
//! `rigtwin diagnose` does:
//!
//! `cargo run --release --example predictor_play -- BUNDLE COUPLING PLAY_RAD INPUT_SD DISTURBANCE_SD`
//!
//! COUPLING is 1-based, PLAY_RAD the play the factors 0, 0.5, 0.8, 1, 1.25 and 2 scale, INPUT_SD
//! the inputs' noise (N·m), DISTURBANCE_SD that of a torque on every body the model lacks (the
//! predictor's process noise beside the inputs'); the outputs' noise is the survey's
//! (`scripts/survey_lines.py`): an encoder's 2.9 mrad/s, a torque sensor's INPUT_SD.

use plant::predictor::Predictor;
use plant::{Backlash, Dynamics, Effect, Quantity};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, bundle, coupling, play, input_sd, disturbance] = &args[..] else {
        eprintln!("usage: predictor_play BUNDLE COUPLING PLAY_RAD INPUT_SD DISTURBANCE_SD");
        std::process::exit(2);
    };
    let parse = |s: &str| s.parse::<f64>().unwrap_or_else(|_| panic!("not a number: {s}"));
    let (coupling, play, input_sd, disturbance) =
        (parse(coupling) as usize - 1, parse(play), parse(input_sd), parse(disturbance));
    let b = rigtwin::bundle::load_drive_test(std::path::Path::new(bundle)).expect("a drive_test bundle");
    let outputs: Vec<(Quantity, usize)> =
        b.outputs.iter().map(|o| (o.quantity.expect("an output's quantity"), o.at)).collect();
    let len = b.input_data[0].len();
    let dt = b.dt_s;
    let corner = ident::diagnose::high_pass_corner_hz(len, dt, ident::diagnose::drive::HIGH_PASS_MIN_HZ);
    let high_passed = |mut v: Vec<f64>| {
        ident::signal::filtfilt_high_pass_in_place(&mut v, dt, corner);
        v
    };
    let measured: Vec<Vec<f64>> = b.output_data.iter().map(|y| high_passed(y.clone())).collect();
    let norms: Vec<f64> = measured.iter().map(|m| m.iter().map(|v| v * v).sum::<f64>().sqrt()).collect();
    let error = |flat: &[f64]| -> f64 {
        let mut sum = 0.0;
        for (o, m) in measured.iter().enumerate() {
            let p = high_passed(flat[o * len..(o + 1) * len].to_vec());
            let w = 1.0 / (norms[o] * (measured.len() as f64).sqrt());
            sum += p.iter().zip(m).map(|(p, m)| ((p - m) * w).powi(2)).sum::<f64>();
        }
        sum.sqrt()
    };
    let output_sd: Vec<f64> =
        outputs
            .iter()
            .map(|o| {
                if o.0 == Quantity::Speed {
                    (2.0 * 0.002f64.powi(2) + 0.001f64.powi(2) / 12.0).sqrt()
                } else {
                    input_sd
                }
            })
            .collect();
    // the first body's mean speed over the quiet start (the survey's first output)
    let speed0 = b.output_data[0][..100.min(len)].iter().sum::<f64>() / 100.min(len) as f64;
    let inputs: Vec<&[f64]> = b.input_data.iter().map(Vec::as_slice).collect();
    let raw: Vec<&[f64]> = b.output_data.iter().map(Vec::as_slice).collect();
    println!("| play × | simulation | predictor |");
    println!("| --- | --- | --- |");
    for factor in [0.0, 0.5, 0.8, 1.0, 1.25, 2.0] {
        let mut m = b.model.clone();
        if factor > 0.0 {
            m.effects.push(Effect::Backlash(Backlash { coupling, backlash: factor * play }));
        }
        let d = Dynamics::new(&m).expect("the model");
        let first: Vec<f64> = inputs.iter().map(|u| u[0]).collect();
        let x0 = d.initial_state(speed0, &first);
        let simulated = d.simulate_flat_from(x0.clone(), &inputs, dt, &outputs).map(|y| error(&y));
        let predictor =
            Predictor::new(&m, dt, &outputs, &vec![input_sd; inputs.len()], disturbance, &output_sd).expect("a gain");
        let predicted = d.predict_flat_from(x0, &inputs, dt, &outputs, &raw, &predictor.gain).map(|y| error(&y));
        let show = |r: plant::error::Result<f64>| r.map_or_else(|e| format!("({e})"), |v| format!("{v:.4}"));
        println!("| {factor} | {} | {} |", show(simulated), show(predicted));
    }
}
