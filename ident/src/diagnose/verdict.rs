//! The diagnosis's answer in one word, and the physical bounds a found effect's parameters must
//! keep to be a finding: what the record can show, not what a fit can reach.
//!
//! - *explained*: effects were found, each parameter inside its bounds;
//! - *declared model fits*: no effect improves the declared model clearly and what is left is
//!   noise (a white residual);
//! - *not explained*: a structured residual that no candidate explains with physical
//!   parameters — no effect found, or the best one's parameters at or beyond a bound — or that
//!   several explain alike (the record does not tell what or where: [`undetermined`]).

use std::collections::BTreeMap;

use serde::Serialize;

use super::CandidateScore;

/// The diagnosis's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The effects found explain the record.
    Explained,
    /// The declared model fits: nothing is missing that the record shows.
    DeclaredModelFits,
    /// The record shows something that no candidate explains with physical parameters, or that
    /// several explain alike.
    NotExplained,
}

/// What the record can show, for the parameter bounds (SI: N·m or N, rad/s or m/s, s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordScales {
    /// Largest |input| the record applies (a torque or force), after the gear stages it drives
    /// through at most (the largest product of ratios along the line).
    pub max_force: f64,
    /// Largest RMS of a measured speed.
    pub rms_speed: f64,
    /// Length of the record, s.
    pub duration_s: f64,
    /// Sample time, s (0: not judged).
    pub sample_time_s: f64,
}

/// Settings of the bounds, with their defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundSettings {
    /// A Coulomb friction is at most this multiple of the largest force the record applies
    /// (default 1: a friction the drive could never overcome stops the line, and a record in
    /// which everything moves shows no such friction).
    pub friction_per_force: f64,
    /// A friction's smoothing speed is at most this fraction of the record's RMS speed (default
    /// 0.25: beyond it the "friction" is a viscous drag in disguise).
    pub smoothing_per_speed: f64,
    /// A dead time or time constant is at most this fraction of the record (default 0.1: a
    /// longer one leaves too little of the record to show it).
    pub time_per_record: f64,
    /// A re-fitted damping is at most this fraction of critical damping: a coupling's of its own
    /// mode (its stiffness on the inertia its twist sees), the rig's shaft damping as the ratio
    /// of its shuffle mode (default 1: shafts, gear meshes and elastic couplings are damped at a
    /// few per cent of critical, rubber elements at up to a few tenths; a "damping" beyond
    /// critical makes the coupling a rigid link that stands in for a missing effect). A body's
    /// drag is bounded as a friction is: its force at the record's RMS speed is at most
    /// `friction_per_force` times the record's largest force.
    pub damping_ratio_max: f64,
}

impl Default for BoundSettings {
    fn default() -> Self {
        BoundSettings {
            friction_per_force: 1.0,
            smoothing_per_speed: 0.25,
            time_per_record: 0.1,
            damping_ratio_max: 1.0,
        }
    }
}

/// A re-fitted damping `d` of report key `key` at or beyond `s.damping_ratio_max` of
/// `critical`, the critical damping of its own mode, as a sentence (`None`: within it).
pub fn damping_beyond_critical(key: &str, d: f64, critical: f64, s: &BoundSettings) -> Option<String> {
    let bound = s.damping_ratio_max * critical;
    (!d.is_finite() || d >= bound).then(|| {
        format!(
            "{key} = {d:.4e} is at or beyond its bound {bound:.4e} ({} × the critical damping of its own mode: a rigid link in disguise)",
            s.damping_ratio_max
        )
    })
}

