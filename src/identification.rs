//! Reports of `rigtwin parametrise` and `rigtwin design-spring`.

use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use ident::{
    design_spring, Confidence, Design, DesignSettings, FrequencyEstimate, Measurement, ModelChoice, MonteCarlo,
    PairSolution, Parametrisation, ParametriseSettings, SeenMode, SweepSettings,
};
use plant::{Deflection, Rig, RigParams, Variant};

use crate::bundle::load_torsional;

/// Which sweep estimate feeds the parametrisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrequencyMethod {
    /// Modal fit of the frequency response (default).
    ModalFit,
    /// The paper's power-over-time procedure (section 3).
    Paper,
}

/// Where the frequencies come from.
pub enum Source {
    /// Sweep bundles.
    Bundles(Vec<PathBuf>),
    /// Frequencies typed in, with one uncertainty, and the rig that supplies the known values.
    Measured {
        /// The rig (its `[model]` gives the load inertias, c_delta, c_long/c_short).
        rig: Box<Rig>,
        /// (variant, Hz).
        values: Vec<(Variant, f64)>,
        /// Standard uncertainty of each, Hz.
        sigma_hz: f64,
    },
}

/// One variant's frequency and where it came from.
#[derive(Debug, Clone, Serialize)]
pub struct MeasurementReport {
    /// Bundle file, if any.
    pub file: Option<String>,
    /// Variant.
    pub variant: Variant,
    /// The frequency used, Hz.
    pub frequency_hz: f64,
    /// Its standard uncertainty, Hz.
    pub sigma_hz: f64,
    /// The paper's estimate (bundles only).
    pub paper: Option<FrequencyEstimate>,
    /// The modal fit (bundles only).
    pub modal_fit: Option<FrequencyEstimate>,
    /// The mode the sweep showed (bundles only).
    pub mode_seen: Option<SeenMode>,
    /// Phase of M2 against M3 at the resonance, degrees (bundles only).
    pub phase_m2_m3_deg: Option<f64>,
    /// Unit conversions and sensor calibrations applied to the bundle's channels.
    pub conversions: Vec<String>,
}

/// All solutions of one variant pair.
#[derive(Debug, Clone, Serialize)]
pub struct PairReport {
    /// The two variants.
    pub variants: [Variant; 2],
    /// Every real, positive solution.
    pub solutions: Vec<PairSolution>,
}

/// The estimate in the contract's shape, with the details beside it.
#[derive(Debug, Clone, Serialize)]
pub struct EstimateReport {
    /// Model used.
    pub model: ModelChoice,
    /// kg m².
    #[serde(rename = "j_drive_kgm2")]
    pub j_drive: f64,
    /// Nm/rad.
    #[serde(rename = "c_short_Nm_per_rad")]
    pub c_short: f64,
    /// Nm/rad.
    #[serde(rename = "c_long_Nm_per_rad")]
    pub c_long: f64,
    /// 95 % interval, kg m² (Monte Carlo where it solved, else linearised).
    #[serde(rename = "j_drive_ci95_kgm2")]
    pub j_drive_ci95: Option<[f64; 2]>,
    /// 95 % interval, Nm/rad.
    #[serde(rename = "c_short_ci95_Nm_per_rad")]
    pub c_short_ci95: Option<[f64; 2]>,
    /// "monte_carlo" or "linearised".
    pub ci_method: &'static str,
    /// Linearised intervals.
    pub linearised: Option<Confidence>,
    /// Monte Carlo intervals and failure rate.
    pub monte_carlo: Option<MonteCarlo>,
    /// Correlation of j_drive and c_short (linearised).
    pub correlation: Option<f64>,
    /// χ² of the fit.
    pub chi2: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// √max(1, χ²/dof): the factor by which the intervals' frequency uncertainties were widened.
    pub sigma_scale: f64,
    /// Model − measured shuffle frequency, Hz.
    pub residuals_hz: BTreeMap<String, f64>,
}

