//! The drive-line survey's CI guard (issue 32, item 5): `scripts/survey_lines.py` writes two
//! `drive_test` records of random lines with a simulator that shares no code with rigtwin
//! (scipy's LSODA, its own Stribeck friction, dead time and lag), each holding a pair of
//! effects, and diagnoses them with this build's `rigtwin diagnose`: seed 6 (3 bodies, 0.023 N·m
//! of friction at the last body and a 3.3 ms dead time at the input, PRBS) and seed 20 (3
//! bodies and a gear stage, play at the coupling and a dead time at the second input, closed
//! loop). Both are found by the `drive_test` engine's second step of forward selection. (Seed
//! 33, the guard's second record until the effects' re-fits kept the declared mechanics within
//! their tolerance, is now answered as its lag alone: docs/validation.md, step 8.) Seeds 3 and
//! 32 were confident wrong answers before the engine scored every candidate as the re-fit of
//! everything, re-fitted the declared model from the answer (leave-out) and named a place only
//! on strong evidence: a play of 0.09 nrad at the wrong coupling (its re-fit of the inertias had
//! found what the declared model's own re-fit missed), and friction at the body next to the true
//! one. They must not be wrong again. Guards against regressions, not a measure: the survey's
//! tables are docs/validation.md.

mod common;

#[test]
fn two_pairs_of_effects_in_drive_lines_are_found() {
    let v = common::survey_script("survey_lines.py", "6,20", "--summary");
    assert_eq!(v["records"], 2, "{v}");
    assert_eq!(v["right"], 2, "a pair the second step finds today is missed: {v}");
}

#[test]
fn a_place_the_record_cannot_tell_is_no_finding() {
    let v = common::survey_script("survey_lines.py", "3,32", "--summary");
    assert_eq!(v["records"], 2, "{v}");
    assert_eq!(v["wrong"], 0, "a confident wrong answer is back: {v}");
}

/// Seeds 24 and 31: a play that rattles about zero torque (4 bodies, multisine; 5 bodies and two
/// gear stages, closed loop). Scored by their simulation over the whole record no model explains
/// them — the truth itself, simulated from the recorded input, errs 0.31 and 0.92 — and they
/// were *not explained*; scored by the one-step-ahead prediction the play is found at the right
/// coupling (docs/validation.md, steps 13–15).
#[test]
fn a_rattling_play_is_found_by_the_prediction() {
    let v = common::survey_script("survey_lines.py", "24,31", "--summary");
    assert_eq!(v["records"], 2, "{v}");
    assert_eq!(v["right"], 2, "a rattling play is missed again: {v}");
}

/// Seed 2909 (7 bodies, PRBS; 0.024 N·m of friction at b2, which is not measured, joined to the
/// measured b3 by the line's stiffest coupling). The declared model's free re-fit is
/// implausible, so the first step screens every place beside the declared mechanics, where b3
/// ranked first; its re-fit (error 0.0045) was the answer, a friction at the wrong body. The
/// swap step screens the places again beside the answer's re-fitted mechanics, where b2 leads
/// and its re-fit reaches error 0.0018 with the friction within 1 % (docs/validation.md,
/// step 18; the record was held out until this step examined it).
#[test]
fn a_friction_is_placed_beside_the_answers_mechanics() {
    let v = common::survey_script("survey_lines.py", "2909", "--summary");
    assert_eq!(v["records"], 1, "{v}");
    assert_eq!(v["right"], 1, "the friction is at the wrong body again: {v}");
}

/// Seed 2937 (2 bodies and a gear stage, a sweep about 0.14 N·m; 0.257 N·m of friction at b1,
/// which holds b1's measured speed about zero, reversing). The declared model, without the
/// friction, spins b1 up and never near zero, so where a friction can act was judged nowhere at
/// b1, and damping stood in for it (error 0.18, a structured residual, *explained*). The
/// measured speed now shows it too (docs/validation.md, step 19; the record was held out until
/// this step examined it).
#[test]
fn a_friction_is_tried_where_the_measured_speed_reverses() {
    let v = common::survey_script("survey_lines.py", "2937", "--summary");
    assert_eq!(v["records"], 1, "{v}");
    assert_eq!(v["right"], 1, "damping stands in for the friction again: {v}");
}

/// Seed 3027 (4 bodies, closed loop; a 2.1 rad play at coupling 1, which the motor's swings of
/// about a radian never close). Any wider play fits the record alike, and the play was reported
/// as found at 44.6 rad, 20 times the truth. The record shows only that the play is wider than
/// the twists it meets: the answer with the play at the largest size the effect allows errs as
/// the fit does, so the size is no finding and the verdict *not explained* (docs/validation.md,
/// step 22; the record was held out until then).
#[test]
fn a_play_the_record_bounds_only_from_below_is_no_finding() {
    let v = common::survey_script("survey_lines.py", "3027", "--summary");
    assert_eq!(v["records"], 1, "{v}");
    assert_eq!(v["not_explained"], 1, "a play's size the record does not bound is printed as a finding again: {v}");
}

