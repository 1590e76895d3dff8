//! Indirect parametrisation (sections 2.3 and 3, Tables 4 and 5) with confidence intervals.
//!
//! The load inertias, c_delta and c_long/c_short are known; the drive inertia j_drive and the
//! short side-shaft stiffness c_short are not. A variant's measured natural frequency ω gives
//! det(C(c_short) − ω² J(j_drive)) = 0 (eqs. (15), (19)); the determinant is affine in j_drive,
//! α(c) + β(c)·j_drive, so each variant ties j_drive to c_short, j = −α(c)/β(c), and two variants
//! leave the scalar equation P(c) = α_a(c) β_b(c) − α_b(c) β_a(c) = 0. P has no poles, so every
//! real positive root is found by a sign scan on a logarithmic grid and bisection. Each solution
//! is then checked as the paper does (Table 5): is the measured frequency, in both variants, the
//! frequency of the shuffle mode?
//!
//! With all variants, the least-squares estimate minimises Σ ((f_shuffle − f_meas)/σ)². Its
//! confidence is given twice: linearised, (JᵀJ)⁻¹ at the optimum, and by Monte Carlo over the
//! frequency uncertainty, which also counts how often a plausible measurement has no solution at
//! all — the honest answer for an ill-conditioned rig.

use nalgebra::{DMatrix, DVector, Vector2};
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use crate::error::{IdentError, Result};
use plant::{MechanicalModel, ModeKind, RigParams, Variant};

/// Which rig model the frequencies are explained with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelChoice {
    /// The open differential (section 2.4): the rig the measurements come from.
    #[default]
    Differential,
    /// The paper's smooth strand (eqs. (14), (18), (44), (45)), as used for Table 4.
    Smooth,
}

/// One variant's measured natural frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Measurement {
    /// Rig variant.
    pub variant: Variant,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Its standard uncertainty, Hz.
    pub sigma_hz: f64,
}

/// How to search and how to count confidence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParametriseSettings {
    /// c_short is searched from `c_range.0 ×` to `c_range.1 ×` the template's c_short.
    pub c_range: (f64, f64),
    /// Points of the logarithmic scan.
    pub scan_points: usize,
    /// Monte Carlo draws (0: none).
    pub monte_carlo_samples: usize,
    /// Seed of the Monte Carlo draws.
    pub seed: u64,
}

impl Default for ParametriseSettings {
    fn default() -> Self {
        ParametriseSettings { c_range: (1e-3, 1e3), scan_points: 4000, monte_carlo_samples: 2000, seed: 1 }
    }
}

/// When an estimate's figures are worth a warning beside it (`rigtwin identify`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EstimateChecks {
    /// Share of the Monte Carlo draws without a solution on the shuffle mode beyond which the
    /// variants hardly separate j_drive and c_short (an ill-conditioned rig, section 4.1).
    /// Default 0.05.
    pub max_failed_share: f64,
    /// Half-width of a 95 % interval, as a share of the value, beyond which the parameter is
    /// not identifiable from the frequencies. Default 0.5.
    pub max_relative_half_width: f64,
    /// Widening √(χ²/dof) of the intervals beyond which the model does not explain the
    /// variants within their uncertainties: √3 by default, χ²/dof = 3, which a model that
    /// fits exceeds by chance with 8 % probability at one degree of freedom, 5 % at two, 3 % at
    /// three.
    pub max_sigma_scale: f64,
}

impl Default for EstimateChecks {
    fn default() -> Self {
        EstimateChecks { max_failed_share: 0.05, max_relative_half_width: 0.5, max_sigma_scale: 3f64.sqrt() }
    }
}

impl EstimateChecks {
    /// Whether the Monte Carlo draws `mc` show an ill-conditioned rig.
    pub fn ill_conditioned(&self, mc: &MonteCarlo) -> bool {
        mc.failed_fraction > self.max_failed_share
    }

    /// Whether `value` with the 95 % interval `[lo, hi]` is not identifiable.
    pub fn unidentifiable(&self, value: f64, [lo, hi]: [f64; 2]) -> bool {
        (hi - lo) / 2.0 > self.max_relative_half_width * value
    }

    /// Whether the model leaves more of the measurements than their uncertainties explain.
    pub fn unexplained(&self, e: &Estimate) -> bool {
        e.sigma_scale > self.max_sigma_scale
    }
}

/// Most Monte Carlo draws a parametrisation takes: 100 000 resolve a 95 % interval's ends to
/// about 0.1 % of the interval; more only cost memory and time.
pub const MAX_MONTE_CARLO_SAMPLES: usize = 100_000;