/// The other model's least-squares estimate, for comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// Model.
    pub model: ModelChoice,
    /// kg m².
    #[serde(rename = "j_drive_kgm2")]
    pub j_drive: Option<f64>,
    /// Nm/rad.
    #[serde(rename = "c_short_Nm_per_rad")]
    pub c_short: Option<f64>,
    /// χ² of its fit.
    pub chi2: Option<f64>,
}

/// `rigtwin parametrise`.
#[derive(Debug, Clone, Serialize)]
pub struct ParametriseReport {
    /// Model of the estimate and the pairs.
    pub model: ModelChoice,
    /// Sweep estimate used.
    pub method: FrequencyMethod,
    /// Frequency per variant (inverse-variance mean of repeats), Hz.
    pub measured_hz: BTreeMap<String, f64>,
    /// Every input.
    pub measurements: Vec<MeasurementReport>,
    /// Every pair of different variants.
    pub pairs: Vec<PairReport>,
    /// The tool's answer: the extension's j_drive and c_short where one explains the variants,
    /// else the least-squares estimate of `model`.
    pub answer: Answer,
    /// Least squares over all variants with `model` (the ideal open differential by default).
    pub least_squares: EstimateReport,
    /// The other model.
    pub other_model: Comparison,
    /// The extended models fitted when the open differential misses the variants (χ²/dof above
    /// `ident::parametrise::EXTEND_ABOVE_CHI2_PER_DOF`), lowest χ² first; empty otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub extensions: Vec<ident::parametrise::ExtendedEstimate>,
    /// The extension that explains the variants (the first of `extensions`): its j_drive and
    /// c_short, with its intervals, are then the answer rather than `estimate`'s.
    pub explained_by: Option<ident::parametrise::Extension>,
    /// Things the user should know.
    pub warnings: Vec<String>,
}

/// The parametrisation's answer, whichever model gave it.
#[derive(Debug, Clone, Serialize)]
pub struct Answer {
    /// Which model: `differential`, `smooth`, or `differential_with_side_gears` /
    /// `differential_with_asymmetry` (an extension that explains the variants).
    pub model: String,
    /// Drive inertia, kg m².
    pub j_drive_kgm2: f64,
    /// Short side-shaft stiffness, N m/rad.
    #[serde(rename = "c_short_Nm_per_rad")]
    pub c_short_nm_per_rad: f64,
    /// 95 % interval of `j_drive_kgm2` (null where not bounded).
    pub j_drive_ci95_kgm2: Option<[f64; 2]>,
    /// 95 % interval of `c_short_Nm_per_rad`.
    #[serde(rename = "c_short_ci95_Nm_per_rad")]
    pub c_short_ci95_nm_per_rad: Option<[f64; 2]>,
    /// χ² of the model that gave it, and its degrees of freedom.
    pub chi2: f64,
    /// Degrees of freedom of `chi2`.
    pub dof: usize,
    /// Whether that model is consistent with every variant: χ² below its 95 % quantile
    /// (`ident::parametrise::chi2_95`; with no degree of freedom left, χ² must be 0).
    pub explains_the_variants: bool,
}

/// A rig model's name as a person reads it.
fn model_words(m: ModelChoice) -> &'static str {
    match m {
        ModelChoice::Differential => "the open differential",
        ModelChoice::Smooth => "the smooth strand (eq. 14)",
    }
}

