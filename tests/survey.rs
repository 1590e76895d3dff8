//! The survey's CI subset (issue 32, item 5): `scripts/survey.py` writes 30 records of the paper
//! rig with a simulator that shares no code with rigtwin (scipy's LSODA, its own play, Stribeck
//! friction, coloured noise, drift, quantisation; seeds 0-29, every effect and `none`, sweeps,
//! multisines, steps and PRBS) and diagnoses each with this build's `rigtwin diagnose`.
//!
//! What it holds is today's measured result, a guard against regressions, not the aim
//! (≥ 95 % of single effects right): on these 30 records 28 are right, one is said to be not
//! explained (seed 10, play under a multisine about zero torque) and one is wrong (seed 25, a
//! compliance reported with shaft damping beside it). The full survey's table, with its
//! held-out part and the intervals' coverage, is docs/validation.md.

mod common;

#[test]
fn the_survey_subset_keeps_its_verdicts() {
    let v = common::survey_script("survey.py", "0-29", "--summary");
    assert_eq!(v["records"], 30);
    assert!(v["right"].as_u64().unwrap() >= 28, "{v}");
    assert!(v["wrong"].as_u64().unwrap() <= 1, "a confident wrong answer more than today: {v}");
    // the 95 % intervals over the held-out folds (issue 32, item 3): of the 20 right answers
    // that give an interval of their scored parameter, 19 hold the truth today (the miss: seed 4,
    // a compliance 0.6 % off with an interval of ±0.1 %); the plays of seeds 3, 17 and 24 give
    // none, since some of their folds' fits could not move (seed 17's had missed: ±0.03 % about
    // a play 0.3 % off)
    assert!(v["intervals_covering"].as_u64().unwrap() >= 19, "fewer intervals hold the truth than today: {v}");
    // no answer gives an interval where a fold's fit could not move (a rattling play's): those
    // folds add no spread (docs/validation.md, step 29)
    assert_eq!(v["intervals_beside_unmoved_folds"], 0, "an interval the folds did not measure: {v}");
}

/// Seeds 1978 and 2034: a compliance inside the drive under steps (5 and 40 N·m). Its fit was
/// by far the best (error 0.048 → 0.0048 on 1978), but was rejected because its mode (29.9 and
/// 23.4 Hz) lay above the frequency under which 99 % of the drive torque's power lies — a step's
/// power lies at low frequencies, yet it rings the mode — and play and shaft damping were the
/// answers. Whether the record shows the mode is now asked of the record: the fit with the mode
/// moved to the highest the engine simulates errs clearly worse (docs/validation.md, step 25;
/// both records were held out until then).
#[test]
fn a_compliance_rung_by_steps_is_found() {
    let v = common::survey_script("survey.py", "1978,2034", "--summary");
    assert_eq!(v["records"], 2, "{v}");
    assert_eq!(v["right"], 2, "a compliance whose mode steps ring is rejected again: {v}");
}