impl ParametriseSettings {
    /// Checks ranges; names the setting.
    pub fn validate(&self) -> Result<()> {
        if self.monte_carlo_samples > MAX_MONTE_CARLO_SAMPLES {
            return Err(IdentError::Invalid(format!(
                "monte_carlo_samples = {}: at most {MAX_MONTE_CARLO_SAMPLES}",
                self.monte_carlo_samples
            )));
        }
        if !(self.c_range.0 > 0.0 && self.c_range.1 > self.c_range.0 && self.c_range.1.is_finite()) {
            return Err(IdentError::Invalid(format!("c_range = {:?}: expected 0 < lower < upper", self.c_range)));
        }
        if !(2..=1_000_000).contains(&self.scan_points) {
            return Err(IdentError::Invalid(format!("scan_points = {}: expected 2 to 1 000 000", self.scan_points)));
        }
        Ok(())
    }
}

/// Where a variant's measured frequency falls among the model's modes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Placement {
    /// Variant.
    pub variant: Variant,
    /// 1-based mode number (f1 is the rigid body).
    pub mode: usize,
    /// The model's frequency of that mode, Hz.
    pub model_frequency_hz: f64,
    /// Its character.
    pub kind: ModeKind,
}

/// One real, positive solution of a variant pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairSolution {
    /// Drive inertia, kg m².
    #[serde(rename = "j_drive_kgm2")]
    pub j_drive: f64,
    /// Short side-shaft stiffness, Nm/rad.
    #[serde(rename = "c_short_Nm_per_rad")]
    pub c_short: f64,
    /// Long side-shaft stiffness, Nm/rad.
    #[serde(rename = "c_long_Nm_per_rad")]
    pub c_long: f64,
    /// True when both measured frequencies are the model's shuffle frequency.
    pub shuffle: bool,
    /// Where each measured frequency falls.
    pub placements: Vec<Placement>,
}

/// A 95 % interval on j_drive and c_short.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Confidence {
    /// kg m².
    #[serde(rename = "j_drive_ci95_kgm2")]
    pub j_drive_ci95: [f64; 2],
    /// Nm/rad.
    #[serde(rename = "c_short_ci95_Nm_per_rad")]
    pub c_short_ci95: [f64; 2],
}

/// The Monte Carlo result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MonteCarlo {
    /// Draws made.
    pub samples: usize,
    /// Fraction of draws whose frequencies have no solution on the shuffle mode.
    pub failed_fraction: f64,
    /// Percentile intervals (2.5 %, 97.5 %) of the solved draws; null if none solved.
    pub confidence: Option<Confidence>,
}

/// The least-squares estimate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// Model used.
    pub model: ModelChoice,
    /// Drive inertia, kg m².
    pub j_drive: f64,
    /// Short side-shaft stiffness, Nm/rad.
    pub c_short: f64,
    /// Long side-shaft stiffness, Nm/rad.
    pub c_long: f64,
    /// Σ ((f_model − f_meas)/σ)².
    pub chi2: f64,
    /// Degrees of freedom, measurements − 2.
    pub dof: usize,
    /// Factor applied to the frequency uncertainties for the intervals, √max(1, χ²/dof).
    pub sigma_scale: f64,
    /// Model − measured shuffle frequency per variant, Hz.
    pub residuals_hz: Vec<(Variant, f64)>,
    /// Linearised 95 % intervals (null when the problem is singular at the estimate).
    pub linearised: Option<Confidence>,
    /// Correlation of j_drive and c_short (linearised).
    pub correlation: Option<f64>,
    /// Monte Carlo intervals.
    pub monte_carlo: Option<MonteCarlo>,
}

/// The parametrisation problem of one rig.
#[derive(Debug, Clone)]
pub struct Parametrisation {
    template: RigParams,
    model: ModelChoice,
    ratio: f64,
}

impl Parametrisation {
    /// `template` supplies the known parameters (load inertias, c_delta, inertias with the
    /// spring, and c_long/c_short — from `c_long` if given, else `c_long_ratio`).
    pub fn new(template: &RigParams, model: ModelChoice) -> Result<Self> {
        template.validate("model")?;
        let ratio = template.c_long.map(|c| c / template.c_short).unwrap_or(template.c_long_ratio);
        Ok(Parametrisation { template: template.clone(), model, ratio })
    }

    /// The model's parameters for a candidate (j_drive, c_short).
    pub fn params(&self, j_drive: f64, c_short: f64) -> RigParams {
        RigParams { j_drive, c_short, c_long: None, c_long_ratio: self.ratio, ..self.template.clone() }
    }

    fn mechanical(&self, variant: Variant, j: f64, c: f64) -> Result<MechanicalModel> {
        let p = self.params(j, c);
        Ok(match self.model {
            ModelChoice::Differential => p.open_differential(variant)?,
            ModelChoice::Smooth => p.three_mass(variant)?,
        })
    }