/// Runs the whole parametrisation.
pub fn parametrise(
    source: Source,
    model: ModelChoice,
    method: FrequencyMethod,
    sigma_override: Option<f64>,
    settings: &ParametriseSettings,
) -> anyhow::Result<ParametriseReport> {
    let mut warnings = Vec::new();
    settings.validate().map_err(|e| anyhow::anyhow!("--samples: {e}"))?;
    let (template, measurements) = match source {
        Source::Measured { rig, values, sigma_hz } => {
            for (i, (v, _)) in values.iter().enumerate() {
                if values[..i].iter().any(|(w, _)| w == v) {
                    anyhow::bail!("--measured {v} is given twice: give each variant's frequency once");
                }
            }
            let m = values
                .into_iter()
                .map(|(variant, f)| MeasurementReport {
                    file: None,
                    variant,
                    frequency_hz: f,
                    sigma_hz: sigma_override.unwrap_or(sigma_hz),
                    paper: None,
                    modal_fit: None,
                    mode_seen: None,
                    phase_m2_m3_deg: None,
                    conversions: Vec::new(),
                })
                .collect();
            (rig.model, m)
        }
        Source::Bundles(files) => {
            for (i, f) in files.iter().enumerate() {
                let same = |g: &PathBuf| match (std::fs::canonicalize(f), std::fs::canonicalize(g)) {
                    (Ok(a), Ok(b)) => a == b,
                    _ => f == g,
                };
                if let Some(g) = files[..i].iter().find(|g| same(g)) {
                    anyhow::bail!(
                        "{} is given twice ({} and {}): each variant's sweep counts once; give sweeps of at least two variants",
                        f.display(),
                        g.display(),
                        f.display()
                    );
                }
            }
            let mut template: Option<(PathBuf, RigParams)> = None;
            let mut m = Vec::new();
            for f in files {
                let b = load_torsional(&f)?;
                if let Some((first, t)) = &template {
                    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
                    let ratio = |p: &RigParams| p.c_long() / p.c_short;
                    if !(same(t.j_m2, b.model.j_m2)
                        && same(t.j_m3, b.model.j_m3)
                        && same(t.c_delta, b.model.c_delta)
                        && same(ratio(t), ratio(&b.model)))
                    {
                        anyhow::bail!(
                            "{} and {} declare different known parameters (j_m2, j_m3, c_delta or c_long/c_short): \
                             the variants of one parametrisation must come from one rig",
                            first.display(),
                            f.display()
                        );
                    }
                } else {
                    template = Some((f.clone(), b.model.clone()));
                }
                let a =
                    b.sweep.analyse(&SweepSettings::default()).map_err(|e| anyhow::anyhow!("{}: {e}", f.display()))?;
                if a.mode != SeenMode::Shuffle {
                    warnings.push(format!(
                        "{}: the load machines are not in phase at the resonance (phase {:.0}°): the sweep may not show the shuffle mode",
                        f.display(),
                        a.phase_m2_m3_deg
                    ));
                }
                let chosen = match method {
                    FrequencyMethod::ModalFit => &a.modal_fit,
                    FrequencyMethod::Paper => &a.paper,
                };
                m.push(MeasurementReport {
                    file: Some(f.display().to_string()),
                    variant: b.variant,
                    frequency_hz: chosen.frequency_hz,
                    sigma_hz: sigma_override.unwrap_or(chosen.sigma_hz),
                    paper: Some(a.paper.clone()),
                    modal_fit: Some(a.modal_fit.clone()),
                    mode_seen: Some(a.mode),
                    phase_m2_m3_deg: Some(a.phase_m2_m3_deg),
                    conversions: b.conversions.clone(),
                });
            }
            let (_, t) = template.ok_or_else(|| anyhow::anyhow!("no bundle given"))?;
            if m.iter().all(|x| x.variant == m[0].variant) {
                let names: Vec<&str> = m.iter().filter_map(|x| x.file.as_deref()).collect();
                anyhow::bail!(
                    "every bundle is a sweep of variant {} ({}): the parametrisation needs sweeps of at least two variants",
                    m[0].variant,
                    names.join(", ")
                );
            }
            (t, m)
        }
    };
    let meas: Vec<Measurement> = measurements
        .iter()
        .map(|m| Measurement { variant: m.variant, frequency_hz: m.frequency_hz, sigma_hz: m.sigma_hz })
        .collect();
    let mut measured_hz = BTreeMap::new();
    for v in Variant::ALL {
        let of: Vec<&Measurement> = meas.iter().filter(|m| m.variant == v).collect();
        if !of.is_empty() {
            let w: f64 = of.iter().map(|m| 1.0 / (m.sigma_hz * m.sigma_hz)).sum();
            measured_hz
                .insert(v.to_string(), of.iter().map(|m| m.frequency_hz / (m.sigma_hz * m.sigma_hz)).sum::<f64>() / w);
        }
    }
    let problem = Parametrisation::new(&template, model)?;
    let mut pairs = Vec::new();
    for (i, a) in meas.iter().enumerate() {
        for b in &meas[i + 1..] {
            if a.variant != b.variant {
                pairs.push(PairReport { variants: [a.variant, b.variant], solutions: problem.pair(a, b, settings)? });
            }
        }
    }
    // the estimate is only a result where some pair of variants admits a solution at all
    if !pairs.is_empty() && pairs.iter().all(|p| p.solutions.is_empty()) {
        let list: Vec<String> = measured_hz.iter().map(|(v, f)| format!("{v} = {f:.4} Hz")).collect();
        anyhow::bail!(
            "no pair of variants has a real positive (j_drive, c_short) that gives its frequencies ({}): the \
             {} cannot explain these measurements, so there is nothing to estimate",
            list.join(", "),
            model_words(model)
        );
    }
    let e = problem.estimate(&meas, settings)?;
    let checks = ident::parametrise::EstimateChecks::default();
    let (extensions, explains) = problem.explain(&meas, &e);
    let explained_by = explains.then(|| extensions[0].extension);
    let mc_ci = e.monte_carlo.as_ref().and_then(|m| m.confidence.clone());
    let (ci, ci_method) = match (&mc_ci, &e.linearised) {
        (Some(c), _) => (Some(c.clone()), "monte_carlo"),
        (None, l) => (l.clone(), "linearised"),
    };
    if let Some(mc) = &e.monte_carlo {
        if checks.ill_conditioned(mc) {
            warnings.push(format!(
                "{:.0} % of frequency sets drawn within the uncertainty have no solution on the shuffle mode: \
                 the variants hardly separate j_drive and c_short (an ill-conditioned rig, section 4.1)",
                100.0 * mc.failed_fraction
            ));
        }
    }
    for (name, value, ci, unit) in [
        ("j_drive", e.j_drive, ci.as_ref().map(|c| c.j_drive_ci95), "kg m^2"),
        ("c_short", e.c_short, ci.as_ref().map(|c| c.c_short_ci95), "Nm/rad"),
    ] {
        match ci {
            Some([lo, hi]) if checks.unidentifiable(value, [lo, hi]) => warnings.push(format!(
                "{name} is not identifiable from these frequencies: its 95 % interval [{lo:.4}, {hi:.4}] {unit} is wider than ±{:.0} % of {value:.4}",
                100.0 * checks.max_relative_half_width
            )),
            None => warnings.push(format!("{name} has no confidence interval: the measurements do not bound it")),
            _ => {}
        }
    }
    if checks.unexplained(&e) {
        warnings.push(format!(
            "{} does not explain all variants within their uncertainties (χ²/dof = {:.1}): \
             the intervals are widened by √(χ²/dof) = {:.2}; a residual this size points to an effect the model lacks",
            model_words(e.model),
            e.chi2 / e.dof as f64,
            e.sigma_scale
        ));
    }
    let estimate = EstimateReport {
        model: e.model,
        j_drive: e.j_drive,
        c_short: e.c_short,
        c_long: e.c_long,
        j_drive_ci95: ci.as_ref().map(|c| c.j_drive_ci95),
        c_short_ci95: ci.as_ref().map(|c| c.c_short_ci95),
        ci_method,
        linearised: e.linearised.clone(),
        monte_carlo: e.monte_carlo.clone(),
        correlation: e.correlation,
        chi2: e.chi2,
        dof: e.dof,
        sigma_scale: e.sigma_scale,
        residuals_hz: e.residuals_hz.iter().map(|(v, r)| (v.to_string(), *r)).collect(),
    };
    let other = match model {
        ModelChoice::Differential => ModelChoice::Smooth,
        ModelChoice::Smooth => ModelChoice::Differential,
    };
    let quick = ParametriseSettings { monte_carlo_samples: 0, ..settings.clone() };
    let other_fit = Parametrisation::new(&template, other)?.estimate(&meas, &quick).ok();
    let other_model = Comparison {
        model: other,
        j_drive: other_fit.as_ref().map(|f| f.j_drive),
        c_short: other_fit.as_ref().map(|f| f.c_short),
        chi2: other_fit.as_ref().map(|f| f.chi2),
    };
    // where an extension explains the variants its values are the answer (`answer`, said first)
    if !explains && !extensions.is_empty() {
        warnings.push(
            "no extension (side gears' inertia, an asymmetry) explains the variants better: the misfit stays unexplained"
                .into(),
        );
    }
    let answer = match extensions.first().filter(|_| explains) {
        Some(x) => Answer {
            model: format!("differential_with_{}", serde_json::to_value(x.extension)?.as_str().unwrap_or("")),
            j_drive_kgm2: x.j_drive,
            c_short_nm_per_rad: x.c_short,
            j_drive_ci95_kgm2: x.j_drive_ci95,
            c_short_ci95_nm_per_rad: x.c_short_ci95,
            chi2: x.chi2,
            dof: x.dof,
            explains_the_variants: x.chi2 <= ident::parametrise::chi2_95(x.dof),
        },
        None => Answer {
            model: serde_json::to_value(model)?.as_str().unwrap_or("").to_string(),
            j_drive_kgm2: estimate.j_drive,
            c_short_nm_per_rad: estimate.c_short,
            j_drive_ci95_kgm2: estimate.j_drive_ci95,
            c_short_ci95_nm_per_rad: estimate.c_short_ci95,
            chi2: estimate.chi2,
            dof: estimate.dof,
            explains_the_variants: estimate.chi2 <= ident::parametrise::chi2_95(estimate.dof),
        },
    };
    Ok(ParametriseReport {
        model,
        method,
        measured_hz,
        measurements,
        pairs,
        answer,
        least_squares: estimate,
        other_model,
        extensions,
        explained_by,
        warnings,
    })
}