/// Which of `parameters` (report keys with units) lie at or beyond their physical bounds, each
/// as a sentence for the report; a dead time or time constant also at or below (within 1 %) the
/// floor of its search ([`plant::drive::INPUT_TIME_FLOOR_SAMPLES`] of a sample). Keys without a
/// bound here (re-fitted inertias, stiffnesses, plays; a coupling's damping, whose bound needs its
/// model: [`damping_beyond_critical`]) are not judged.
pub fn out_of_bounds(parameters: &BTreeMap<String, f64>, scales: &RecordScales, s: &BoundSettings) -> Vec<String> {
    let mut out = Vec::new();
    for (key, &v) in parameters {
        let time = key == "delay_s" || key == "time_constant_s";
        let (bound, what) = if key.starts_with("friction") {
            (s.friction_per_force * scales.max_force, "the largest force (torque) the record applies")
        } else if key.starts_with("smoothing_speed") {
            (s.smoothing_per_speed * scales.rms_speed, "a quarter of the record's RMS speed")
        } else if time {
            (s.time_per_record * scales.duration_s, "a tenth of the record")
        } else if key == "damping_ratio" {
            (s.damping_ratio_max, "critical damping")
        } else if key.starts_with("drag_") {
            // no speed measured (an infinite RMS speed): not judged
            let per_speed = if scales.rms_speed.is_finite() { scales.rms_speed } else { 0.0 };
            (
                s.friction_per_force * scales.max_force / per_speed,
                "the drag whose force at the record's RMS speed is the largest force (torque) the record applies",
            )
        } else {
            continue;
        };
        if !v.is_finite() || v >= bound {
            out.push(format!("{key} = {v:.4e} is at or beyond its bound {bound:.4e} ({what})"));
        }
        let floor = plant::drive::INPUT_TIME_FLOOR_SAMPLES * scales.sample_time_s;
        if time && v.is_finite() && v <= 1.01 * floor {
            out.push(format!(
                "{key} = {v:.4e} is at or below the shortest the record can show, {floor:.4e} ({} of a sample)",
                plant::drive::INPUT_TIME_FLOOR_SAMPLES
            ));
        }
    }
    out
}

/// How far the declared mechanics may move in a re-fit, with its default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeclaredSettings {
    /// A declared inertia or stiffness is trusted to within this factor (default 1.3: the
    /// spread of inertias from drawings and stiffnesses from shaft geometry against a rig's
    /// measured modes; beyond it a re-fit imitates a missing effect). Applied to what each
    /// effect leaves unchanged ([`Moves`]), not to every raw parameter.
    pub tolerance_factor: f64,
    /// How strongly the record must prefer the declared model's free re-fit over its re-fit
    /// within the tolerance factor for the declared mechanics to be judged distorted: a
    /// difference of information criterion ([`moved_by_the_record`]; default 6, the "strong"
    /// evidence that names a finding, [`PlaceSettings::min_evidence`]). Below it the record does
    /// not determine the quantities the free re-fit moved (a stiff coupling whose mode lies
    /// above the excitation, an inertia no output sees), and the declared model within its
    /// tolerance is the answer.
    pub min_evidence: f64,
}

impl Default for DeclaredSettings {
    fn default() -> Self {
        DeclaredSettings { tolerance_factor: 1.3, min_evidence: 6.0 }
    }
}

/// Whether the record demands the declared mechanics beyond their tolerance: the free re-fit of
/// the declared model (`free_score`, information criterion) beats its re-fit kept within the
/// tolerance factor (`boxed_score`, the same parameters) by at least
/// [`DeclaredSettings::min_evidence`].
pub fn moved_by_the_record(free_score: f64, boxed_score: f64, s: &DeclaredSettings) -> bool {
    let gap = boxed_score - free_score;
    gap.is_nan() || gap >= s.min_evidence
}

pub use plant::drive::Moves;

/// A declared quantity as a fit left it, relative to its declared value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Refitted<'a> {
    /// An inertia (one that an effect split in two: their total).
    Inertia {
        /// Its name in the report.
        name: &'a str,
        /// Re-fitted over declared value.
        ratio: f64,
    },
    /// A stiffness.
    Stiffness {
        /// Its name in the report.
        name: &'a str,
        /// Re-fitted over declared value.
        ratio: f64,
        /// Where an effect put a spring in series with it ([`Moves::SeriesSpring`]): the pair's
        /// stiffness over the declared one.
        series_ratio: Option<f64>,
    },
}