    /// The model's shuffle frequency, Hz (None if the model shows no shuffle mode).
    pub fn shuffle_frequency_hz(&self, variant: Variant, j: f64, c: f64) -> Option<f64> {
        if !(j > 0.0 && c > 0.0 && j.is_finite() && c.is_finite()) {
            return None;
        }
        let m = self.mechanical(variant, j, c).ok()?;
        let modes = m.modes().ok()?;
        modes.shuffle_mode(&m.layout?).map(|i| modes.frequencies_hz[i])
    }

    /// det(C(c) − ω² J(j)) = α + β j.
    fn det_affine(&self, variant: Variant, omega: f64, c: f64) -> Result<(f64, f64)> {
        let m = self.mechanical(variant, 1.0, c)?;
        let drive =
            m.layout.and_then(|l| l.drive).ok_or_else(|| IdentError::Invalid("model without a drive".into()))?;
        let k = m.stiffness_matrix();
        let mut j = m.inertia.clone();
        j[(drive, drive)] = 0.0;
        let alpha = (&k - &j * (omega * omega)).determinant();
        j[(drive, drive)] = 1.0;
        let beta = (&k - &j * (omega * omega)).determinant() - alpha;
        Ok((alpha, beta))
    }

    /// Where each measured frequency falls in the model with (j, c).
    pub fn placements(&self, meas: &[&Measurement], j: f64, c: f64) -> Result<Vec<Placement>> {
        meas.iter()
            .map(|m| {
                let model = self.mechanical(m.variant, j, c)?;
                let modes = model.modes()?;
                let k = (0..modes.frequencies_hz.len())
                    .min_by(|&a, &b| {
                        (modes.frequencies_hz[a] - m.frequency_hz)
                            .abs()
                            .total_cmp(&(modes.frequencies_hz[b] - m.frequency_hz).abs())
                    })
                    .expect("three modes");
                let kind = model.layout.map(|l| modes.kinds(&l)[k]).unwrap_or(ModeKind::Other);
                Ok(Placement { variant: m.variant, mode: k + 1, model_frequency_hz: modes.frequencies_hz[k], kind })
            })
            .collect()
    }

    /// Every real, positive (j_drive, c_short) that gives both variants their measured
    /// frequency, each marked by whether the frequencies sit on the shuffle mode.
    pub fn pair(&self, a: &Measurement, b: &Measurement, settings: &ParametriseSettings) -> Result<Vec<PairSolution>> {
        let (wa, wb) = (2.0 * PI * a.frequency_hz, 2.0 * PI * b.frequency_hz);
        let p = |c: f64| -> Result<(f64, f64, f64)> {
            let (aa, ba) = self.det_affine(a.variant, wa, c)?;
            let (ab, bb) = self.det_affine(b.variant, wb, c)?;
            Ok((aa * bb - ab * ba, aa, ba))
        };
        let (lo, hi) = (self.template.c_short * settings.c_range.0, self.template.c_short * settings.c_range.1);
        let n = settings.scan_points.max(10);
        let grid: Vec<f64> = (0..=n).map(|i| lo * (hi / lo).powf(i as f64 / n as f64)).collect();
        let values = grid.iter().map(|&c| p(c).map(|v| v.0)).collect::<Result<Vec<f64>>>()?;
        let mut out = Vec::new();
        for i in 0..n {
            if values[i] == 0.0 || values[i].signum() == values[i + 1].signum() {
                continue;
            }
            let (mut l, mut h, mut pl) = (grid[i], grid[i + 1], values[i]);
            for _ in 0..100 {
                let m = (l * h).sqrt();
                let pm = p(m)?.0;
                if pm.signum() == pl.signum() {
                    l = m;
                    pl = pm;
                } else {
                    h = m;
                }
                if h / l - 1.0 < 1e-14 {
                    break;
                }
            }
            let c = (l * h).sqrt();
            let (_, alpha, beta) = p(c)?;
            let j = -alpha / beta;
            if !(j > 0.0 && j.is_finite()) {
                continue;
            }
            let placements = self.placements(&[a, b], j, c)?;
            // both variants must really have their measured frequency at (j, c)
            if placements
                .iter()
                .zip([a, b])
                .any(|(pl, m)| (pl.model_frequency_hz - m.frequency_hz).abs() > 1e-6 * m.frequency_hz)
            {
                continue;
            }
            let shuffle = placements.iter().all(|p| p.kind == ModeKind::Shuffle);
            out.push(PairSolution { j_drive: j, c_short: c, c_long: self.ratio * c, shuffle, placements });
        }
        Ok(out)
    }