fn interval(ci: Option<[f64; 2]>, digits: usize) -> String {
    ci.map(|[a, b]| format!("[{a:.digits$}, {b:.digits$}]")).unwrap_or_else(|| "not bounded".into())
}

impl ParametriseReport {
    /// Human-readable form.
    pub fn human(&self) -> String {
        let mut s = String::new();
        let a = &self.answer;
        let _ = writeln!(
            s,
            "j_drive {} {}, c_short {} {} (95 % intervals)",
            crate::units::quantity(a.j_drive_kgm2, "kg·m²"),
            interval(a.j_drive_ci95_kgm2, 4),
            crate::units::quantity(a.c_short_nm_per_rad, "N·m/rad"),
            interval(a.c_short_ci95_nm_per_rad, 1),
        );
        let from = match self.explained_by {
            Some(ident::parametrise::Extension::SideGears) => {
                format!("{} with its side gears' inertia", model_words(self.model))
            }
            Some(ident::parametrise::Extension::Asymmetry) => {
                format!("{} with c_long/c_short fitted", model_words(self.model))
            }
            None => model_words(self.model).to_string(),
        };
        let _ = writeln!(
            s,
            "  from {from}, which {} the {} variants (χ² {:.2} with {} degrees of freedom; 95 % bound {:.2})",
            if a.explains_the_variants { "explains" } else { "does NOT explain all of" },
            self.measured_hz.len(),
            a.chi2,
            a.dof,
            ident::parametrise::chi2_95(a.dof)
        );
        let method = match self.method {
            FrequencyMethod::ModalFit => "modal fit of each sweep",
            FrequencyMethod::Paper => "the paper's power-over-time method",
        };
        let _ =
            writeln!(s, "\nHow: the shuffle frequency of each variant ({method}), then {}:", model_words(self.model));
        let _ = writeln!(s, "  variant  f [Hz]      σ [Hz]    paper's method [Hz]   mode seen       source");
        for m in &self.measurements {
            let paper = m
                .paper
                .as_ref()
                .map(|p| format!("{:.3} ± {:.3}", p.frequency_hz, p.sigma_hz))
                .unwrap_or_else(|| "-".into());
            let mode = m
                .mode_seen
                .map(|k| {
                    let seen = match k {
                        ident::SeenMode::Shuffle => "shuffle",
                        ident::SeenMode::OutputsAntiphase => "loads antiphase",
                        ident::SeenMode::Unclear => "unclear",
                    };
                    format!("{seen} ({:+.0}°)", m.phase_m2_m3_deg.unwrap_or(0.0))
                })
                .unwrap_or_else(|| "-".into());
            let _ = writeln!(
                s,
                "  {:<7}  {:<10.4}  {:<8.4}  {:<20}  {:<14}  {}",
                m.variant.to_string(),
                m.frequency_hz,
                m.sigma_hz,
                paper,
                mode,
                m.file.as_deref().unwrap_or("typed in")
            );
            for c in &m.conversions {
                let _ = writeln!(s, "           converted: {c}");
            }
        }
        let _ = writeln!(s, "\n  pair    j_drive [kg m^2]  c_short [Nm/rad]  measured on the shuffle mode");
        for p in &self.pairs {
            let name = format!("{}/{}", p.variants[0], p.variants[1]);
            if p.solutions.is_empty() {
                let _ = writeln!(s, "  {name:<7} no real positive solution");
            }
            for sol in &p.solutions {
                let modes: Vec<String> =
                    sol.placements.iter().map(|pl| format!("{} at f{}", pl.variant, pl.mode)).collect();
                let _ = writeln!(
                    s,
                    "  {name:<7} {:>16.4}  {:>16.1}  {} ({})",
                    sol.j_drive,
                    sol.c_short,
                    if sol.shuffle { "yes" } else { "no" },
                    modes.join(", ")
                );
            }
        }
        let e = &self.least_squares;
        let _ = writeln!(
            s,
            "\n  least squares over {} measurements (χ² = {:.3}, dof {}), {} 95 % intervals:",
            self.measurements.len(),
            e.chi2,
            e.dof,
            e.ci_method.replace('_', " ")
        );
        let _ = writeln!(s, "    j_drive = {:.4} kg m^2   {}", e.j_drive, interval(e.j_drive_ci95, 4));
        let _ = writeln!(s, "    c_short = {:.1} Nm/rad   {}", e.c_short, interval(e.c_short_ci95, 1));
        let _ = writeln!(s, "    c_long  = {:.1} Nm/rad", e.c_long);
        if let Some(mc) = &e.monte_carlo {
            let _ = writeln!(
                s,
                "    Monte Carlo: {} draws, {:.1} % without a solution",
                mc.samples,
                100.0 * mc.failed_fraction
            );
        }
        if let Some(l) = &e.linearised {
            let _ = writeln!(
                s,
                "    linearised: j_drive {}, c_short {}",
                interval(Some(l.j_drive_ci95), 4),
                interval(Some(l.c_short_ci95), 1)
            );
        }
        for x in &self.extensions {
            let chosen = if Some(x.extension) == self.explained_by { " ← explains the variants" } else { "" };
            let _ = writeln!(
                s,
                "  extended by {}: {} = {:.4e} {}, j_drive = {:.4} kg m^2 {}, c_short = {:.1} Nm/rad {}, χ² = {:.3} (dof {}){chosen}",
                match x.extension {
                    ident::parametrise::Extension::SideGears => "the side gears' inertia",
                    ident::parametrise::Extension::Asymmetry => "c_long/c_short fitted",
                },
                x.extension.parameter(),
                x.value,
                interval(x.value_ci95, 6),
                x.j_drive,
                interval(x.j_drive_ci95, 4),
                x.c_short,
                interval(x.c_short_ci95, 1),
                x.chi2,
                x.dof
            );
        }
        let o = &self.other_model;
        match (o.j_drive, o.c_short, o.chi2) {
            (Some(j), Some(c), Some(x)) => {
                let _ = writeln!(
                    s,
                    "  for comparison, {}: j_drive {j:.4} kg m^2, c_short {c:.1} Nm/rad, χ² = {x:.3}",
                    model_words(o.model)
                );
            }
            _ => {
                let _ = writeln!(s, "  for comparison, {} finds no estimate", model_words(o.model));
            }
        }
        for w in &self.warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
        s
    }
}

