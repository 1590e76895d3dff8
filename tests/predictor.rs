//! The one-step-ahead predictor (`plant::predictor`) measures a play that rattles about zero
//! torque, which the error of a simulation over the whole record does not (docs/validation.md,
//! steps 13 and 14). `scripts/survey_lines.py`'s simulator (scipy's LSODA, its own play: a dead
//! zone with contact damping; no code shared with rigtwin) writes survey record 24: 4 bodies, a
//! play of 26 mrad in the first coupling, multisine about zero torque, the measurement's noise,
//! drift and quantisation, the declared inertias and stiffnesses a few per cent off. rigtwin's
//! declared line with its own play of 0.5, 1 and 2 times the truth's at that coupling is
//! simulated and predicted (the survey's noise levels as the predictor's).

mod common;

#[path = "../examples/common/predictor_play.rs"]
mod predictor_play;

use std::process::Command;

#[test]
fn the_predictor_is_least_in_error_at_the_true_play() {
    let dir = common::scratch("predictor", "record");
    let scripts = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts");
    let code = "import sys, json\nsys.path.insert(0, sys.argv[1])\nimport survey_lines as S\n\
                t = S.truth_of(24)\nS.write_bundle(sys.argv[2], t)\n\
                p = [e for e in t['effects'] if e['effect'] == 'backlash'][0]\n\
                print(json.dumps(dict(coupling=p['coupling'], play=p['size'], input_sd=0.002 * t['amplitude'])))";
    let out = Command::new(common::python()).arg("-c").arg(code).arg(&scripts).arg(&*dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let truth: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (coupling, play, input_sd) = (
        truth["coupling"].as_u64().unwrap() as usize,
        truth["play"].as_f64().unwrap(),
        truth["input_sd"].as_f64().unwrap(),
    );
    let rows =
        predictor_play::play_errors(&dir.join("line_0024.toml"), coupling, play, input_sd, input_sd, &[0.5, 1.0, 2.0])
            .unwrap();
    let [(_, sim_half, pred_half), (_, sim_true, pred_true), (_, sim_double, pred_double)] = rows[..] else {
        panic!("three rows: {rows:?}")
    };
    eprintln!("simulation {sim_half:.4} {sim_true:.4} {sim_double:.4}; predictor {pred_half:.4} {pred_true:.4} {pred_double:.4}");
    // measured: 0.034 at the truth against 0.23 and 0.30 beside it; half of the better
    // neighbour says the minimum is the play's, not the noise's (the simulation's errors, 0.51,
    // 0.57 and 0.78, have their least at half the play)
    assert!(
        pred_true < 0.5 * pred_half.min(pred_double),
        "the predictor's error at the true play {pred_true} is not clearly least ({pred_half} at half, {pred_double} \
         at twice)"
    );
    // and it is far below the simulation's at the same play: the predictor restarts from the
    // measurement (measured 0.034 against 0.57)
    assert!(pred_true < 0.25 * sim_true, "predictor {pred_true}, simulation {sim_true}");
}