    /// Relative 95 % half-widths of j_drive and c_short, linearised at (j, c), when the shuffle
    /// frequencies of `variants` are measured with standard uncertainty `sigma_hz` each;
    /// infinite where the variants cannot separate the two.
    pub fn relative_ci95(&self, variants: &[Variant], j: f64, c: f64, sigma_hz: f64) -> [f64; 2] {
        let meas: Vec<Measurement> = variants
            .iter()
            .map(|&v| Measurement {
                variant: v,
                frequency_hz: self.shuffle_frequency_hz(v, j, c).unwrap_or(f64::NAN),
                sigma_hz,
            })
            .collect();
        if meas.iter().any(|m| !m.frequency_hz.is_finite()) {
            return [f64::INFINITY; 2];
        }
        let jac = self.jacobian(&meas, &Vector2::new(j.ln(), c.ln()));
        match (jac.transpose() * &jac).try_inverse() {
            Some(cov) if cov[(0, 0)] > 0.0 && cov[(1, 1)] > 0.0 && cov.iter().all(|v| v.is_finite()) => {
                [1.96 * cov[(0, 0)].sqrt(), 1.96 * cov[(1, 1)].sqrt()]
            }
            _ => [f64::INFINITY; 2],
        }
    }

    fn residuals(&self, meas: &[Measurement], theta: &Vector2<f64>) -> DVector<f64> {
        let (j, c) = (theta[0].exp(), theta[1].exp());
        DVector::from_iterator(
            meas.len(),
            meas.iter().map(|m| match self.shuffle_frequency_hz(m.variant, j, c) {
                Some(f) => (f - m.frequency_hz) / m.sigma_hz,
                None => 1e6,
            }),
        )
    }

    fn jacobian(&self, meas: &[Measurement], theta: &Vector2<f64>) -> DMatrix<f64> {
        central_jacobian(&|t| self.residuals(meas, &Vector2::new(t[0], t[1])), theta.as_slice())
    }

    /// Levenberg–Marquardt on (ln j, ln c) from `start`; returns (j, c, χ²).
    fn least_squares_from(&self, meas: &[Measurement], start: (f64, f64)) -> Option<(f64, f64, f64)> {
        let (theta, cost) = levenberg_marquardt(
            &|t| self.residuals(meas, &Vector2::new(t[0], t[1])),
            vec![start.0.ln(), start.1.ln()],
        )?;
        Some((theta[0].exp(), theta[1].exp(), cost))
    }

    /// The best least-squares solution over several starts.
    fn best_fit(&self, meas: &[Measurement], starts: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
        starts
            .iter()
            .filter_map(|&s| self.least_squares_from(meas, s))
            .filter(|&(_, _, chi2)| chi2 < 1e11)
            .min_by(|a, b| a.2.total_cmp(&b.2))
    }

    /// Least-squares estimate from all measurements, with linearised and Monte Carlo intervals.
    pub fn estimate(&self, meas: &[Measurement], settings: &ParametriseSettings) -> Result<Estimate> {
        let mut variants: Vec<Variant> = meas.iter().map(|m| m.variant).collect();
        variants.sort_by_key(|v| *v as u8);
        variants.dedup();
        if variants.len() < 2 {
            return Err(IdentError::Invalid(format!(
                "the parametrisation needs the frequencies of at least two variants, got {}",
                variants.len()
            )));
        }
        for m in meas {
            if !(m.frequency_hz > 0.0 && m.sigma_hz > 0.0 && m.frequency_hz.is_finite() && m.sigma_hz.is_finite()) {
                return Err(IdentError::Invalid(format!(
                    "variant {}: frequency {} Hz and uncertainty {} Hz must be positive",
                    m.variant, m.frequency_hz, m.sigma_hz
                )));
            }
        }
        // starts: every shuffle-placed pair solution, the template, and a coarse grid around it
        let mut starts = Vec::new();
        for (i, a) in meas.iter().enumerate() {
            for b in &meas[i + 1..] {
                if a.variant != b.variant {
                    starts.extend(
                        self.pair(a, b, settings)?.into_iter().filter(|s| s.shuffle).map(|s| (s.j_drive, s.c_short)),
                    );
                }
            }
        }
        let (j0, c0) = (self.template.j_drive, self.template.c_short);
        for fj in [0.1, 1.0, 10.0] {
            for fc in [0.1, 1.0, 10.0] {
                starts.push((j0 * fj, c0 * fc));
            }
        }
        let (j, c, chi2) = self.best_fit(meas, &starts).ok_or_else(|| {
            IdentError::Data("no (j_drive, c_short) puts the measured frequencies on the shuffle mode".into())
        })?;
        let dof = meas.len().saturating_sub(2);
        let theta = Vector2::new(j.ln(), c.ln());
        let jac_log = self.jacobian(meas, &theta);
        // ∂r/∂j = ∂r/∂ln j / j
        let jac = DMatrix::from_fn(meas.len(), 2, |i, k| jac_log[(i, k)] / [j, c][k]);
        let scale = if dof > 0 { (chi2 / dof as f64).max(1.0) } else { 1.0 };
        let cov = (jac.transpose() * &jac)
            .try_inverse()
            .map(|m| m * scale)
            .filter(|m| m.iter().all(|v| v.is_finite()) && m[(0, 0)] > 0.0 && m[(1, 1)] > 0.0);
        let linearised = cov.as_ref().map(|m| {
            let (sj, sc) = (m[(0, 0)].sqrt(), m[(1, 1)].sqrt());
            Confidence { j_drive_ci95: [j - 1.96 * sj, j + 1.96 * sj], c_short_ci95: [c - 1.96 * sc, c + 1.96 * sc] }
        });
        let correlation = cov.as_ref().map(|m| m[(0, 1)] / (m[(0, 0)] * m[(1, 1)]).sqrt());
        // a misfit beyond the stated uncertainties (χ²/dof > 1) widens both intervals alike:
        // the draws use σ·√(χ²/dof) (Birge ratio)
        let widened: Vec<Measurement> =
            meas.iter().map(|m| Measurement { sigma_hz: m.sigma_hz * scale.sqrt(), ..*m }).collect();
        let monte_carlo =
            (settings.monte_carlo_samples > 0).then(|| self.monte_carlo(&widened, (j, c), &starts, settings));
        let residuals_hz = meas
            .iter()
            .map(|m| {
                (m.variant, self.shuffle_frequency_hz(m.variant, j, c).map(|f| f - m.frequency_hz).unwrap_or(f64::NAN))
            })
            .collect();
        Ok(Estimate {
            model: self.model,
            j_drive: j,
            c_short: c,
            c_long: self.ratio * c,
            chi2,
            dof,
            sigma_scale: scale.sqrt(),
            residuals_hz,
            linearised,
            correlation,
            monte_carlo,
        })
    }

