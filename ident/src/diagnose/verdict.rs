//! The diagnosis's answer in one word, and the physical bounds a found effect's parameters must
//! keep to be a finding: what the record can show, not what a fit can reach.
//!
//! - *explained*: effects were found, each parameter inside its bounds;
//! - *declared model fits*: no effect improves the declared model clearly and what is left is
//!   noise (a white residual);
//! - *not explained*: a structured residual that no candidate explains with physical
//!   parameters — no effect found, or the best one's parameters at or beyond a bound.

use std::collections::BTreeMap;

use serde::Serialize;

/// The diagnosis's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The effects found explain the record.
    Explained,
    /// The declared model fits: nothing is missing that the record shows.
    DeclaredModelFits,
    /// The record shows something that no candidate explains with physical parameters.
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
}

impl Default for BoundSettings {
    fn default() -> Self {
        BoundSettings { friction_per_force: 1.0, smoothing_per_speed: 0.25, time_per_record: 0.1 }
    }
}

/// Which of `parameters` (report keys with units) lie at or beyond their physical bounds, each
/// as a sentence for the report. Keys without a bound here (re-fitted inertias, stiffnesses,
/// dampings, plays) are not judged.
pub fn out_of_bounds(parameters: &BTreeMap<String, f64>, scales: &RecordScales, s: &BoundSettings) -> Vec<String> {
    let mut out = Vec::new();
    for (key, &v) in parameters {
        let (bound, what) = if key.starts_with("friction") {
            (s.friction_per_force * scales.max_force, "the largest force (torque) the record applies")
        } else if key.starts_with("smoothing_speed") {
            (s.smoothing_per_speed * scales.rms_speed, "a quarter of the record's RMS speed")
        } else if key == "delay_s" || key == "time_constant_s" {
            (s.time_per_record * scales.duration_s, "a tenth of the record")
        } else {
            continue;
        };
        if !v.is_finite() || v >= bound {
            out.push(format!("{key} = {v:.4e} is at or beyond its bound {bound:.4e} ({what})"));
        }
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    fn scales() -> RecordScales {
        RecordScales { max_force: 2.0, rms_speed: 20.0, duration_s: 10.0 }
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

    #[test]
    fn the_declared_model_fits_only_where_the_residual_is_white() {
        assert_eq!(verdict("none", false, &[]), Verdict::DeclaredModelFits);
        assert_eq!(verdict("none", true, &[]), Verdict::NotExplained);
        // a dead time of half the record cannot be told from the record
        let p = BTreeMap::from([("delay_s".to_string(), 5.0)]);
        assert_eq!(out_of_bounds(&p, &scales(), &BoundSettings::default()).len(), 1);
        let p = BTreeMap::from([("delay_s".to_string(), f64::NAN)]);
        assert_eq!(out_of_bounds(&p, &scales(), &BoundSettings::default()).len(), 1, "NaN is never a finding");
    }
}