/// How `refitted` moved the declared mechanics beyond what the effects beside it explain, each
/// as a sentence for the report (empty: plausible). The one rule for every model: an inertia's
/// total and a stiffness no effect put a spring in series with stay within the tolerance factor
/// either way; a stiffness with a spring in series may be stiffer (the series pair is what was
/// measured) but not softer than declared within it, and the pair no stiffer.
pub fn declared_moved(refitted: &[Refitted], s: &DeclaredSettings) -> Vec<String> {
    let f = s.tolerance_factor;
    let within = |r: f64| log_factor(r).is_some_and(|l| l <= f.ln());
    let mut out = Vec::new();
    for q in refitted {
        match *q {
            Refitted::Inertia { name, ratio } | Refitted::Stiffness { name, ratio, series_ratio: None } => {
                if !within(ratio) {
                    out.push(format!(
                        "{name} ×{ratio:.3} of its declared value, beyond the factor {f} it is trusted to"
                    ));
                }
            }
            Refitted::Stiffness { name, ratio, series_ratio: Some(series) } => {
                if !(ratio.is_finite() && ratio >= 1.0 / f) {
                    out.push(format!(
                        "{name} ×{ratio:.3} of its declared value: a spring in series cannot make it softer than measured (factor {f})"
                    ));
                }
                if !(series.is_finite() && series <= f) {
                    out.push(format!(
                        "{name} in series with the compliance ×{series:.3} of the declared value: stiffer than measured (factor {f})"
                    ));
                }
            }
        }
    }
    out
}

/// How near the edge of its box a re-fitted quantity counts as at it: within this share of the
/// edge, in the logarithm of its ratio to the declared value (a millionth: a fit that stopped
/// there was stopped by the box, far closer than the record determines any quantity).
pub const AT_EDGE_LN_SHARE: f64 = 1e-6;

/// Whether a quantity `l` = |ln ratio| off its declared value lies at (or beyond) the edge
/// `edge_ln` of its box: within [`AT_EDGE_LN_SHARE`] of it. The one rule for the report
/// ([`declared_at_tolerance`]) and for the `drive_test` engine's restart from the declared
/// values.
pub fn at_edge(l: f64, edge_ln: f64) -> bool {
    l >= edge_ln * (1.0 - AT_EDGE_LN_SHARE)
}

/// Which of `refitted` a re-fit kept within the tolerance factor ended at its edge
/// ([`at_edge`]), each as a sentence for the report: the effect explains the record only with
/// those declared quantities as far off as they are trusted to be, and the fit would have moved
/// them further.
pub fn declared_at_tolerance(refitted: &[Refitted], s: &DeclaredSettings) -> Vec<String> {
    let f = s.tolerance_factor;
    // beyond the factor is [`declared_moved`]'s to report
    let at_edge = |r: f64| log_factor(r).is_some_and(|l| l <= f.ln() && at_edge(l, f.ln()));
    refitted
        .iter()
        .filter_map(|q| match *q {
            Refitted::Inertia { name, ratio } | Refitted::Stiffness { name, ratio, series_ratio: None } => {
                at_edge(ratio)
                    .then(|| format!("{name} ×{ratio:.3} of its declared value, at the factor {f} it is trusted to"))
            }
            Refitted::Stiffness { .. } => None,
        })
        .collect()
}

/// How far a re-fitted quantity is off its declared value: |ln ratio|, `None` where the ratio
/// is no positive finite number (never plausible).
fn log_factor(ratio: f64) -> Option<f64> {
    (ratio.is_finite() && ratio > 0.0).then(|| ratio.ln().abs())
}

/// How strongly the record must prefer the answer over every other explanation (the same
/// effects at other places, other effects), with its default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaceSettings {
    /// Least difference of information criterion (≈ 2 ln of the Bayes factor, Kass & Raftery
    /// 1995) between the answer and the best rival explanation ([`undetermined`]; default 6:
    /// "strong" evidence, posterior odds of 20 to 1 — the effect and its place are named with
    /// the 95 % confidence the intervals have). Below it the record shows that something is
    /// missing, but not what or where.
    pub min_evidence: f64,
}

impl Default for PlaceSettings {
    fn default() -> Self {
        PlaceSettings { min_evidence: 6.0 }
    }
}