    /// Percentile intervals over frequencies drawn from N(f, σ²). With two measurements a draw
    /// counts as solved only if the model meets both frequencies (χ² < 1e-6); with more, every
    /// converged least-squares fit counts.
    fn monte_carlo(
        &self,
        meas: &[Measurement],
        nominal: (f64, f64),
        starts: &[(f64, f64)],
        settings: &ParametriseSettings,
    ) -> MonteCarlo {
        let mut rng = StdRng::seed_from_u64(settings.seed);
        let n = settings.monte_carlo_samples;
        let exact = meas.len() == 2;
        // all draws first, so the result does not depend on how many threads solve them
        let draws: Vec<Vec<Measurement>> = (0..n)
            .map(|_| {
                meas.iter()
                    .map(|m| {
                        let z: f64 = StandardNormal.sample(&mut rng);
                        Measurement { frequency_hz: m.frequency_hz + m.sigma_hz * z, ..*m }
                    })
                    .collect()
            })
            .collect();
        let solve = |draw: &Vec<Measurement>| {
            self.least_squares_from(draw, nominal).filter(|f| !exact || f.2 < 1e-6).or_else(|| {
                // the nominal start can miss a solution that moved; try the others
                self.best_fit(draw, starts).filter(|f| !exact || f.2 < 1e-6)
            })
        };
        let threads = std::thread::available_parallelism().map(|t| t.get()).unwrap_or(1).min(8);
        let chunk = n.div_ceil(threads).max(1);
        let fits: Vec<Option<(f64, f64, f64)>> = std::thread::scope(|scope| {
            let handles: Vec<_> =
                draws.chunks(chunk).map(|c| scope.spawn(move || c.iter().map(solve).collect::<Vec<_>>())).collect();
            handles.into_iter().flat_map(|h| h.join().expect("a Monte Carlo worker panicked")).collect()
        });
        let (mut js, mut cs): (Vec<f64>, Vec<f64>) = fits.into_iter().flatten().map(|(j, c, _)| (j, c)).unzip();
        let solved = js.len();
        let confidence = (solved >= 20)
            .then(|| Confidence { j_drive_ci95: percentiles(&mut js), c_short_ci95: percentiles(&mut cs) });
        MonteCarlo { samples: n, failed_fraction: 1.0 - solved as f64 / n.max(1) as f64, confidence }
    }
}

/// An extension of the open differential for variant sets it cannot explain (χ²/dof ≫ 1): the
/// ideal differential ties the four variants' shuffle frequencies together, so a misfit of
/// several σ is structure the model lacks, not noise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Extension {
    /// The side gears' inertia J_d2 = J_d3 (eq. (28); section 2.4 drops it): the two side
    /// shafts are then not exactly in series, and V3 and V4 no longer mirror each other.
    SideGears,
    /// c_long/c_short free instead of the declared ratio: the two sides differ by more than
    /// their shaft lengths say.
    Asymmetry,
}

impl Extension {
    /// Both, in the order they are tried.
    pub const ALL: [Extension; 2] = [Extension::SideGears, Extension::Asymmetry];

