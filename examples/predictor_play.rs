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
//! (`scripts/survey_lines.py`): an encoder's 2.8 mrad/s, a torque sensor's INPUT_SD.

#[path = "common/predictor_play.rs"]
mod common;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, bundle, coupling, play, input_sd, disturbance] = &args[..] else {
        eprintln!("usage: predictor_play BUNDLE COUPLING PLAY_RAD INPUT_SD DISTURBANCE_SD");
        std::process::exit(2);
    };
    let numbers: Result<Vec<f64>, _> =
        [coupling, play, input_sd, disturbance].iter().map(|s| s.parse::<f64>()).collect();
    let Ok(&[coupling, play, input_sd, disturbance]) = numbers.as_deref() else {
        eprintln!("COUPLING, PLAY_RAD, INPUT_SD and DISTURBANCE_SD are numbers");
        std::process::exit(2);
    };
    if coupling < 1.0 {
        eprintln!("COUPLING counts from 1");
        std::process::exit(2);
    }
    let factors = [0.0, 0.5, 0.8, 1.0, 1.25, 2.0];
    match common::play_errors(
        std::path::Path::new(bundle),
        coupling as usize - 1,
        play,
        input_sd,
        disturbance,
        &factors,
    ) {
        Ok(rows) => {
            println!("| play × | simulation | predictor |");
            println!("| --- | --- | --- |");
            for (factor, simulated, predicted) in rows {
                println!("| {factor} | {simulated:.4} | {predicted:.4} |");
            }
        }
        Err(e) => {
            eprintln!("{bundle}: {e}");
            std::process::exit(1);
        }
    }
}