/// Seed 3128 (3 bodies and two gear stages, closed loop; a dead time of 1.9 ms at the input and
/// 0.015 N·m of friction at b1, the body the input drives, which turns at 0.44–5.4 rad/s
/// throughout). There the friction is a constant torque, which the record cannot tell from an
/// offset of the input's torque; it was reported as found beside the dead time. It is no
/// finding now, and the verdict *not explained* (docs/validation.md, step 23; the record was
/// held out until then).
#[test]
fn a_friction_that_never_meets_a_reversal_at_an_input_is_no_finding() {
    let v = common::survey_script("survey_lines.py", "3128", "--summary");
    assert_eq!(v["records"], 1, "{v}");
    assert_eq!(v["wrong"], 0, "a friction the record cannot tell from an input's offset is a finding again: {v}");
}

/// Seed 3322 (4 bodies, multisine; 0.011 N·m of friction at b2, which no input drives and which
/// turns at 0.37–13 rad/s throughout). A friction of a body that turns one way is a constant
/// force: the record shows it only as offsets, which the high-pass removes, and through the state
/// the simulation is assumed to start in. It was reported as found; it is no finding now, as at a
/// body an input drives (docs/validation.md, step 34; the record was held out until then).
#[test]
fn a_friction_that_never_meets_a_reversal_is_no_finding() {
    let v = common::survey_script("survey_lines.py", "3322", "--summary");
    assert_eq!(v["records"], 1, "{v}");
    assert_eq!(v["wrong"], 0, "a constant friction force is a finding again: {v}");
}

/// Seed 3333 (4 bodies and a gear stage, multisine; a dead time of 2.94 ms at input 2). Every
/// effect's re-fit started beside the declared model's re-fit, which the missing dead time had
/// bent along the ridge of b2's inertia and coupling 2's stiffness to the tolerance's edge, and
/// stayed there: a lag beat the dead time, and a dead time with a lag was the answer. A re-fit
/// that ends on the edge is now also fitted from the declared mechanics: the dead time alone,
/// 0.3 % off (docs/validation.md, step 35; the record was held out until step 33).
#[test]
fn a_dead_time_is_not_split_into_a_dead_time_and_a_lag() {
    let v = common::survey_script("survey_lines.py", "3333", "--summary");
    assert_eq!(v["records"], 1, "{v}");
    assert_eq!(v["right"], 1, "a re-fit stuck at the tolerance's edge turns the dead time into a lag again: {v}");
}

/// `--only compliance --search-compliance` seed 1028 (3 bodies and a gear stage, closed loop; a
/// compliance inside b3): answered `damping` with coupling 2's damping about 10⁵ times the
/// critical damping of its own mode, a rigid link standing in for the compliance. A damping at or
/// beyond critical is no finding (docs/validation.md, step 33; the record was held out until then).
#[test]
fn a_damping_beyond_critical_is_no_finding() {
    let v = common::survey_script_with(
        "survey_lines.py",
        "1028",
        "--summary",
        &["--only", "compliance", "--search-compliance"],
    );
    assert_eq!(v["records"], 1, "{v}");
    assert_eq!(v["wrong"], 0, "a damping beyond critical is a finding again: {v}");
}

/// Seeds 3087 (8 bodies and two gear stages, steps) and 3136 (7 bodies and two gear stages,
/// steps): no effect, the declared inertias and stiffnesses a few per cent off. The declared
/// model's re-fit within its tolerance started from its free re-fit, which had moved quantities
/// the record hardly determines far off, and stopped at the tolerance's edge: *not explained*
/// ("the declared model fits only with its mechanics at the edge"). Restarted from the declared
/// values, or held there where it ends at the edge again, it fits as well as the free re-fit, and
/// the declared model fits (docs/validation.md, step 24; both records were held out until then).
#[test]
fn a_declared_quantity_the_record_does_not_determine_is_held_at_its_declared_value() {
    let v = common::survey_script("survey_lines.py", "3087,3136", "--summary");
    assert_eq!(v["records"], 2, "{v}");
    assert_eq!(v["right"], 2, "a re-fit stopped at the tolerance's edge makes the declared model distorted again: {v}");
}

/// `--only compliance --search-compliance` seeds 9 (4 bodies and two gear stages, closed loop; a compliance inside
/// b4, 0.43 of its inertia on the driven side) and 16 (5 bodies, multisine; inside b1, the body
/// the input drives, damped at 4.8 % of its own mode's critical damping): the compliance is found
/// at its body, alone. Seed 16 was answered as the compliance and a friction at b1 while the
/// compliance kept the body's stiffness-proportional damping, 0.3 % of critical there: the
/// friction stood in for the missing damping until a compliance answer's damping ratio was
/// profiled before anything is added beside it (docs/validation.md, step 32).
#[test]
fn a_compliance_inside_a_body_is_found_alone() {
    let v = common::survey_script_with(
        "survey_lines.py",
        "9,16",
        "--summary",
        &["--only", "compliance", "--search-compliance"],
    );
    assert_eq!(v["records"], 2, "{v}");
    assert_eq!(v["right"], 2, "a compliance inside a body is missed or named beside another effect: {v}");
}