    /// The name of its parameter, with unit.
    pub fn parameter(self) -> &'static str {
        match self {
            Extension::SideGears => "j_side_gear_kg_m2",
            Extension::Asymmetry => "c_long_over_c_short",
        }
    }
}

/// χ²/dof above which the extensions are fitted: the declared model misses the variants by
/// more than their uncertainties can explain (χ²/dof = 3 with 2 dof: p ≈ 0.05).
pub const EXTEND_ABOVE_CHI2_PER_DOF: f64 = 3.0;
/// The 95 % quantile of χ² with `dof` degrees of freedom (Wilson–Hilferty's cube-root normal
/// approximation: 3.75 for 1, 5.99 for 2, 7.81 for 3; within 3 % of the exact quantile from one
/// degree of freedom up): a model whose χ² is below it is consistent with the measurements.
pub fn chi2_95(dof: usize) -> f64 {
    if dof == 0 {
        return 0.0;
    }
    let k = dof as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + 1.644_853_6 * a.sqrt()).powi(3)
}

/// An extension explains the variants when it lowers χ² by more than this: the 95 % quantile
/// of χ² with one degree of freedom (the one parameter it adds).
pub const EXTENSION_DELTA_CHI2: f64 = 3.84;

/// The fit of an extended model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExtendedEstimate {
    /// The extension.
    pub extension: Extension,
    /// Drive inertia J_drive of eq. (28) (the side gears beside it), kg m².
    #[serde(rename = "j_drive_kgm2")]
    pub j_drive: f64,
    /// Short side-shaft stiffness, Nm/rad.
    #[serde(rename = "c_short_Nm_per_rad")]
    pub c_short: f64,
    /// Long side-shaft stiffness, Nm/rad.
    #[serde(rename = "c_long_Nm_per_rad")]
    pub c_long: f64,
    /// The extension's parameter ([`Extension::parameter`]).
    pub value: f64,
    /// Σ ((f_model − f_meas)/σ)².
    pub chi2: f64,
    /// Degrees of freedom, measurements − 3.
    pub dof: usize,
    /// √max(1, χ²/dof) (1 with no degree of freedom).
    pub sigma_scale: f64,
    /// Linearised 95 % intervals of j_drive, c_short and the extension's parameter (null when
    /// the three are not separable at the estimate).
    #[serde(rename = "j_drive_ci95_kgm2")]
    pub j_drive_ci95: Option<[f64; 2]>,
    /// Nm/rad.
    #[serde(rename = "c_short_ci95_Nm_per_rad")]
    pub c_short_ci95: Option<[f64; 2]>,
    /// In the parameter's unit.
    pub value_ci95: Option<[f64; 2]>,
    /// Model − measured shuffle frequency per variant, Hz.
    #[serde(rename = "residuals_hz")]
    pub residuals_hz: Vec<(Variant, f64)>,
}

impl Parametrisation {
    /// The shuffle frequency of the model with `extension` at `value`, Hz.
    pub fn extended_shuffle_hz(
        &self,
        variant: Variant,
        j: f64,
        c: f64,
        extension: Extension,
        value: f64,
    ) -> Option<f64> {
        if !(j > 0.0 && c > 0.0 && value > 0.0 && j.is_finite() && c.is_finite() && value.is_finite()) {
            return None;
        }
        let m = match extension {
            Extension::SideGears => self.params(j, c).open_differential_with_side_gears(variant, value).ok()?,
            Extension::Asymmetry => {
                RigParams { c_long_ratio: value, ..self.params(j, c) }.open_differential(variant).ok()?
            }
        };
        let modes = m.modes().ok()?;
        modes.shuffle_mode(&m.layout?).map(|i| modes.frequencies_hz[i])
    }

    fn extended_residuals(&self, meas: &[Measurement], ext: Extension, theta: &[f64]) -> DVector<f64> {
        let (j, c, v) = (theta[0].exp(), theta[1].exp(), theta[2].exp());
        DVector::from_iterator(
            meas.len(),
            meas.iter().map(|m| match self.extended_shuffle_hz(m.variant, j, c, ext, v) {
                Some(f) => (f - m.frequency_hz) / m.sigma_hz,
                None => 1e6,
            }),
        )
    }

    fn extended_jacobian(&self, meas: &[Measurement], ext: Extension, theta: &[f64]) -> DMatrix<f64> {
        central_jacobian(&|t| self.extended_residuals(meas, ext, t), theta)
    }

    /// Levenberg–Marquardt on (ln j, ln c, ln value) from `start`; (θ, χ²).
    fn extended_from(&self, meas: &[Measurement], ext: Extension, start: [f64; 3]) -> Option<(Vec<f64>, f64)> {
        levenberg_marquardt(&|t| self.extended_residuals(meas, ext, t), start.iter().map(|v| v.ln()).collect())
            .filter(|f| f.1 < 1e11)
    }