/// Why `answer` is no finding because the record does not tell it from another explanation: a
/// candidate among `rivals` that is neither a part of the answer nor contains it — the same
/// effects at other places, or other effects — scores within [`PlaceSettings::min_evidence`]
/// of it (the closest named, as a sentence for the report; `None`: the record tells what and
/// where). The declared model (`none`) is no finding to tell from others: an answer `none` has
/// no rivals, and no answer has `none` as one (it beat `none` clearly to be chosen); nor are
/// implausible candidates (which distort the mechanics) rivals.
pub fn undetermined(answer: &CandidateScore, rivals: &[CandidateScore], s: &PlaceSettings) -> Option<String> {
    if answer.effect == "none" {
        return None;
    }
    let mine = &answer.parts;
    let closest = rivals
        .iter()
        .filter(|r| r.effect != "none" && !r.implausible)
        .filter(|r| {
            let theirs = &r.parts;
            !theirs.iter().all(|p| mine.contains(p)) && !mine.iter().all(|p| theirs.contains(p))
        })
        .min_by(|a, b| a.score.total_cmp(&b.score))?;
    let evidence = closest.score - answer.score;
    let named = |c: &CandidateScore| match &c.at {
        Some(at) => format!("{} at {at}", c.effect),
        None => c.effect.clone(),
    };
    let what = if closest.effect == answer.effect { "where" } else { "what" };
    (evidence < s.min_evidence).then(|| {
        format!(
            "the record does not tell {what}: {} (error {:.4}) and {} (error {:.4}) explain it alike \
             (information criterion {evidence:.1} apart, less than the {} that names a finding)",
            named(answer),
            answer.error_after,
            named(closest),
            closest.error_after,
            s.min_evidence
        )
    })
}

/// When the residual the best model leaves is structured — something the model does not
/// describe remains — with its defaults: the rule of both time-domain engines' verdicts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidualSettings {
    /// A residual whose lag-1 autocorrelation exceeds this in magnitude is structured (default
    /// 0.5: white measurement noise gives about 0, and a residual sampled finer than what it
    /// misses is close to 1).
    pub structured_lag1: f64,
    /// A residual whose normalised error is at most this is not judged (default 0.02: the model
    /// then describes all but 2 % of the measured signals, and what is left holds the
    /// measurement's own coloured noise and drift).
    pub negligible_error: f64,
}

impl Default for ResidualSettings {
    fn default() -> Self {
        ResidualSettings { structured_lag1: 0.5, negligible_error: 0.02 }
    }
}

impl ResidualSettings {
    /// Whether a residual of lag-1 autocorrelation `rho` and normalised error `error` is
    /// structured.
    pub fn structured(&self, rho: f64, error: f64) -> bool {
        rho.abs() > self.structured_lag1 && error > self.negligible_error
    }
}

/// The notes of a time-domain diagnosis that chose `effect`: `none` chosen (nothing beats
/// re-fitting `refitted`), a residual still far from white.
pub fn fit_notes(effect: &str, refitted: &str, structured_residual: bool, error_after: f64) -> Vec<String> {
    let mut notes = Vec::new();
    if effect == "none" {
        notes.push(format!("no candidate beats re-fitting {refitted}"));
    }
    if structured_residual {
        notes.push(format!(
            "the best model still leaves a structured residual (lag-1 autocorrelation above {}, error {error_after:.3})",
            ResidualSettings::default().structured_lag1
        ));
    }
    notes
}

/// Why each implausible candidate was not chosen (how its re-fit moved the declared mechanics).
pub fn implausible_notes(candidates: &[CandidateScore]) -> Vec<String> {
    candidates
        .iter()
        .filter(|c| c.implausible)
        .map(|c| {
            let at = c.at.as_ref().map(|a| format!(" at {a}")).unwrap_or_default();
            format!("{}{at} not chosen (error {:.4}): {}", c.effect, c.error_after, c.implausible_because.join("; "))
        })
        .collect()
}

/// The verdict of a diagnosis that chose `effect` ("none" for the declared model), left a
/// structured residual or not, with `violations` from [`out_of_bounds`].
pub fn verdict(effect: &str, structured_residual: bool, violations: &[String]) -> Verdict {
    match (effect, structured_residual) {
        _ if !violations.is_empty() => Verdict::NotExplained,
        ("none", true) => Verdict::NotExplained,
        ("none", false) => Verdict::DeclaredModelFits,
        _ => Verdict::Explained,
    }
}

