//! The re-fit of the declared model reaches the least-squares minimum of its own cost (issue 32,
//! item 6): `scripts/refit_check.py` simulates the declared paper rig on its own (the open
//! differential's four states stepped exactly with scipy's matrix exponential, rigtwin's
//! high-pass written again), checks that its cost of the declared model is rigtwin's
//! `error_before`², and minimises the same cost with scipy's `least_squares` over the same two
//! parameters. Two survey records with play (seeds 17 and 31: the declared model's valley is long
//! and curved there; seed 31's re-fit stopped at twice the minimum before the damping of the
//! fits could grow without limit).

mod common;

/// Each row of a re-fit check (`script` on `seeds`) at scipy's minimum: the same cost of the
/// declared model here and in rigtwin — both step the same linear model exactly and filter
/// alike, so they differ by rounding only (1e-4: the matrix exponentials' and, for a line, the
/// pseudo-inverse's own) — and rigtwin's re-fit within 1 % of the minimum scipy reaches (the
/// issue's criterion).
fn refitted_to_the_minimum(script: &str, seeds: &str, records: usize) {
    let v = common::survey_script(script, seeds, "--json");
    let rows = v.as_array().unwrap();
    assert_eq!(rows.len(), records, "one row per record: {v}");
    for r in rows {
        let same = r["same_cost"].as_f64().unwrap();
        assert!((same - 1.0).abs() < 1e-4, "seed {}: the declared model's cost here / rigtwin's = {same}", r["seed"]);
        let ratio = r["ratio"].as_f64().unwrap();
        assert!(ratio <= 1.01, "seed {}: rigtwin's re-fit costs {ratio} × scipy's minimum", r["seed"]);
    }
}

#[test]
fn the_declared_model_is_refitted_to_the_least_squares_minimum() {
    refitted_to_the_minimum("refit_check.py", "17,31", 2);
}

/// The same for a declared drive line (`scripts/refit_check_lines.py`: the line's angles and
/// speeds stepped exactly with scipy's matrix exponential, started as rigtwin starts a record,
/// every output high-passed and weighted as rigtwin's cost is; scipy's `least_squares` over the
/// logarithms of every inertia and stiffness within rigtwin's bound). Seed 21: a 4-body line
/// with two gear stages and no effect, whose re-fit moves a stiffness beyond the factor the
/// declared model is trusted to. Seed 2100: a 5-body line with a gear stage whose two stiff,
/// damped couplings in series trade against each other; with forward differences its re-fit
/// stopped at 23 times the minimum (`lm::Fit::central`). A declared model that lacks the
/// record's effect may have minima far apart (seed 2, docs/validation.md), so these guard lines
/// without one, and the cost itself.
#[test]
fn a_declared_drive_line_is_refitted_to_the_least_squares_minimum() {
    refitted_to_the_minimum("refit_check_lines.py", "21,2100", 2);
}