/// `rigtwin design-spring`: the design study, and the extra shaft's bending if described.
#[derive(Debug, Clone, Serialize)]
pub struct DesignReport {
    /// Rig name.
    pub rig: String,
    /// The study.
    pub design: Design,
    /// Deflection of the rig's `[bending]` shaft line under its own weight (section 2.5).
    pub bending: Option<Deflection>,
}

/// Runs the design study for a rig.
pub fn design(rig: &Rig, model: ModelChoice, settings: &DesignSettings) -> anyhow::Result<DesignReport> {
    let design = design_spring(&rig.model, model, settings)?;
    let bending = match &rig.bending {
        Some(beam) => Some(beam.deflection(plant::bending::GRAVITY_M_PER_S2, 4000)?),
        None => None,
    };
    Ok(DesignReport { rig: rig.name.clone(), design, bending })
}

fn pct(x: f64) -> String {
    if x >= 1e6 {
        "not identifiable".into()
    } else {
        format!("±{:.1} %", 100.0 * x)
    }
}

impl DesignReport {
    /// Human-readable form.
    pub fn human(&self) -> String {
        let d = &self.design;
        let st = &d.settings;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Additional-spring design — {} ({} model), σ_f = {} Hz per variant, target ±{:.1} % (95 %)",
            self.rig,
            crate::report::words(&d.model),
            st.sigma_hz,
            100.0 * st.target
        );
        let sets = |v: &[Variant]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join("+");
        let _ = writeln!(
            s,
            "  the rig's spring, c_delta = {:.0} Nm/rad:",
            d.current.first().map(|r| r.c_delta).unwrap_or(0.0)
        );
        for r in &d.current {
            let _ = writeln!(
                s,
                "    {:<12} shift {:.3} Hz   j_drive {:<18} c_short {}",
                sets(&r.variants),
                r.shift_hz,
                pct(r.j_drive_rel_ci95),
                pct(r.c_short_rel_ci95)
            );
        }
        match &d.recommended {
            Some(r) => {
                let _ = writeln!(
                    s,
                    "  recommended: c_delta = {:.0} Nm/rad with {} (the stiffest that meets the target): j_drive {}, c_short {}, shift {:.3} Hz",
                    r.c_delta,
                    sets(&r.variants),
                    pct(r.j_drive_rel_ci95),
                    pct(r.c_short_rel_ci95),
                    r.shift_hz
                );
            }
            None => {
                let b = &d.best;
                let _ = writeln!(
                    s,
                    "  no c_delta in the range meets the target; best: c_delta = {:.0} Nm/rad with {}: j_drive {}, c_short {} — a smaller σ_f is needed",
                    b.c_delta,
                    sets(&b.variants),
                    pct(b.j_drive_rel_ci95),
                    pct(b.c_short_rel_ci95)
                );
            }
        }
        let _ = writeln!(
            s,
            "  c_delta [Nm/rad]   {}",
            st.variant_sets.iter().map(|v| format!("{:<24}", sets(v))).collect::<String>()
        );
        for chunk in d.rows.chunks(st.variant_sets.len()).step_by(3) {
            let cells: String = chunk
                .iter()
                .map(|r| format!("{:<24}", format!("{} / {}", pct(r.j_drive_rel_ci95), pct(r.c_short_rel_ci95))))
                .collect();
            let _ = writeln!(s, "  {:>14.0}     {cells}", chunk[0].c_delta);
        }
        let _ = writeln!(s, "  (cells: 95 % half-width of j_drive / c_short)");
        if let Some(b) = &self.bending {
            let _ = writeln!(
                s,
                "  bending under self-weight (section 2.5): max {:.1} µm at {:.3} m; bearing forces {:.1} N, {:.1} N",
                b.max_m * 1e6,
                b.at_m,
                b.bearing_forces_n[0],
                b.bearing_forces_n[1]
            );
        }
        s
    }
}