    /// The least-squares fit of the model with `extension`, from the declared model's estimate
    /// `(j, c)` and a few values of the extension's parameter, with linearised intervals
    /// (widened by √(χ²/dof) as the declared model's are). None where no start converges.
    pub fn estimate_extended(
        &self,
        meas: &[Measurement],
        extension: Extension,
        j: f64,
        c: f64,
    ) -> Option<ExtendedEstimate> {
        let values: Vec<f64> = match extension {
            // a few g m² on a drive of some 0.5 kg m²: 0.05 % to 5 % of j_drive each
            Extension::SideGears => [5e-4, 2e-3, 6e-3, 2e-2, 5e-2].iter().map(|f| f * j).collect(),
            Extension::Asymmetry => [0.7, 1.0, 1.4].iter().map(|f| f * self.ratio).collect(),
        };
        let (theta, chi2) = values
            .into_iter()
            .filter_map(|v| self.extended_from(meas, extension, [j, c, v]))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let p: Vec<f64> = theta.iter().map(|t| t.exp()).collect();
        let dof = meas.len().saturating_sub(3);
        let scale = if dof > 0 { (chi2 / dof as f64).max(1.0) } else { 1.0 };
        let jac_log = self.extended_jacobian(meas, extension, &theta);
        let jac = DMatrix::from_fn(meas.len(), 3, |i, k| jac_log[(i, k)] / p[k]);
        let cov = (jac.transpose() * &jac)
            .try_inverse()
            .map(|m| m * scale)
            .filter(|m| m.iter().all(|v| v.is_finite()) && (0..3).all(|i| m[(i, i)] > 0.0));
        let ci = |k: usize| cov.as_ref().map(|m| [p[k] - 1.96 * m[(k, k)].sqrt(), p[k] + 1.96 * m[(k, k)].sqrt()]);
        let c_long = match extension {
            Extension::SideGears => self.ratio * p[1],
            Extension::Asymmetry => p[2] * p[1],
        };
        let residuals_hz = meas
            .iter()
            .map(|m| {
                let f = self.extended_shuffle_hz(m.variant, p[0], p[1], extension, p[2]);
                (m.variant, f.map(|f| f - m.frequency_hz).unwrap_or(f64::NAN))
            })
            .collect();
        Some(ExtendedEstimate {
            extension,
            j_drive: p[0],
            c_short: p[1],
            c_long,
            value: p[2],
            chi2,
            dof,
            sigma_scale: scale.sqrt(),
            j_drive_ci95: ci(0),
            c_short_ci95: ci(1),
            value_ci95: ci(2),
            residuals_hz,
        })
    }

    /// When the declared model's `base` fit misses the variants (χ²/dof above
    /// [`EXTEND_ABOVE_CHI2_PER_DOF`]), every [`Extension`] fitted; the one that explains them
    /// (χ² lower by more than [`EXTENSION_DELTA_CHI2`], the lowest χ²) is the first returned,
    /// `true` beside it. Empty when the declared model explains the variants, or with fewer
    /// than four measurements (an extension needs a degree of freedom left).
    pub fn explain(&self, meas: &[Measurement], base: &Estimate) -> (Vec<ExtendedEstimate>, bool) {
        if self.model != ModelChoice::Differential
            || meas.len() < 4
            || base.dof == 0
            || base.chi2 / (base.dof as f64) <= EXTEND_ABOVE_CHI2_PER_DOF
        {
            return (Vec::new(), false);
        }
        let mut fits: Vec<ExtendedEstimate> = Extension::ALL
            .iter()
            .filter_map(|&e| self.estimate_extended(meas, e, base.j_drive, base.c_short))
            .collect();
        fits.sort_by(|a, b| a.chi2.total_cmp(&b.chi2));
        let explains = fits.first().is_some_and(|f| f.chi2 < base.chi2 - EXTENSION_DELTA_CHI2);
        (fits, explains)
    }
}

/// Central differences (step 1e-6 in the log parameters) of the residuals at `theta`.
fn central_jacobian(residuals: &dyn Fn(&[f64]) -> DVector<f64>, theta: &[f64]) -> DMatrix<f64> {
    let h = 1e-6;
    let cols: Vec<DVector<f64>> = (0..theta.len())
        .map(|i| {
            let (mut tp, mut tm) = (theta.to_vec(), theta.to_vec());
            tp[i] += h;
            tm[i] -= h;
            (residuals(&tp) - residuals(&tm)) / (2.0 * h)
        })
        .collect();
    DMatrix::from_columns(&cols)
}

