//! Design of the additional spring (the paper's future work, sections 4.1 and 5): which c_delta,
//! and which variants, make j_drive and c_short identifiable to a requested accuracy for a given
//! frequency uncertainty. Linearised: the 95 % half-width in ln j and ln c is 1.96 √diag((JᵀJ)⁻¹)
//! with J = ∂f_shuffle/∂(ln j, ln c) / σ over the variants measured. A softer spring shifts the
//! frequency more, but a spring much softer than the side shaft hides c_short behind itself;
//! and the softer the spring, the longer and thinner the extra shaft (travel of the load
//! machines, bending, section 2.5). The recommendation is therefore the stiffest c_delta that
//! meets the target.

use serde::Serialize;

use crate::error::{IdentError, Result};
use crate::parametrise::{ModelChoice, Parametrisation};
use plant::{RigParams, Variant};

/// What to design for.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignSettings {
    /// Standard uncertainty of each measured frequency, Hz.
    pub sigma_hz: f64,
    /// Required relative 95 % half-width of j_drive and c_short (0.05 = ±5 %).
    pub target: f64,
    /// c_delta searched from `.0 ×` to `.1 ×` c_short.
    pub c_delta_range: (f64, f64),
    /// Points of the logarithmic c_delta grid.
    pub points: usize,
    /// Variant sets compared.
    pub variant_sets: Vec<Vec<Variant>>,
}

impl Default for DesignSettings {
    fn default() -> Self {
        use Variant::*;
        DesignSettings {
            sigma_hz: 0.05,
            target: 0.05,
            c_delta_range: (0.1, 100.0),
            points: 31,
            variant_sets: vec![vec![V1, V2], vec![V1, V3], vec![V1, V4], vec![V1, V2, V3, V4]],
        }
    }
}

/// Identifiability with one spring and one set of variants.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignRow {
    /// Additional spring, Nm/rad.
    pub c_delta: f64,
    /// Variants measured.
    pub variants: Vec<Variant>,
    /// Largest shuffle-frequency shift against V1 among the variants, Hz.
    pub shift_hz: f64,
    /// Relative 95 % half-width of j_drive (inf: not identifiable).
    pub j_drive_rel_ci95: f64,
    /// Relative 95 % half-width of c_short.
    pub c_short_rel_ci95: f64,
    /// Both within the target.
    pub meets_target: bool,
}

/// The design study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Design {
    /// Model used.
    pub model: ModelChoice,
    /// Settings used.
    pub settings: DesignSettings,
    /// The rig's present spring, for every variant set.
    pub current: Vec<DesignRow>,
    /// The whole grid.
    pub rows: Vec<DesignRow>,
    /// The stiffest spring (fewest variants on a tie) that meets the target, if any.
    pub recommended: Option<DesignRow>,
    /// The row with the smallest worse half-width.
    pub best: DesignRow,
}

fn json_safe(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        f64::MAX
    }
}

/// The design study for the rig `template` (its j_drive and c_short are the expected values).
pub fn design_spring(template: &RigParams, model: ModelChoice, settings: &DesignSettings) -> Result<Design> {
    if !(settings.sigma_hz > 0.0 && settings.target > 0.0) {
        return Err(IdentError::Invalid(format!(
            "sigma_hz ({}) and target ({}) must be positive",
            settings.sigma_hz, settings.target
        )));
    }
    let row = |c_delta: f64, variants: &Vec<Variant>| -> Result<DesignRow> {
        let p = Parametrisation::new(&RigParams { c_delta, ..template.clone() }, model)?;
        let (j, c) = (template.j_drive, template.c_short);
        let f1 = p.shuffle_frequency_hz(Variant::V1, j, c).unwrap_or(f64::NAN);
        let shift = variants
            .iter()
            .filter_map(|&v| p.shuffle_frequency_hz(v, j, c))
            .map(|f| (f - f1).abs())
            .fold(0.0, f64::max);
        let [rj, rc] = p.relative_ci95(variants, j, c, settings.sigma_hz);
        Ok(DesignRow {
            c_delta,
            variants: variants.clone(),
            shift_hz: shift,
            j_drive_rel_ci95: json_safe(rj),
            c_short_rel_ci95: json_safe(rc),
            meets_target: rj <= settings.target && rc <= settings.target,
        })
    };
    let current = settings.variant_sets.iter().map(|set| row(template.c_delta, set)).collect::<Result<Vec<_>>>()?;
    let n = settings.points.max(2);
    let (lo, hi) = (template.c_short * settings.c_delta_range.0, template.c_short * settings.c_delta_range.1);
    let mut rows = Vec::new();
    for i in 0..n {
        let c_delta = lo * (hi / lo).powf(i as f64 / (n - 1) as f64);
        for set in &settings.variant_sets {
            rows.push(row(c_delta, set)?);
        }
    }
    let worse = |r: &DesignRow| r.j_drive_rel_ci95.max(r.c_short_rel_ci95);
    let recommended = rows
        .iter()
        .filter(|r| r.meets_target)
        .max_by(|a, b| a.c_delta.total_cmp(&b.c_delta).then(b.variants.len().cmp(&a.variants.len())))
        .cloned();
    let best = rows.iter().min_by(|a, b| worse(a).total_cmp(&worse(b))).cloned().expect("non-empty grid");
    Ok(Design { model, settings: settings.clone(), current, rows, recommended, best })
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::paper;

    #[test]
    fn a_tighter_frequency_makes_a_tighter_interval_in_proportion() {
        // Linearised half-widths scale with σ: halving σ halves them (independent of the model).
        let t = paper::params(0.529, 1479.0);
        let a = design_spring(&t, ModelChoice::Differential, &DesignSettings { sigma_hz: 0.02, ..Default::default() })
            .unwrap();
        let b = design_spring(&t, ModelChoice::Differential, &DesignSettings { sigma_hz: 0.01, ..Default::default() })
            .unwrap();
        let r = a.current[0].c_short_rel_ci95 / b.current[0].c_short_rel_ci95;
        assert!((r - 2.0).abs() < 1e-3, "{r}");
    }
}