/// The verdict of a diagnosis that chose `effect` with a structured residual or not: the
/// parameters of everything it found judged against the record's bounds ([`out_of_bounds`],
/// `settings`; the declared model's `none` has no effect parameters to judge), beside the reason
/// the diagnosis itself gave why its answer is no finding (`no_finding`: none, one or several).
/// Returns the verdict and its reasons (a *not explained* always has one).
pub fn judge<'a>(
    effect: &str,
    structured_residual: bool,
    parameters: impl Iterator<Item = &'a BTreeMap<String, f64>>,
    scales: &RecordScales,
    no_finding: impl IntoIterator<Item = &'a String>,
    settings: &BoundSettings,
) -> (Verdict, Vec<String>) {
    let mut reasons: Vec<String> = no_finding.into_iter().cloned().collect();
    if effect != "none" {
        for p in parameters {
            for r in out_of_bounds(p, scales, settings) {
                if !reasons.contains(&r) {
                    reasons.push(r);
                }
            }
        }
    }
    let v = verdict(effect, structured_residual, &reasons);
    if v == Verdict::NotExplained && reasons.is_empty() {
        reasons.push("the residual is structured and no candidate explains it with physical parameters".into());
    }
    (v, reasons)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scales() -> RecordScales {
        RecordScales { max_force: 2.0, rms_speed: 20.0, duration_s: 10.0, sample_time_s: 1e-3 }
    }

    /// A quantity a boxed re-fit left on its box — the `drive_test` engine's box lies a
    /// billionth inside the tolerance factor in the logarithm — is at the tolerance for the
    /// report as for the restart; a ten-thousandth inside it is not, and beyond the factor is
    /// the distortion's to report, not this sentence's.
    #[test]
    fn a_quantity_on_its_box_is_at_the_tolerance() {
        let s = DeclaredSettings::default();
        let f: f64 = s.tolerance_factor;
        let at = |ratio: f64| {
            let q = [Refitted::Inertia { name: "j", ratio }];
            (declared_at_tolerance(&q, &s).len(), at_edge(ratio.ln().abs(), f.ln()))
        };
        assert_eq!(at(f.powf(1.0 - 1e-9)), (1, true));
        assert_eq!(at(f.powf(-(1.0 - 1e-9))), (1, true));
        assert_eq!(at(f.powf(1.0 - 1e-4)), (0, false));
        assert_eq!(at(f * 1.01), (0, true));
    }

    #[test]
    fn a_friction_larger_than_any_force_is_no_finding() {
        // the real shaft line's "friction" of 2.3e14 N m smoothed over 7.3e12 rad/s
        let p = BTreeMap::from([("friction_Nm".to_string(), 2.3e14), ("smoothing_speed_radps".to_string(), 7.3e12)]);
        let v = out_of_bounds(&p, &scales(), &BoundSettings::default());
        assert_eq!(v.len(), 2, "{v:?}");
        assert_eq!(verdict("coulomb_friction", false, &v), Verdict::NotExplained);
        // a friction the drive overcomes, smoothed over 1 % of the speed, is a finding
        let p = BTreeMap::from([("friction_Nm".to_string(), 0.3), ("smoothing_speed_radps".to_string(), 0.2)]);
        let v = out_of_bounds(&p, &scales(), &BoundSettings::default());
        assert!(v.is_empty(), "{v:?}");
        assert_eq!(verdict("coulomb_friction", true, &v), Verdict::Explained);
    }

    /// A held-out compliant line (survey seed 1028) was answered "damping" with a coupling's
    /// damping of 6.4e5 N·m·s/rad on 1160 N·m/rad: 10^5 times its critical damping, a rigid link
    /// standing in for the compliance, reported as a finding.
    #[test]
    fn a_damping_beyond_critical_or_a_drag_beyond_the_force_is_no_finding() {
        let s = BoundSettings::default();
        // two bodies of 0.0047 and 0.0118 kg m² on 1160 N m/rad: J = 1/(1/0.0047 + 1/0.0118),
        // critical damping 2 √(k J) = 3.95 N m s/rad
        let critical = 2.0 * (1160.0f64 / (1.0 / 0.0047 + 1.0 / 0.0118)).sqrt();
        assert!((critical - 3.949).abs() < 1e-3, "{critical}");
        assert!(damping_beyond_critical("damping_coupling2_Nms_per_rad", 6.44e5, critical, &s).is_some());
        assert!(damping_beyond_critical("d", 1.01 * critical, critical, &s).is_some());
        assert!(damping_beyond_critical("d", f64::NAN, critical, &s).is_some());
        // 5 % of critical, a shaft's, is a finding
        assert_eq!(damping_beyond_critical("d", 0.05 * critical, critical, &s), None);
        // the rig's shaft damping as a ratio, and a drag against the record's force: at 20 rad/s
        // RMS and 2 N m at most, a drag of 0.1 N m s/rad takes all of it
        let p = |k: &str, v: f64| BTreeMap::from([(k.to_string(), v)]);
        assert_eq!(out_of_bounds(&p("damping_ratio", 1.2), &scales(), &s).len(), 1);
        assert!(out_of_bounds(&p("damping_ratio", 0.05), &scales(), &s).is_empty());
        assert_eq!(out_of_bounds(&p("drag_b1_Nms_per_rad", 0.1), &scales(), &s).len(), 1);
        assert!(out_of_bounds(&p("drag_b1_Nms_per_rad", 0.01), &scales(), &s).is_empty());
        // without a measured speed a drag is not judged
        let blind = RecordScales { rms_speed: f64::INFINITY, ..scales() };
        assert!(out_of_bounds(&p("drag_b1_Nms_per_rad", 1e6), &blind, &s).is_empty());
    }

    #[test]
    fn a_compliance_may_stiffen_the_shafts_but_nothing_else_may() {
        let s = DeclaredSettings::default();
        // the record: the compliance's fit moved c_short ×1.37, which a series spring
        // explains (the pair measured ×0.9 of the declared value)
        let c = |ratio, series_ratio| Refitted::Stiffness { name: "c_short", ratio, series_ratio };
        assert!(declared_moved(&[c(1.37, Some(0.9))], &s).is_empty());
        // the same move beside a friction is a distortion
        assert_eq!(declared_moved(&[c(1.37, None)], &s).len(), 1);
        // a compliance does not make the shafts softer, nor the pair stiffer, than measured
        assert_eq!(declared_moved(&[c(0.7, Some(0.5))], &s).len(), 1);
        assert_eq!(declared_moved(&[c(2.0, Some(1.5))], &s).len(), 1);
        // inertias: within the factor either way; NaN is never plausible
        let j = |ratio| Refitted::Inertia { name: "j_drive", ratio };
        assert!(declared_moved(&[j(1.29), j(1.0 / 1.29)], &s).is_empty());
        assert_eq!(declared_moved(&[j(1.31), j(f64::NAN), j(0.0)], &s).len(), 3);
        // a re-fit kept within the factor that ends on its edge (either way) says so: the drive
        // engine's box lies a billionth inside the factor (exactly 1/1.3 is a rounding beyond it,
        // a move)
        let edge = 1.3f64.powf(1.0 - 1e-9);
        assert_eq!(declared_at_tolerance(&[j(edge), j(1.0 / edge), j(1.29), j(f64::NAN)], &s).len(), 2);
        // and a ratio beyond the factor is a move (`declared_moved`), not an edge
        assert!(declared_at_tolerance(&[j(2.0), j(0.4)], &s).is_empty());
    }

    /// The declared mechanics are distorted only where the record prefers the free re-fit by
    /// the evidence that names a finding; a boxed re-fit that failed (no score) leaves them so.
    #[test]
    fn only_a_move_the_record_demands_distorts_the_declared_model() {
        let s = DeclaredSettings::default();
        assert!(!moved_by_the_record(-1000.0, -994.5, &s));
        assert!(moved_by_the_record(-1000.0, -994.0, &s));
        assert!(moved_by_the_record(-1000.0, f64::NAN, &s));
        assert!(moved_by_the_record(-1000.0, f64::INFINITY, &s));
    }

    #[test]
    fn the_declared_model_fits_only_where_the_residual_is_white() {
        assert_eq!(verdict("none", false, &[]), Verdict::DeclaredModelFits);
        assert_eq!(verdict("none", true, &[]), Verdict::NotExplained);
        // a dead time of half the record cannot be told from the record
        let p = BTreeMap::from([("delay_s".to_string(), 5.0)]);
        assert_eq!(out_of_bounds(&p, &scales(), &BoundSettings::default()).len(), 1);
        let p = BTreeMap::from([("delay_s".to_string(), f64::NAN)]);
        assert_eq!(out_of_bounds(&p, &scales(), &BoundSettings::default()).len(), 1, "NaN is never a finding");
        // nor a lag at the floor of its search, 0.3 of the 1 ms sample; one sample is a finding
        let p = BTreeMap::from([("time_constant_s".to_string(), 3.0e-4)]);
        assert_eq!(out_of_bounds(&p, &scales(), &BoundSettings::default()).len(), 1);
        let p = BTreeMap::from([("time_constant_s".to_string(), 1.0e-3)]);
        assert!(out_of_bounds(&p, &scales(), &BoundSettings::default()).is_empty());
    }

    #[test]
    fn an_effect_and_its_place_are_named_only_with_strong_evidence_over_every_other() {
        let c = |effect: &str, at: Option<&str>, score| CandidateScore {
            effect: effect.into(),
            at: at.map(Into::into),
            parameters: BTreeMap::new(),
            error_after: 0.1,
            score,
            fitted_parameters: 1,
            implausible: false,
            implausible_because: Vec::new(),
            parts: effect
                .split(" + ")
                .zip(at.map_or_else(|| vec![""; 2], |a| a.split(" + ").collect()))
                .map(|(e, a)| (e.to_string(), a.to_string()))
                .collect(),
        };
        let s = PlaceSettings::default();
        let answer = c("backlash", Some("coupling 5"), -256.3);
        // the same effect elsewhere 2.5 apart: "positive" evidence only, no place
        let rivals = [answer.clone(), c("backlash", Some("coupling 4"), -253.8), c("none", None, -300.0)];
        let why = undetermined(&answer, &rivals, &s).expect("two places alike");
        assert!(why.contains("tell where") && why.contains("coupling 4"), "{why}");
        // another effect 0.5 apart: the record does not tell what
        let rivals = [c("backlash", Some("coupling 4"), -240.0), c("actuator_lag", Some("input 2"), -255.8)];
        let why = undetermined(&answer, &rivals, &s).expect("two effects alike");
        assert!(why.contains("tell what") && why.contains("input 2"), "{why}");
        // 6 or more apart from every rival, or a rival only implausible, leaves the answer named
        let mut distorted = c("coulomb_friction", Some("body b5"), -257.0);
        distorted.implausible = true;
        let rivals = [c("backlash", Some("coupling 4"), -250.3), distorted];
        assert_eq!(undetermined(&answer, &rivals, &s), None);
        // nested candidates are no rivals: the answer's own parts, and pairs that contain it
        let pair = c("backlash + time_delay", Some("coupling 5 + input 1"), -256.0);
        assert_eq!(undetermined(&answer, std::slice::from_ref(&pair), &s), None);
        assert_eq!(undetermined(&pair, std::slice::from_ref(&answer), &s), None);
        // but a pair with the answer's second effect elsewhere is
        let elsewhere = c("backlash + time_delay", Some("coupling 5 + input 2"), -255.0);
        assert!(undetermined(&pair, &[elsewhere], &s).is_some());
        // the declared model, chosen where no effect beat it clearly, is no finding to tell apart
        assert_eq!(undetermined(&c("none", None, -250.0), std::slice::from_ref(&answer), &s), None);
        // places are compared as the candidates name them, not as the report's joined text
        // reads: a body whose name holds " + " is one place, another body no part of it
        let mut odd = c("coulomb_friction", None, -256.3);
        odd.at = Some("body pinion + hub".into());
        odd.parts = vec![("coulomb_friction".into(), "body pinion + hub".into())];
        let mut near = c("coulomb_friction", None, -255.0);
        near.at = Some("body pinion".into());
        near.parts = vec![("coulomb_friction".into(), "body pinion".into())];
        let why = undetermined(&odd, &[near], &s).expect("two places alike");
        assert!(why.contains("tell where") && why.contains("at body pinion (error"), "{why}");
    }
}