/// Levenberg–Marquardt on the log parameters `theta` (the frequencies' fits: a handful of
/// residuals, so central differences and at most 200 iterations); (θ, χ²), None where the
/// cost is not finite.
fn levenberg_marquardt(residuals: &dyn Fn(&[f64]) -> DVector<f64>, mut theta: Vec<f64>) -> Option<(Vec<f64>, f64)> {
    let p = theta.len();
    let mut r = residuals(&theta);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let jac = central_jacobian(residuals, &theta);
        let jtj = jac.transpose() * &jac;
        let g = jac.transpose() * &r;
        let mut accepted = false;
        for _ in 0..40 {
            let mut m = jtj.clone();
            for i in 0..p {
                m[(i, i)] = jtj[(i, i)] * (1.0 + lambda) + 1e-12;
            }
            let Some(step) = m.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            // keep steps moderate: at most a factor e per iteration
            let step = &step * (1.0f64).min(1.0 / step.amax().max(1e-300));
            let trial: Vec<f64> = theta.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            let rt = residuals(&trial);
            let ct = rt.norm_squared();
            if ct < cost {
                // converged when the cost stalls (relative 1e-10) or the step is below 1e-9 in
                // the log parameters — a relative change far under any uncertainty
                let small = (cost - ct) <= 1e-10 * cost.max(1e-300) || step.amax() < 1e-9;
                theta = trial;
                r = rt;
                cost = ct;
                lambda = (lambda / 3.0).max(1e-15);
                accepted = true;
                if small {
                    return Some((theta, cost));
                }
                break;
            }
            lambda *= 4.0;
        }
        if !accepted {
            break;
        }
    }
    cost.is_finite().then_some((theta, cost))
}

fn percentiles(v: &mut [f64]) -> [f64; 2] {
    v.sort_by(|a, b| a.total_cmp(b));
    let q = |p: f64| {
        let x = p * (v.len() - 1) as f64;
        let i = x.floor() as usize;
        let t = x - i as f64;
        v[i] * (1.0 - t) + v[(i + 1).min(v.len() - 1)] * t
    };
    [q(0.025), q(0.975)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use plant::paper;

    fn exact(p: &Parametrisation, v: Variant, j: f64, c: f64) -> Measurement {
        Measurement { variant: v, frequency_hz: p.shuffle_frequency_hz(v, j, c).unwrap(), sigma_hz: 0.01 }
    }

    #[test]
    fn chi2_quantiles_match_the_tables() {
        // the exact 95 % quantiles (any statistics table): 3.841, 5.991, 7.815, 18.307 (10 dof)
        for (dof, exact) in [(1, 3.841), (2, 5.991), (3, 7.815), (10, 18.307)] {
            assert!((chi2_95(dof) / exact - 1.0).abs() < 0.03, "{dof}: {}", chi2_95(dof));
        }
    }

    #[test]
    fn exact_frequencies_give_back_the_parameters_in_both_models() {
        for model in [ModelChoice::Differential, ModelChoice::Smooth] {
            let p = Parametrisation::new(&paper::params(3.5, 13_000.0), model).unwrap();
            let (j, c) = (0.6, 1600.0);
            let m1 = exact(&p, Variant::V1, j, c);
            let m2 = exact(&p, Variant::V2, j, c);
            let sols = p.pair(&m1, &m2, &ParametriseSettings::default()).unwrap();
            let s = sols.iter().find(|s| s.shuffle).expect("a shuffle solution");
            assert_relative_eq!(s.j_drive, j, max_relative = 1e-8);
            assert_relative_eq!(s.c_short, c, max_relative = 1e-8);
        }
    }

    #[test]
    fn differential_pair_equation_is_linear_in_one_over_c() {
        // In the differential model 1/c_s = (1 + 1/r)/c + m/c_Δ (m springs mounted), so a
        // V1/V2 pair has one solution: 1/c = 2 ω2² / (c_Δ (1 + 1/r)(ω1² − ω2²)) when the load
        // inertias do not change.
        let mut t = paper::params(3.5, 13_000.0);
        t.j_m2_delta = None;
        t.j_m3_delta = None;
        let p = Parametrisation::new(&t, ModelChoice::Differential).unwrap();
        let (f1, f2) = (12.56, 12.44);
        let m1 = Measurement { variant: Variant::V1, frequency_hz: f1, sigma_hz: 0.01 };
        let m2 = Measurement { variant: Variant::V2, frequency_hz: f2, sigma_hz: 0.01 };
        let sols = p.pair(&m1, &m2, &ParametriseSettings::default()).unwrap();
        assert_eq!(sols.len(), 1);
        let r = 7.0 / 9.0;
        let c = 64_330.0 * (1.0 + 1.0 / r) * (f1 * f1 - f2 * f2) / (2.0 * f2 * f2);
        assert_relative_eq!(sols[0].c_short, c, max_relative = 1e-9);
    }
}
