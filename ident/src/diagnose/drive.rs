//! Diagnosis of any drivetrain (`drive_test`): the declared [`DriveModel`] simulated with the
//! recorded inputs, its residual over every measured output, and the vocabulary applied at
//! every element where it can act — Coulomb friction at each body, backlash in each coupling, a
//! dead time and an actuator lag at each input, the damping re-fitted, or nothing (`none`: the
//! inertias and stiffnesses re-fitted). Each effect says where a record can show it and how its
//! size is searched (`plant::drive::Search`), so an effect added to the vocabulary is searched
//! for without a change here. Each candidate re-fits the declared inertias and
//! stiffnesses beside its own parameters; the choice is by the information criterion, as for
//! the torsional sweep.
//!
//! Outputs are compared as measured (positions as positions), each normalised by its own
//! spread, offsets and slow drift removed by the same zero-phase high-pass on measurement and
//! model: nothing assumes a sweep.

use std::collections::BTreeMap;

use plant::drive::{Dimension, DriveModel, Effect, Element, Limit, Scale, Shows, SizeContext};
use plant::{Domain, Quantity};
use serde::Serialize;

use super::torsional::{FoundEffect, WHITE_RESIDUAL_LAG1};
use super::verdict::{declared_moved, DeclaredSettings, PlaceSettings, Refitted};
use super::{
    bic, effective_count, lag1_autocorrelation, lm, rms, CandidateScore, HeldOut, FRICTION_SMOOTHING_FRACTION,
    LM_REL_TOL,
};
use crate::error::{IdentError, Result};
use crate::signal::{filtfilt_high_pass_in_place, filtfilt_high_pass_pair};

/// Lowest high-pass corner, Hz.
pub const HIGH_PASS_MIN_HZ: f64 = 0.02;

/// Levenberg–Marquardt iterations of the screen (an effect's own 1–2 parameters, the declared
/// inertias and stiffnesses held).
pub const SCREEN_ITERATIONS: usize = 8;

/// The longest step of every fit of the drive engine, in the parameters' logarithms (a factor e
/// on one parameter): its trust region ([`lm::Fit::within`]). The declared model's re-fit
/// left its minimum's basin without it (`scripts/refit_check_lines.py`, seeds 2 and 28).
pub const TRUST_RADIUS: f64 = 1.0;

/// Effects the screen passes on to the full re-fit (with the inertias and stiffnesses), beside
/// `none` and `damping`.
pub const SCREEN_KEEP: usize = 2;
/// Refinements of a one-parameter profile around its best point ([`refine_profile`]).
pub const PROFILE_LEVELS: usize = 3;
/// Points on each side of the best point at each refinement.
pub const PROFILE_POINTS: usize = 4;

/// Refines a one-parameter profile: around the best point (ln of the parameter, its cost), the
/// cost at ±1…±[`PROFILE_POINTS`] steps of a quarter of the last grid's step, the best kept,
/// [`PROFILE_LEVELS`] times (the final step 1/64 of the coarse one: with a play's 10 % steps,
/// 0.15 % of the play).
fn refine_profile(start: (Vec<f64>, f64), step: f64, cost_of: &dyn Fn(&Vec<f64>) -> f64) -> (Vec<f64>, f64) {
    let (mut best, mut step) = (start, step);
    for _ in 0..PROFILE_LEVELS {
        step /= PROFILE_POINTS as f64;
        let centre = best.0[0];
        for k in (1..=PROFILE_POINTS).flat_map(|k| [k as f64, -(k as f64)]) {
            let s = vec![centre + k * step];
            let cost = cost_of(&s);
            if cost < best.1 {
                best = (s, cost);
            }
        }
    }
    best
}

/// A candidate's score, its model, the lag-1 autocorrelation of its residual, the candidate,
/// its parameters, and whether its inertias and stiffnesses were fitted (or held at their
/// re-fit) rather than held at the declared values.
type Scored = (CandidateScore, DriveModel, f64, Candidate, Vec<f64>, bool);

/// Whether `challenger` beats the `incumbent` clearly ([`super::clearly_beats`]), `reference`
/// the model it adds to: the re-fitted declared model for a single effect, the single effect
/// for a pair. Where the models are scored by their one-step-ahead prediction (`predicted`), the
/// error need only be lower, not 10 % lower: a prediction restarts from every measurement, so
/// most of a near-right model's error is the measurement noise, which no effect removes (a play
/// beside a friction took 8 % of it, with an information criterion 13 better). The strong
/// evidence by the information criterion stays; the 10 % guards the simulation's error, which a
/// model's form accumulates over the record, against effects that only bend it.
fn clearly_beats(
    challenger: &CandidateScore,
    incumbent: &CandidateScore,
    reference: &CandidateScore,
    predicted: bool,
) -> bool {
    super::clearly_beats_with(
        challenger.score,
        challenger.error_after,
        incumbent.score,
        (reference.score, reference.error_after),
        if predicted { 1.0 } else { super::CLEARLY_LESS_ERROR },
    )
}

/// Whether candidate `c` is effect `e` alone: of its kind at its place (a compliance's profiled
/// motor share and damping aside).
fn is_alone(c: Candidate, e: Effect) -> bool {
    matches!(c, Candidate::Effect(a) if a.name() == e.name() && a.at() == e.at())
}

/// The best-scoring entry of `scored` that is effect `e` alone (`plausible`: among those whose
/// mechanics moved only where the effect may move them). A profiled compliance is entered beside
/// its screen at the search's share and damping: the effect alone is its best fit, not the first
/// one found.
fn best_alone(scored: &[Scored], e: Effect, plausible: bool) -> Option<usize> {
    (0..scored.len())
        .filter(|&i| is_alone(scored[i].3, e) && !(plausible && scored[i].0.implausible))
        .min_by(|&a, &b| scored[a].0.score.total_cmp(&scored[b].0.score))
}

/// Whether the pair `first` + `second` in `m0` is stepped whole (`plant::Dynamics::has_exact_steps`):
/// the structure decides, not the sizes (every parameter at 1). Two nonlinear effects without
/// whole steps take RK4's fine steps throughout: minutes per record.
fn stepped_whole(m0: &DriveModel, first: Effect, second: Effect) -> bool {
    if !(first.is_nonlinear() && second.is_nonlinear()) {
        return true;
    }
    let mut m = m0.clone();
    for mut e in [first, second] {
        e.set_values(&vec![1.0; e.values().len()]);
        m.effects.push(e);
    }
    plant::Dynamics::new(&m).is_ok_and(|d| d.has_exact_steps())
}

/// Times an answer kept from the screen is re-fitted with everything and chosen again (each
/// round may bring up another candidate only screened).
const ANSWER_REFITS: usize = 2;

/// The motor shares at which a compliance of the answer is re-fitted ([`ShareProfile`]): the
/// search holds the share at one half (one size per effect), and a share of 0.3 against 0.5
/// moves the reduced inertia of the split, s(1 − s)·J, by 16 % — and the fitted stiffness with it.
pub const COMPLIANCE_SHARES: [f64; 9] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];

/// The information-criterion rise (n_eff · ln(cost/cost_best)) within which a share fits as well
/// as the best: the 95 % point of χ² with one degree of freedom, the profile-likelihood interval.
pub const PROFILE_CHI2_95: f64 = 3.84;

/// The damping ratios of a compliance's own mode (its spring on the two parts' reduced inertia
/// s(1 − s)·J) at which a compliance of the answer is re-fitted before its share is profiled
/// ([`ShareProfile`]): a machine's internal spring (a rotor's shaft, a rubber element) is damped
/// at about 0.5–8 % of critical, which the body's stiffness-proportional damping need not match.
pub const COMPLIANCE_DAMPING_RATIOS: [f64; 5] = [0.005, 0.01, 0.02, 0.04, 0.08];

/// A compliance's damping and motor share profiled over [`COMPLIANCE_DAMPING_RATIOS`] and
/// [`COMPLIANCE_SHARES`]: what the answer's fold fits (which hold them) cannot say.
#[derive(Debug, Clone, PartialEq)]
struct ShareProfile {
    /// The body of the compliance.
    body: usize,
    /// The report's key of the share.
    share_key: String,
    /// The shares between the nearest the profile rejects (0 or 1 where none is rejected on that
    /// side): the share's interval.
    share_interval: [f64; 2],
    /// The report's key of the stiffness.
    stiffness_key: String,
    /// The stiffnesses fitted at the shares of the share's interval, its ends included.
    stiffness_range: [f64; 2],
    /// The profile in words.
    note: String,
}

/// A declared inertia or stiffness may be re-fitted within this factor of its declared value.
pub const MAX_REFIT_FACTOR: f64 = 100.0;

/// What a candidate adds to the declared model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Candidate {
    /// Nothing: the inertias and stiffnesses re-fitted.
    None,
    /// The couplings' damping and the bodies' drags re-fitted.
    Damping,
    /// An effect of the vocabulary ([`Effect::vocabulary`]) at its element, its size searched
    /// as the effect says ([`plant::drive::Search`]).
    Effect(Effect),
    /// Two effects of different kinds at once (the forward selection's second step: the best
    /// single effect, and another added to it).
    Pair(Effect, Effect),
}

impl Candidate {
    /// The vocabulary name.
    pub fn name(self) -> &'static str {
        match self {
            Candidate::None => "none",
            Candidate::Damping => "damping",
            Candidate::Effect(e) | Candidate::Pair(e, _) => e.name(),
        }
    }

    /// Its effects, in the order their sizes follow the base parameters.
    fn effects(self) -> Vec<Effect> {
        match self {
            Candidate::None | Candidate::Damping => vec![],
            Candidate::Effect(e) => vec![e],
            Candidate::Pair(a, b) => vec![a, b],
        }
    }

    /// The same candidate with its compliance's motor share `share` and damping `damping`
    /// (unchanged without one).
    fn with_compliance(self, share: f64, damping: Option<f64>) -> Candidate {
        let set = |e: Effect| match e {
            Effect::Compliance(c) => Effect::Compliance(plant::Compliance { motor_share: share, damping, ..c }),
            other => other,
        };
        match self {
            Candidate::Effect(e) => Candidate::Effect(set(e)),
            Candidate::Pair(a, b) => Candidate::Pair(set(a), set(b)),
            other => other,
        }
    }

    /// The choices a profile made for it beside its searched sizes, counted as fitted
    /// parameters by the information criterion: 2 where it holds a compliance re-fitted at a
    /// damping and motor share of the profile's grids ([`ShareProfile`]), not the search's own
    /// (the vocabulary's share, the body's proportional damping). Where the profile keeps the
    /// search's own share and damping law, the candidate is the search's and counted as such.
    fn profiled_choices(self) -> usize {
        let searched = Effect::vocabulary().into_iter().find_map(|e| match e {
            Effect::Compliance(k) => Some(k),
            _ => None,
        });
        let profiled = self.effects().into_iter().any(|e| match (e, searched) {
            (Effect::Compliance(k), Some(s)) => k.damping != s.damping || k.motor_share != s.motor_share,
            _ => false,
        });
        2 * usize::from(profiled)
    }

    /// The body of its compliance (`None`: it holds none).
    fn compliance_body(self) -> Option<usize> {
        self.effects().into_iter().find_map(|e| match e {
            Effect::Compliance(k) => Some(k.body),
            _ => None,
        })
    }
}

/// A record of a drivetrain: the declared model, the measured inputs and outputs.
#[derive(Debug, Clone, Copy)]
pub struct DriveRecord<'a> {
    /// The declared model (its effects, if any, are kept in every candidate).
    pub model: &'a DriveModel,
    /// One sampled signal per model input, N or Nm.
    pub inputs: &'a [Vec<f64>],
    /// What each measured output is.
    pub outputs: &'a [(Quantity, usize)],
    /// One sampled signal per output, SI.
    pub measured: &'a [Vec<f64>],
    /// Sample time, s.
    pub dt_s: f64,
}

/// Signals for plots and `--save-signals`: every output, high-passed as the error is.
#[derive(Debug, Clone, Default)]
pub struct DriveTraces {
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Measured outputs.
    pub measured: Vec<Vec<f64>>,
    /// The declared model's outputs.
    pub before: Vec<Vec<f64>>,
    /// The extended model's outputs.
    pub after: Vec<Vec<f64>>,
}

/// The diagnosis of a drive record.
#[derive(Debug, Clone, Serialize)]
pub struct DriveDiagnosis {
    /// The chosen effect (vocabulary name; the first of two).
    pub effect: String,
    /// Where it acts ("body load", "coupling 2", "input 1"), if at an element.
    pub at: Option<String>,
    /// Every effect found (none for `none` and `damping`), each with its own parameters.
    pub effects: Vec<FoundEffect>,
    /// Where the search was narrower than the vocabulary, in words.
    pub search_notes: Vec<String>,
    /// Its parameters and the re-fitted declared ones, SI, keys with units.
    pub parameters: BTreeMap<String, f64>,
    /// 95 % intervals of `parameters` over the held-out folds ([`super::jackknife_interval`]
    /// of the answer fitted without each fold).
    pub intervals: BTreeMap<String, [f64; 2]>,
    /// The answer on data its fit did not see ([`HeldOutSettings`]).
    pub held_out: HeldOut,
    /// Why the answer is no finding although it fits the record: its effect does not predict
    /// the held-out folds better than the re-fitted declared model — or the record does not determine a
    /// size of it ([`super::sizes_not_determined`]; `None`: it does, and it determines them).
    pub unsupported: Option<String>,
    /// The keys of `parameters` the record does not determine ([`super::not_determined`];
    /// each effect's are in `effects`): reported, never a finding.
    pub not_determined: Vec<String>,
    /// Why the answer is no finding: the same effects elsewhere, or other effects, explain the
    /// record about as well ([`super::verdict::undetermined`]; `None`: the record tells what and
    /// where).
    pub undetermined: Option<String>,
    /// Normalised error of the declared model (1 = no better than predicting nothing).
    pub error_before: f64,
    /// Normalised error of the extended model.
    pub error_after: f64,
    /// Every candidate, best score first.
    pub candidates: Vec<CandidateScore>,
    /// The best model still leaves a structured (non-white) residual.
    pub structured_residual: bool,
    /// How the answer's re-fit moved the declared inertias or stiffnesses beyond what its effect
    /// explains ([`super::verdict::declared_moved`]; only `none`'s re-fit is free to).
    pub moved_declared: Vec<String>,
    /// The declared inertias and stiffnesses an effect's re-fit left at the edge of the factor
    /// they are trusted to ([`super::verdict::declared_at_tolerance`]).
    pub at_tolerance: Vec<String>,
    /// Why the answer is no finding although it fits: the declared model (`none`) fits only
    /// with its mechanics moved beyond what it may (`None` otherwise).
    pub distorted: Option<String>,
    /// Corner of the high-pass that removes offsets and drift, Hz.
    pub high_pass_hz: f64,
    /// The models were scored by their one-step-ahead prediction (`plant::predictor`), not by
    /// their simulation over the whole record ([`diagnose`]): the errors are the prediction's.
    pub scored_by_prediction: bool,
    /// The extended model.
    pub model: DriveModel,
    /// The answer in one word ([`super::verdict::judge`]: its parameters against the record's
    /// bounds, beside `distorted`, `unsupported` and `undetermined`).
    pub verdict: super::verdict::Verdict,
    /// Why the verdict is what it is (a *not explained* always has a reason).
    pub verdict_reasons: Vec<String>,
    /// What a reader needs beside the numbers, in words.
    pub notes: Vec<String>,
    /// Signals for plots.
    #[serde(skip)]
    pub traces: DriveTraces,
}

impl DriveDiagnosis {
    /// What a reader needs beside the numbers: the fit's notes
    /// ([`super::verdict::fit_notes`]), how the answer's re-fit moved the declared mechanics,
    /// where the search was narrower than the vocabulary, and how a found friction is smoothed.
    fn notes_in_words(&self) -> Vec<String> {
        let refitted = "the declared inertias and stiffnesses";
        let mut notes = super::verdict::fit_notes(&self.effect, refitted, self.structured_residual, self.error_after);
        if !self.moved_declared.is_empty() {
            notes.push(format!("the answer's re-fit moved the declared mechanics: {}", self.moved_declared.join("; ")));
        }
        if !self.at_tolerance.is_empty() {
            notes.push(format!(
                "the answer's re-fit kept the declared mechanics within their tolerance and ended at its edge: {}",
                self.at_tolerance.join("; ")
            ));
        }
        notes.extend(self.search_notes.iter().cloned());
        for e in &self.model.effects {
            if let Effect::CoulombFriction(plant::CoulombFriction { smoothing_speed, .. }) = e {
                notes.push(format!(
                    "Coulomb friction is smoothed as F_c·v/√(v² + v_s²) with v_s = {smoothing_speed:.3e} (1 % of the body's RMS speed in the declared model, or wider where the friction would be faster than the mechanics)"
                ));
            }
        }
        notes
    }

    /// The verdict on `rec`: the answer's parameters against the record's bounds — its largest
    /// input force through the gear stages at most (the product of the ratios above 1 along the
    /// line), its largest RMS measured speed (none measured: not judged), its length and sample
    /// time; [`super::verdict::BoundSettings`]' defaults — beside `distorted`, `unsupported` and
    /// `undetermined`.
    fn judged(&self, rec: &DriveRecord) -> (super::verdict::Verdict, Vec<String>) {
        let gearing: f64 = rec.model.line.couplings.iter().map(|c| c.ratio.abs().max(1.0)).product();
        let rms_speed = rec
            .outputs
            .iter()
            .zip(rec.measured)
            .filter(|((q, _), _)| *q == Quantity::Speed)
            .map(|(_, y)| rms(y))
            .fold(f64::NAN, f64::max);
        let scales = super::verdict::RecordScales {
            max_force: gearing * rec.inputs.iter().flatten().fold(0.0, |a: f64, v| a.max(v.abs())),
            rms_speed: if rms_speed.is_nan() { f64::INFINITY } else { rms_speed },
            duration_s: rec.inputs[0].len() as f64 * rec.dt_s,
            sample_time_s: rec.dt_s,
        };
        let settings = super::verdict::BoundSettings::default();
        let beyond = self.dampings_beyond_critical(&settings);
        super::verdict::judge(
            &self.effect,
            self.structured_residual,
            std::iter::once(&self.parameters),
            &scales,
            self.distorted.iter().chain(&self.unsupported).chain(&self.undetermined).chain(&beyond),
            &settings,
        )
    }

    /// The re-fitted couplings' dampings at or beyond their bound
    /// ([`super::verdict::BoundSettings::damping_ratio_max`] of the coupling's own critical
    /// damping, [`critical_damping`], in the answer's model), each as a sentence.
    fn dampings_beyond_critical(&self, s: &super::verdict::BoundSettings) -> Vec<String> {
        let rotational = self.model.line.domain == Domain::Rotational;
        (0..self.model.line.couplings.len())
            .filter_map(|i| {
                let key = damping_key(i, rotational);
                let d = *self.parameters.get(&key)?;
                super::verdict::damping_beyond_critical(&key, d, critical_damping(&self.model, i), s)
            })
            .collect()
    }
}

struct Problem<'a> {
    rec: DriveRecord<'a>,
    measured: Vec<Vec<f64>>,
    /// 1 / (‖measured_i‖ √channels) per output.
    weights: Vec<f64>,
    high_pass_hz: f64,
    initial_speed: f64,
    /// Reference scales of the extras: drag and damping where declared zero; per body the
    /// input force reflected to it and a friction's smoothing speed; per coupling its RMS
    /// elastic twist ([`Scale`]).
    drag_ref: Vec<f64>,
    damping_ref: Vec<f64>,
    body_force: Vec<f64>,
    smoothing: Vec<f64>,
    twist_rms: Vec<f64>,
    /// Fastest rate of the declared model's linear part, 1/s.
    rate: f64,
    /// Where the models are scored by their one-step-ahead prediction, the noise its gain is
    /// built for ([`diagnose`], [`record_noise`]); `None`: by their simulation over the whole
    /// record.
    predictor: Option<plant::predictor::Noise>,
}

/// The noise of `rec`'s signals as a drive model's one-step-ahead predictor needs it
/// (`plant::predictor`), estimated from the record ([`crate::signal::noise_sd`]): each input's
/// and each output's, and a torque on every body as large as the largest input's noise (what
/// the model may lack there).
fn record_noise(rec: &DriveRecord) -> plant::predictor::Noise {
    let inputs_sd: Vec<f64> = rec.inputs.iter().map(|u| crate::signal::noise_sd(u)).collect();
    let disturbance_sd = inputs_sd.iter().copied().fold(0.0, f64::max);
    // an output without measurable noise (a clean synthetic record) is trusted to a millionth
    // of its own size: the Riccati equation needs a positive one
    let outputs_sd = rec
        .measured
        .iter()
        .map(|y| {
            let rms = (y.iter().map(|v| v * v).sum::<f64>() / y.len().max(1) as f64).sqrt();
            crate::signal::noise_sd(y).max(1e-6 * rms).max(f64::MIN_POSITIVE)
        })
        .collect();
    plant::predictor::Noise { inputs_sd, disturbance_sd, outputs_sd }
}

impl Problem<'_> {
    fn nbase(&self) -> usize {
        self.rec.model.line.bodies.len() + self.rec.model.line.couplings.len()
    }

    /// The model of candidate `c` at parameters `x` (base scales in log, then the extras).
    fn build(&self, c: Candidate, x: &[f64]) -> Option<DriveModel> {
        let limit = MAX_REFIT_FACTOR.ln();
        let n = self.rec.model.line.bodies.len();
        // the base scales, then one value per extra: a fit of another candidate's parameters
        // (a failed screen's, without its size) builds no model
        let own = match c {
            Candidate::None => 0,
            Candidate::Damping => self.nbase(),
            Candidate::Effect(_) | Candidate::Pair(..) => c.effects().len(),
        };
        if x.len() != self.nbase() + own {
            return None;
        }
        if x[..self.nbase()].iter().any(|v| v.abs() > limit) || x.iter().any(|v| !v.is_finite() || v.abs() > 40.0) {
            return None;
        }
        let mut m = self.rec.model.clone();
        for (b, s) in m.line.bodies.iter_mut().zip(&x[..n]) {
            b.inertia *= s.exp();
        }
        for (c, s) in m.line.couplings.iter_mut().zip(&x[n..]) {
            c.stiffness *= s.exp();
        }
        let extra = &x[self.nbase()..];
        match c {
            Candidate::None => {}
            Candidate::Damping => {
                for (i, b) in m.line.bodies.iter_mut().enumerate() {
                    b.drag = self.drag_ref[i] * extra[i].exp();
                }
                for (i, c) in m.line.couplings.iter_mut().enumerate() {
                    c.damping = self.damping_ref[i] * extra[n + i].exp();
                }
            }
            Candidate::Effect(_) | Candidate::Pair(..) => {
                for (e, &log_size) in c.effects().into_iter().zip(extra) {
                    let sized = self.sized(e, log_size, &m)?;
                    m.effects.push(sized);
                }
            }
        }
        Some(m)
    }

    /// Effect `e` of size scale·exp(`log_size`) in model `m` (its friction's smoothing from the
    /// body's inertia there); `None` beyond the size the effect allows.
    fn sized(&self, e: Effect, log_size: f64, m: &DriveModel) -> Option<Effect> {
        let scale = self.scale(e);
        let size = scale * log_size.exp();
        if size < e.search().floor * scale || self.largest_size(e).is_some_and(|limit| size > limit) {
            return None;
        }
        let body = match e.at() {
            Element::Body(b) => Some(b),
            _ => None,
        };
        let context = SizeContext {
            smoothing_speed: body.map_or(0.0, |b| self.smoothing[b]),
            inertia: body.map_or(1.0, |b| m.line.bodies[b].inertia),
            fastest_rate: self.rate,
        };
        Some(e.of_size(size, &context))
    }

    /// What effect `e`'s size is searched as a multiple of in this record ([`Scale`]).
    fn scale(&self, e: Effect) -> f64 {
        let i = e.at().index();
        match e.search().scale {
            Scale::BodyForce => self.body_force[i],
            Scale::CouplingTwist => self.twist_rms[i],
            Scale::BodyStiffness => self.rec.model.line.diagonal(i).0,
            Scale::SampleTime => self.rec.dt_s,
        }
    }

    /// The largest size of effect `e` that is still an answer in this record ([`Limit`];
    /// `None`: unbounded).
    fn largest_size(&self, e: Effect) -> Option<f64> {
        match e.search().limit {
            Limit::Unbounded => None,
            Limit::TimesScale(k) => Some(k * self.scale(e)),
            Limit::RecordShare(share) => Some(share * self.rec.dt_s * self.rec.inputs[0].len() as f64),
        }
    }

    /// Why the sizes of candidate `c`'s effects, fitted as `x` at `cost`, are no finding: the
    /// record does not bound one from above. With that size moved to the largest its effect
    /// allows ([`Problem::largest_size`]) and everything else held, the answer scores within
    /// `min_evidence` of the information criterion (`n_eff` effective residual values) of
    /// itself — a play whose coupling never closes in the fitted model fits alike at any wider
    /// play, and the record then shows only that it is wider than the twists the coupling
    /// makes. The key of each such size, and why (none: the record bounds them all).
    fn unbounded_above(
        &self,
        c: Candidate,
        x: &[f64],
        cost: f64,
        n_eff: f64,
        min_evidence: f64,
    ) -> Vec<(String, String)> {
        let nbase = self.nbase();
        let mut out = Vec::new();
        for (k, e) in c.effects().into_iter().enumerate() {
            let Some(limit) = self.largest_size(e) else { continue };
            let Some(&log_size) = x.get(nbase + k) else { continue };
            let mut at_limit = x.to_vec();
            // just inside the limit (`sized` refuses beyond it)
            at_limit[nbase + k] = (limit / self.scale(e)).ln() - 1e-9;
            let cost_at_limit = self.cost(c, &at_limit);
            let evidence = n_eff * (cost_at_limit / cost).ln();
            if evidence.is_nan() || evidence < min_evidence {
                let m = &self.rec.model;
                let key = e.parameters(m).first().map_or_else(String::new, |p| p.0.clone());
                let why = format!(
                    "the record does not bound {key} = {:.4e} of the {} {} from above: at {limit:.4e}, the largest the effect allows, the answer errs {:.4} against {:.4} (information criterion {evidence:.1} apart, less than the {min_evidence} that names a finding), so the record shows only a lower bound: no finding",
                    self.scale(e) * log_size.exp(),
                    e.name(),
                    e.at().phrase(m),
                    cost_at_limit.sqrt(),
                    cost.sqrt(),
                );
                out.push((key, why));
            }
        }
        out
    }

    /// Why effects of candidate `c` in its fitted model `m` are no finding as a constant force
    /// ([`plant::drive::Search::offset_where_one_way`], a friction): one at a body that turns
    /// one way throughout the record — as measured where the record measures its speed, else in
    /// `m`'s simulation. There it is a constant force against the motion. The line being linear
    /// beside it, its response is that of a force switched on where the simulation starts: a
    /// step to constant offsets of the speeds and twists, which the high-pass removes, reached
    /// through a transient that only the state the record is assumed to start in makes (a real
    /// record starts with the friction already acting). At a body an input drives it is, in
    /// addition, exactly an offset of that input's measured force (a motor held at a speed by a
    /// closed loop). The key of each such effect's size, and why (none: every such effect of
    /// the answer meets a reversal).
    fn one_way_offsets(&self, c: Candidate, m: &DriveModel) -> Vec<(String, String)> {
        // a speed's least and largest value; NaN where one is not finite, which tells nothing
        // of its sign
        let range = |y: &[f64]| {
            if y.iter().all(|v| v.is_finite()) {
                y.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
            } else {
                (f64::NAN, f64::NAN)
            }
        };
        let own = c.effects().len();
        let mut out = Vec::new();
        for e in &m.effects[m.effects.len() - own..] {
            let Element::Body(body) = e.at() else { continue };
            if !e.search().offset_where_one_way {
                continue;
            }
            let measured = self
                .rec
                .outputs
                .iter()
                .zip(self.rec.measured)
                .find(|((q, b), _)| *q == Quantity::Speed && *b == body)
                .map(|(_, y)| (range(y), "as measured"));
            let speeds = measured.or_else(|| {
                let simulated =
                    m.simulate(self.rec.inputs, self.rec.dt_s, self.initial_speed, &[(Quantity::Speed, body)]);
                simulated.ok().map(|s| (range(&s[0]), "in the answer's simulation"))
            });
            let Some(((lo, hi), source)) = speeds else { continue };
            if lo > 0.0 || hi < 0.0 {
                let Some((key, size)) = e.parameters(m).into_iter().next() else { continue };
                let unit = if m.line.domain == Domain::Rotational { "rad/s" } else { "m/s" };
                let offset = match m.inputs.iter().position(|&b| b == body) {
                    Some(input) => format!(
                        ", and an input acts on it (input {}), whose offset the record cannot tell from such a force",
                        input + 1
                    ),
                    None => String::new(),
                };
                let why = format!(
                    "{key} = {size:.4e} of the {} {} is a constant force there: its body turns one way throughout the record ({lo:.4e} to {hi:.4e} {unit}, {source}), so the record shows it only as offsets, which the high-pass removes, and through the state the simulation is assumed to start in{offset}: no finding",
                    e.name(),
                    e.at().phrase(m),
                );
                out.push((key, why));
            }
        }
        out
    }

    /// The screen of candidate `c`'s last effect's size with the parameters before it `held`:
    /// the best of its grid ([`Problem::starts`]), refined where the effect's profile is rough
    /// (a play's: each impact shifts with it), then [`SCREEN_ITERATIONS`] of LM. The whole
    /// parameter vector and its cost (`held` and its cost for a candidate without a size).
    fn screen(&self, c: Candidate, held: &[f64]) -> (Vec<f64>, f64) {
        let own = |s: &[f64]| self.residual(c, &[held, s].concat());
        let cost_of = |s: &Vec<f64>| self.cost(c, &[held, s].concat());
        let best = self
            .starts(c)
            .into_iter()
            .map(|s| {
                let cost = cost_of(&s);
                (s, cost)
            })
            .filter(|g| g.1.is_finite())
            .min_by(|p, q| p.1.total_cmp(&q.1));
        let best = match (c.effects().last(), best) {
            (Some(e), Some(start)) if e.search().rough => {
                let (lo, hi, k) = e.search().grid;
                Some(refine_profile(start, (hi / lo).ln() / (k - 1) as f64, &cost_of))
            }
            (_, best) => best,
        };
        let (s, cost) = match best {
            Some((s0, _)) if !s0.is_empty() => {
                lm::minimise(&own, &s0, lm::Fit::new(SCREEN_ITERATIONS, LM_REL_TOL).within(TRUST_RADIUS))
            }
            Some((s0, cost)) => (s0, cost),
            None => (vec![], f64::INFINITY),
        };
        ([held, &s].concat(), cost)
    }

    /// The model's outputs as the models are scored — simulated, or predicted one step ahead
    /// where [`Problem::predictor`] is set — high-passed as the measurement is, one after
    /// another in one vector (the residual is then formed in place, and a fit holds one
    /// record-sized buffer per evaluation, not two).
    fn simulate(&self, m: &DriveModel) -> Option<Vec<f64>> {
        match &self.predictor {
            None => self.simulate_open(m),
            Some(noise) => {
                let (rec, speed) = (&self.rec, self.initial_speed);
                self.high_passed(m.predict_flat(rec.inputs, rec.dt_s, speed, rec.outputs, rec.measured, noise).ok()?)
            }
        }
    }

    /// The model's outputs simulated over the whole record (`DriveModel::simulate_flat`),
    /// high-passed: the traces, and the score where no predictor is set.
    fn simulate_open(&self, m: &DriveModel) -> Option<Vec<f64>> {
        let y = m.simulate_flat(self.rec.inputs, self.rec.dt_s, self.initial_speed, self.rec.outputs).ok()?;
        self.high_passed(y)
    }

    /// `y` (outputs one after another) high-passed as the measurement is; `None` where not
    /// finite.
    fn high_passed(&self, mut y: Vec<f64>) -> Option<Vec<f64>> {
        let len = self.rec.inputs.first().map_or(0, Vec::len);
        if len == 0 {
            return None;
        }
        // two outputs at a time (the filter's recurrences interleaved)
        for pair in y.chunks_mut(2 * len) {
            match pair.len() / len {
                2 => {
                    let (a, b) = pair.split_at_mut(len);
                    filtfilt_high_pass_pair(a, b, self.rec.dt_s, self.high_pass_hz)
                }
                1 => filtfilt_high_pass_in_place(pair, self.rec.dt_s, self.high_pass_hz),
                _ => {}
            }
        }
        y.iter().all(|v| v.is_finite()).then_some(y)
    }

    /// The residual (measured − simulated, weighted per output) of the outputs `y` of
    /// [`Problem::simulate`], formed in their place.
    fn residual_of(&self, mut y: Vec<f64>) -> Vec<f64> {
        let len = self.rec.inputs.first().map_or(0, Vec::len).max(1);
        for ((s, m), w) in y.chunks_mut(len).zip(&self.measured).zip(&self.weights) {
            for (s, m) in s.iter_mut().zip(m) {
                *s = (m - *s) * w;
            }
        }
        y
    }

    fn residual(&self, c: Candidate, x: &[f64]) -> Option<Vec<f64>> {
        let m = self.build(c, x)?;
        Some(self.residual_of(self.simulate(&m)?))
    }

    /// The squared norm of [`Problem::residual`]; infinite where the model cannot be built or
    /// simulated.
    fn cost(&self, c: Candidate, x: &[f64]) -> f64 {
        self.residual(c, x).map_or(f64::INFINITY, |r| r.iter().map(|v| v * v).sum())
    }

    /// The outputs `y` of [`Problem::simulate`], one vector each (the traces).
    fn per_output(&self, y: Vec<f64>) -> Vec<Vec<f64>> {
        plant::drive::split_outputs(y, self.rec.outputs.len())
    }

    /// Starting values of the candidate's own parameters to grid over.
    fn starts(&self, c: Candidate) -> Vec<Vec<f64>> {
        let n = self.rec.model.line.bodies.len();
        let grid = |lo: f64, hi: f64, k: usize| -> Vec<Vec<f64>> {
            (0..k).map(|i| vec![lo.ln() + (hi / lo).ln() * i as f64 / (k - 1) as f64]).collect()
        };
        match c {
            Candidate::None => vec![vec![]],
            Candidate::Damping => vec![vec![0.0; n + self.rec.model.line.couplings.len()]],
            Candidate::Effect(e) | Candidate::Pair(_, e) => {
                let (lo, hi, k) = e.search().grid;
                grid(lo, hi, k)
            }
        }
    }

    /// Whether the record can show effect `e` where it acts: judged on the declared model's
    /// `motion` (every body's speed, then every coupling's force) and, where the record measures
    /// that speed or force, on the measurement too — either may show it. The declared model
    /// lacks the effect, and its motion can stay clear of where the effect acts while the real
    /// one does not (survey record 2937: a friction holds b1's measured speed about zero, which
    /// reverses; the declared model, without it, spins b1 up and never near zero, so no friction
    /// was tried there and damping stood in for it).
    fn shows(&self, e: Effect, motion: &[Vec<f64>]) -> bool {
        let n = self.rec.model.line.bodies.len();
        let measured = |q: Quantity, i: usize| {
            self.rec
                .outputs
                .iter()
                .zip(self.rec.measured)
                .filter(move |((mq, mi), _)| *mq == q && *mi == i)
                .map(|(_, y)| y)
        };
        match (e.search().shows, e.at()) {
            (Shows::SpeedNearZero, Element::Body(b)) => {
                let vs = self.smoothing[b];
                let near_zero = |v: &Vec<f64>| v.iter().any(|v| v.abs() < 10.0 * vs);
                vs > 0.0 && (near_zero(&motion[b]) || measured(Quantity::Speed, b).any(near_zero))
            }
            (Shows::ForceChangesSign, Element::Coupling(c)) => {
                let both_signs = |f: &Vec<f64>| f.iter().any(|&v| v > 0.0) && f.iter().any(|&v| v < 0.0);
                self.twist_rms[c] > 0.0
                    && (both_signs(&motion[n + c]) || measured(Quantity::CouplingForce, c).any(both_signs))
            }
            _ => true,
        }
    }

    /// The report's key of declared quantity `i` of a fit's parameters (the inertias, then the
    /// stiffnesses).
    fn base_key(&self, i: usize) -> String {
        let line = &self.rec.model.line;
        let rotational = line.domain == Domain::Rotational;
        match line.bodies.get(i) {
            Some(body) => {
                let inertia = if rotational { "inertia" } else { "mass" };
                format!("{inertia}_{}_{}", body.name.replace(' ', "_"), Dimension::Inertia.key_unit(rotational))
            }
            None => {
                let coupling = i - line.bodies.len() + 1;
                format!("stiffness_coupling{coupling}_{}", Dimension::Stiffness.key_unit(rotational))
            }
        }
    }

    /// The candidate's parameters as reported: the re-fitted inertias and stiffnesses, then
    /// its own.
    fn report(&self, c: Candidate, m: &DriveModel) -> BTreeMap<String, f64> {
        let rotational = m.line.domain == Domain::Rotational;
        let mut b = BTreeMap::new();
        let quantities = m.line.bodies.iter().map(|b| b.inertia).chain(m.line.couplings.iter().map(|c| c.stiffness));
        for (i, value) in quantities.enumerate() {
            b.insert(self.base_key(i), value);
        }
        if matches!(c, Candidate::Damping) {
            for body in &m.line.bodies {
                b.insert(drag_key(&body.name, rotational), body.drag);
            }
            for (i, c) in m.line.couplings.iter().enumerate() {
                b.insert(damping_key(i, rotational), c.damping);
            }
        }
        let own = c.effects().len();
        for e in &m.effects[m.effects.len() - own..] {
            for (k, v) in e.parameters(m) {
                b.insert(k, v);
            }
        }
        b
    }
}

/// How `fitted` moved the inertias and stiffnesses of `declared` beyond what its effect
/// explains ([`declared_moved`]): every effect of the drive vocabulary, and damping, acts beside
/// them (their `EffectModel::MOVES` is `Moves::Nothing`), so each should stay within the
/// tolerance; a candidate that moves them further is not chosen.
fn moved_declared(declared: &DriveModel, fitted: &DriveModel) -> Vec<String> {
    judge_declared(declared, fitted, declared_moved)
}

/// `rule` ([`declared_moved`], [`declared_at_tolerance`]) applied to the inertias and
/// stiffnesses of `fitted` relative to `declared`.
fn judge_declared(
    declared: &DriveModel,
    fitted: &DriveModel,
    rule: fn(&[Refitted], &DeclaredSettings) -> Vec<String>,
) -> Vec<String> {
    let (d, f) = (&declared.line, &fitted.line);
    let inertias: Vec<(String, f64)> = d
        .bodies
        .iter()
        .zip(&f.bodies)
        .map(|(a, b)| (format!("inertia of {}", a.name), b.inertia / a.inertia))
        .collect();
    let stiffnesses: Vec<(String, f64)> = d
        .couplings
        .iter()
        .zip(&f.couplings)
        .enumerate()
        .map(|(i, (a, b))| (format!("stiffness of coupling {}", i + 1), b.stiffness / a.stiffness))
        .collect();
    let refitted: Vec<Refitted> = inertias
        .iter()
        .map(|(name, ratio)| Refitted::Inertia { name, ratio: *ratio })
        .chain(stiffnesses.iter().map(|(name, ratio)| Refitted::Stiffness { name, ratio: *ratio, series_ratio: None }))
        .collect();
    rule(&refitted, &DeclaredSettings::default())
}

/// The declared model's re-fit within the tolerance (`fit`, in the box `bounds`) where it ended
/// at the box's edge: that re-fit started from the free one, which moves along what the record
/// does not determine, and the box stops such a quantity at its edge — an edge the record need
/// not ask for. The quantities at the edge are set back to their declared values and the fit
/// restarted from there, in the box; where it ends at the edge again, they are held at their
/// declared values and the rest re-fitted — and so on while a re-fit ends at the edge somewhere.
/// A re-fit replaces `fit` only where the record does not prefer the free re-fit (`free_score`)
/// strongly over it ([`super::verdict::moved_by_the_record`], the rule that judges the box
/// itself); else the record demands the edge, and the declared mechanics are distorted.
/// Returns the keys of the quantities held (none where the restart left the edge). `score`
/// scores a re-fit (its parameters and sum of squares); a held quantity is counted as fitted,
/// which asks a held re-fit for a little more.
fn hold_edges_at_declared(
    problem: &Problem,
    bounds: &[f64],
    fit: &mut Scored,
    free_score: f64,
    score: &dyn Fn(Vec<f64>, f64) -> Option<Scored>,
) -> Vec<String> {
    let within = |x: &[f64]| problem.residual(Candidate::None, x);
    let accepted =
        |h: &Scored| !super::verdict::moved_by_the_record(free_score, h.0.score, &DeclaredSettings::default());
    let refit = |start: &[f64], b: &[f64]| {
        let (x, cost) = lm::minimise(&within, start, lm::Fit::new(20, LM_REL_TOL).within(TRUST_RADIUS).boxed(b));
        score(x, cost)
    };
    let mut held_box = bounds.to_vec();
    let mut held = Vec::new();
    loop {
        let edge = on_box_edge(&fit.4, &held_box);
        if edge.is_empty() {
            break;
        }
        let mut start = fit.4.clone();
        for &i in &edge {
            start[i] = 0.0;
        }
        if let Some(restarted) =
            refit(&start, &held_box).filter(|r| accepted(r) && on_box_edge(&r.4, &held_box).is_empty())
        {
            *fit = restarted;
            break;
        }
        for &i in &edge {
            held_box[i] = 0.0;
        }
        match refit(&start, &held_box).filter(accepted) {
            Some(h) => {
                *fit = h;
                held.extend(edge);
            }
            None => break,
        }
    }
    held.iter().map(|&i| problem.base_key(i)).collect()
}

/// The indices of `x` on the edge of the box `bounds` (a bound of 0 holds its parameter, no edge).
fn on_box_edge(x: &[f64], bounds: &[f64]) -> Vec<usize> {
    (0..bounds.len()).filter(|&i| bounds[i] > 0.0 && super::verdict::at_edge(x[i].abs(), bounds[i])).collect()
}

/// The box an effect's re-fit keeps the declared inertias and stiffnesses in (the first `nbase`
/// of its `len` parameters, logarithms of their ratio to the declared values): within the
/// factor the declared values are trusted to ([`DeclaredSettings::tolerance_factor`]), as every
/// effect of the drive vocabulary and damping move none of them ([`moved_declared`]); a
/// billionth inside it, so that the ratio rebuilt from the bound is within it after rounding.
/// The declared model's re-fit (`none`) is free: where it must leave the box, the declared
/// mechanics do not describe the record (`distorted`).
fn mechanics_box(c: Candidate, nbase: usize, len: usize) -> Vec<f64> {
    if matches!(c, Candidate::None) {
        return Vec::new();
    }
    tolerance_box(nbase, len)
}

/// The box of parameters of `len` whose first `nbase` are the declared inertias and
/// stiffnesses (logarithms of their ratio to the declared values): those within the tolerance
/// factor, a billionth inside it; the rest free.
fn tolerance_box(nbase: usize, len: usize) -> Vec<f64> {
    let inside = DeclaredSettings::default().tolerance_factor.ln() * (1.0 - 1e-9);
    (0..len).map(|i| if i < nbase { inside } else { f64::INFINITY }).collect()
}

/// The report's key of body `name`'s drag.
fn drag_key(name: &str, rotational: bool) -> String {
    format!("drag_{}_{}", name.replace(' ', "_"), Dimension::Damping.key_unit(rotational))
}

/// The report's key of coupling `i`'s damping (0-based; 1-based in the key).
fn damping_key(i: usize, rotational: bool) -> String {
    format!("damping_coupling{}_{}", i + 1, Dimension::Damping.key_unit(rotational))
}

/// The critical damping of coupling `i` of `m` on its own: 2√(k·J) with J = 1/Σ e_j²/J_j, the
/// inertia its twist sees (two neighbours through a gear: seen from the load side).
fn critical_damping(m: &DriveModel, i: usize) -> f64 {
    let c = &m.line.couplings[i];
    let j = 1.0 / c.terms(i).iter().map(|&(b, e)| e * e / m.line.bodies[b].inertia).sum::<f64>();
    2.0 * (c.stiffness * j).sqrt()
}

/// Speed of body `b` per speed of body 0 (the gear stages between them).
fn gear_to(m: &DriveModel, b: usize) -> f64 {
    // the gear stages between neighbours before it (a coupling with an elongation has ratio 1)
    m.line.couplings.iter().take(b).map(|c| 1.0 / c.ratio).product()
}

/// What the search of a drive record looks for beyond its default vocabulary, with the
/// defaults.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SearchSettings {
    /// A compliance inside every body (`rigtwin diagnose --search-compliance`; default off). On
    /// the drive-line survey's compliant lines it finds the compliance at its body in 12 of 20
    /// tuning records and 9 of 20 held-out ones, where the default search explains none, but
    /// answers 9 of the held-out ones wrongly (a friction or a play beside it, the wrong body);
    /// on the survey's other records it names a compliance beside a play that the record does
    /// not hold (seed 3: its mode takes up what the play model misses). So it is not part of the
    /// default search (docs/validation.md, step 32).
    pub compliance: bool,
}

/// Diagnoses `rec`. `progress` is told each candidate's name as it finishes.
///
/// The models are scored by their simulation over the whole record. Where that leaves the
/// record *not explained*, or its answer leaves a structured residual (it explains only part of
/// the record: a poorly simulated play lets a wrong second effect win 10 % of a large error),
/// they are scored again by their one-step-ahead prediction
/// (`plant::predictor`: the simulation held to the measured outputs after each sample), and
/// an *explained* answer of that search is the answer. A simulation over the whole record
/// drifts where nothing holds the bodies together — a play that rattles about zero torque: the
/// input's noise, integrated twice, moves when the bodies strike, and the truth itself then
/// errs 0.3–0.9 where the record's noise floor is 0.001–0.004 — while the prediction restarts
/// from the measurement at every sample (docs/validation.md, steps 13 and 14). Where the
/// simulation explains the record with a white residual, or the prediction finds the same effects
/// at the same places, the simulation's answer stands: the prediction's correction takes up part
/// of what a friction does, and its friction levels were a few per cent low.
pub fn diagnose(rec: DriveRecord, progress: &(dyn Fn(&str) + Sync)) -> Result<DriveDiagnosis> {
    diagnose_with(rec, progress, &SearchSettings::default())
}

/// [`diagnose`] with the search's vocabulary widened by `settings`.
pub fn diagnose_with(
    rec: DriveRecord,
    progress: &(dyn Fn(&str) + Sync),
    settings: &SearchSettings,
) -> Result<DriveDiagnosis> {
    let simulated = diagnose_scored(rec, progress, None, settings)?;
    if simulated.verdict != super::verdict::Verdict::NotExplained && !simulated.structured_residual {
        return Ok(simulated);
    }
    // what each answer found, where: effects and places
    let found = |d: &DriveDiagnosis| -> Vec<(String, Option<String>)> {
        let mut f: Vec<_> = d.effects.iter().map(|e| (e.effect.clone(), e.at.clone())).collect();
        f.sort();
        f
    };
    match diagnose_scored(rec, progress, Some(record_noise(&rec)), settings) {
        // the same effects at the same places: the simulation's sizes stand (the prediction's
        // correction takes up part of what an effect does)
        Ok(predicted)
            if simulated.verdict == super::verdict::Verdict::Explained && found(&predicted) == found(&simulated) =>
        {
            Ok(simulated)
        }
        Ok(mut predicted) if predicted.verdict == super::verdict::Verdict::Explained => {
            let why = if simulated.verdict == super::verdict::Verdict::NotExplained {
                "no model explained the record"
            } else {
                "the best model left a structured residual"
            };
            predicted.notes.push(format!(
                "scored by the one-step-ahead prediction (the simulation held to the measured outputs after each \
                 sample): scored by their simulation over the whole record, {why} (best: {}, error {:.3})",
                simulated.effect, simulated.error_after
            ));
            Ok(predicted)
        }
        _ => Ok(simulated),
    }
}

/// [`diagnose`] with the models scored by their simulation (`predictor` `None`) or by their
/// one-step-ahead prediction with these noise levels.
fn diagnose_scored(
    rec: DriveRecord,
    progress: &(dyn Fn(&str) + Sync),
    predictor: Option<plant::predictor::Noise>,
    settings: &SearchSettings,
) -> Result<DriveDiagnosis> {
    let m0 = rec.model;
    m0.validate()?;
    let n = m0.line.bodies.len();
    let len = rec.inputs.first().map_or(0, Vec::len);
    if rec.inputs.len() != m0.inputs.len() || rec.inputs.iter().any(|u| u.len() != len) {
        return Err(IdentError::Invalid("one input signal per model input, all of one length".into()));
    }
    if rec.outputs.is_empty() || rec.outputs.len() != rec.measured.len() || rec.measured.iter().any(|y| y.len() != len)
    {
        return Err(IdentError::Invalid("one measured signal per output, as long as the inputs".into()));
    }
    if len < 200 {
        return Err(IdentError::Data(format!("a record of {len} samples is too short to diagnose (need 200)")));
    }
    let dt = rec.dt_s;
    let high_pass_hz = super::high_pass_corner_hz(len, dt, HIGH_PASS_MIN_HZ);
    let mut measured: Vec<Vec<f64>> = rec.measured.to_vec();
    let mut weights = Vec::new();
    for (i, y) in measured.iter_mut().enumerate() {
        filtfilt_high_pass_in_place(y, dt, high_pass_hz);
        let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(IdentError::Data(format!(
                "output {} does not vary above {high_pass_hz:.3} Hz: nothing to compare",
                i + 1
            )));
        }
        weights.push(1.0 / (norm * (rec.outputs.len() as f64).sqrt()));
    }
    // the first body's speed at the start, from the first measured speed or position
    let k0 = 10.min(len - 1);
    let initial_speed = rec
        .outputs
        .iter()
        .zip(rec.measured)
        .find_map(|(&(q, b), y)| match q {
            Quantity::Speed => Some(y[..k0].iter().sum::<f64>() / k0 as f64 / gear_to(m0, b)),
            Quantity::Position => Some((y[k0] - y[0]) / (k0 as f64 * dt) / gear_to(m0, b)),
            Quantity::CouplingForce => None,
        })
        .unwrap_or(0.0);

    // scales of the extras from the declared model's own motion
    let all_speeds: Vec<(Quantity, usize)> = (0..n).map(|b| (Quantity::Speed, b)).collect();
    let nc = m0.line.couplings.len();
    let all_twists: Vec<(Quantity, usize)> = (0..nc).map(|c| (Quantity::CouplingForce, c)).collect();
    let declared_motion = m0
        .simulate(rec.inputs, dt, initial_speed, &[all_speeds, all_twists].concat())
        .map_err(|e| IdentError::Data(format!("the declared model cannot be simulated: {e}")))?;
    let modes = m0.line.model()?.modes()?;
    let w_ref =
        2.0 * std::f64::consts::PI * modes.frequencies_hz.iter().copied().filter(|f| *f > 1e-3).fold(1.0, f64::max);
    let drag_ref: Vec<f64> =
        m0.line.bodies.iter().map(|b| if b.drag > 0.0 { b.drag } else { 0.01 * b.inertia * w_ref }).collect();
    let damping_ref: Vec<f64> = m0
        .line
        .couplings
        .iter()
        .enumerate()
        .map(|(i, c)| {
            if c.damping > 0.0 {
                c.damping
            } else {
                // 1 % of critical for the inertia the coupling's twist sees
                0.01 * critical_damping(m0, i)
            }
        })
        .collect();
    // friction scale: the input's RMS force reflected to the body
    let input_rms: f64 = rec.inputs.iter().zip(&m0.inputs).map(|(u, &b)| rms(u) / gear_to(m0, b)).fold(0.0, f64::max);
    let body_force: Vec<f64> = (0..n).map(|b| input_rms * gear_to(m0, b)).collect();
    let smoothing: Vec<f64> = (0..n).map(|b| FRICTION_SMOOTHING_FRACTION * rms(&declared_motion[b])).collect();
    let twist_rms: Vec<f64> = m0
        .line
        .couplings
        .iter()
        .enumerate()
        .map(|(i, c)| rms(&declared_motion[n + i]) / c.stiffness.max(1e-300))
        .collect();

    let rate = m0.fastest_linear_rate()?.max(1.0 / dt);
    let predicted = predictor.is_some();
    let problem = Problem {
        rec,
        measured,
        weights,
        high_pass_hz,
        initial_speed,
        drag_ref,
        damping_ref,
        body_force,
        smoothing,
        twist_rms,
        rate,
        predictor,
    };
    let cannot_simulate = || IdentError::Data("the declared model cannot be simulated (check its parameters)".into());
    let r0 = problem.residual_of(problem.simulate(m0).ok_or_else(cannot_simulate)?);
    let error_before = r0.iter().map(|v| v * v).sum::<f64>().sqrt();
    let nres = r0.len();
    let n_eff = effective_count(nres, lag1_autocorrelation(&r0));
    // the fits run without the declared model's signals (memory: a few record-sized buffers
    // per worker); its outputs are simulated again for the traces
    drop(r0);

    // the vocabulary at every element where it can act and the data can show it
    let mut cands = vec![Candidate::None, Candidate::Damping];
    let asked = |e: &Effect| settings.compliance || !matches!(e, Effect::Compliance(_));
    for prototype in Effect::vocabulary().into_iter().filter(asked) {
        for i in 0..prototype.at().count(m0) {
            let e = prototype.at_index(i);
            if problem.shows(e, &declared_motion) {
                cands.push(Candidate::Effect(e));
            }
        }
    }
    drop(declared_motion);

    // Three stages. The declared model re-fitted (`none`: its inertias and stiffnesses to the
    // least-squares minimum). Screen: every effect's own parameters fitted with the inertias and
    // stiffnesses held (1–2 parameters, few simulations each) — held at their re-fitted values
    // where that re-fit is plausible (a declared model a few per cent off would otherwise hide
    // every effect behind its own misfit), else at the declared ones. Then the re-fit of
    // everything (base + own) for `damping` and the SCREEN_KEEP effects the screen ranks best;
    // the others keep their screened fit.
    let nbase = problem.nbase();
    let label = |c: Candidate| match c {
        Candidate::None | Candidate::Damping => c.name().to_string(),
        _ => c.effects().iter().map(|e| format!("{} {}", e.name(), e.at().phrase(m0))).collect::<Vec<_>>().join(" + "),
    };
    let declared_refit = {
        let f = |x: &[f64]| problem.residual(Candidate::None, x);
        let zero = vec![0.0; nbase];
        let (x, cost) = if m0.effects.is_empty() {
            let fit = lm::Fit::new(super::torsional::DECLARED_REFIT_ITERATIONS, LM_REL_TOL).smooth(true).central();
            lm::minimise(&f, &zero, fit.within(TRUST_RADIUS))
        } else {
            lm::minimise(&f, &zero, lm::Fit::new(20, LM_REL_TOL).within(TRUST_RADIUS))
        };
        progress(&label(Candidate::None));
        (x, cost)
    };
    let base_refitted = problem
        .build(Candidate::None, &declared_refit.0)
        .is_some_and(|refit| declared_refit.1.is_finite() && moved_declared(m0, &refit).is_empty());
    let held_base = if base_refitted { declared_refit.0.clone() } else { vec![0.0; nbase] };
    // `none` is screened as the re-fit above
    let screen_or_refit = |i: usize| match cands[i] {
        Candidate::None => (i, declared_refit.0.clone(), declared_refit.1),
        c => {
            let (x, cost) = problem.screen(c, &held_base);
            (i, x, cost)
        }
    };
    let screened: Vec<(usize, Vec<f64>, f64)> = super::on_two_workers(cands.len(), &screen_or_refit);
    let mut ranked: Vec<&(usize, Vec<f64>, f64)> =
        screened.iter().filter(|s| !matches!(cands[s.0], Candidate::None | Candidate::Damping)).collect();
    ranked.sort_by(|a, b| a.2.total_cmp(&b.2));
    // where the declared model's re-fit is implausible the screens held the declared mechanics,
    // whose few per cent of error the screens' costs then mostly measure, alike for every
    // place of one effect but not across effects: the best place of each effect is re-fitted
    let mut refit: Vec<usize> = screened
        .iter()
        .filter(|s| matches!(cands[s.0], Candidate::Damping))
        .chain(ranked.iter().take(SCREEN_KEEP).copied())
        .map(|s| s.0)
        .collect();
    if !base_refitted {
        for s in &ranked {
            let name = cands[s.0].name();
            if !refit.iter().any(|&i| cands[i].name() == name) {
                refit.push(s.0);
            }
        }
    }
    // the re-fit of candidate `c` from `x0`, its first `held` parameters held
    // (an effect's re-fit keeps the declared mechanics within what the effect may move of them,
    // `mechanics_box`; the declared model's own re-fit above is free, and judged as the answer)
    let fit_from = |c: Candidate, x0: &[f64], held: usize| {
        let free = |s: &[f64]| problem.residual(c, &[&x0[..held], s].concat());
        let bounds = mechanics_box(c, nbase, x0.len());
        let fit = lm::Fit::new(20, LM_REL_TOL).within(TRUST_RADIUS);
        let (s, cost) = lm::minimise(&free, &x0[held..], fit.boxed(&bounds[held.min(bounds.len())..]));
        progress(&label(c));
        ([&x0[..held], &s[..]].concat(), cost)
    };
    let fit_all = |c: Candidate, x0: &[f64]| fit_from(c, x0, 0);
    // the re-fit starts from the better of the screen and, where the screen held the declared
    // inertias and stiffnesses, the same size beside the declared model's re-fit moved into the
    // box the re-fit keeps them in (a play's or a friction's cost is too rough for the re-fit
    // to walk from one to the other; compared where the re-fit would start, not outside it)
    let fit_one = |k: usize| -> (usize, Vec<f64>, f64) {
        let i = refit[k];
        let (_, x_screen, cost_screen) = screened.iter().find(|s| s.0 == i).expect("screened");
        let mut start = x_screen.clone();
        let bounds = mechanics_box(cands[i], nbase, x_screen.len());
        if !base_refitted && matches!(cands[i], Candidate::Effect(_)) {
            let mut beside: Vec<f64> = [&declared_refit.0[..], &x_screen[nbase..]].concat();
            lm::into_box(&mut beside, &bounds);
            let cost = problem.cost(cands[i], &beside);
            if cost < *cost_screen {
                start = beside;
            }
        }
        let (x, cost) = fit_all(cands[i], &start);
        // a re-fit started beside the declared model's re-fit that ends on the box's edge may
        // have stayed in that re-fit's basin, which the missing effect bent there (a lag's
        // time constant standing in for a dead time along a ridge of an inertia and a
        // stiffness: validation.md, step 35): the re-fit from the screen, at the declared
        // mechanics, too, and the better kept
        if start != *x_screen && !on_box_edge(&x, &bounds).is_empty() {
            let (x_declared, cost_declared) = fit_all(cands[i], x_screen);
            if cost_declared < cost {
                return (i, x_declared, cost_declared);
            }
        }
        (i, x, cost)
    };
    // the re-fits longest first: a nonlinear effect's simulations take many short steps (a
    // friction's re-fit on the real-sized line was half of the whole diagnosis), then by their
    // parameters (a Jacobian column each)
    let longest_first = |jobs: &[usize]| -> Vec<usize> {
        let mut order: Vec<usize> = (0..jobs.len()).collect();
        let cost = |k: &usize| {
            let c = cands[jobs[*k]];
            let nonlinear = c.effects().iter().any(|e| e.is_nonlinear());
            let parameters = screened.iter().find(|s| s.0 == jobs[*k]).map_or(0, |s| s.1.len());
            (std::cmp::Reverse(nonlinear), std::cmp::Reverse(parameters))
        };
        order.sort_by_key(cost);
        order
    };
    // (candidate, parameters, cost, whether the inertias and stiffnesses were fitted or held at
    // their re-fit — else at the declared values)
    let mut fits: Vec<(usize, Vec<f64>, f64, bool)> = super::on_two_workers_in_order(&longest_first(&refit), &fit_one)
        .into_iter()
        .map(|(i, x, c)| (i, x, c, true))
        .collect();
    for s in &screened {
        if !refit.contains(&s.0) {
            let base_fitted = matches!(cands[s.0], Candidate::None) || base_refitted;
            fits.push((s.0, s.1.clone(), s.2, base_fitted));
        }
    }

    // (score, model, lag-1 autocorrelation of its residual, candidate, parameters, base fitted);
    // residuals are already normalised. Every candidate is scored as the re-fit of everything
    // (k = all its parameters, and the choices a profile made for it: `profiled_choices`): one
    // only screened is scored at its screen's cost, which its re-fit could only lower, so its
    // score is an upper bound of that re-fit's — candidates compare like with like, and none
    // wins by the parameters it did not fit
    let score_fit = |c: Candidate, x: Vec<f64>, cost: f64, base_fitted: bool| -> Option<Scored> {
        let fitted = x.len() + c.profiled_choices();
        if !cost.is_finite() {
            return None;
        }
        let m = problem.build(c, &x)?;
        let rho = problem.simulate(&m).map_or(0.0, |s| lag1_autocorrelation(&problem.residual_of(s)));
        let own = c.effects();
        let parts: Vec<(String, String)> = if own.is_empty() {
            vec![(c.name().to_string(), String::new())]
        } else {
            own.iter().map(|e| (e.name().to_string(), e.element(&m))).collect()
        };
        let effect = parts.iter().map(|p| p.0.as_str()).collect::<Vec<_>>().join(" + ");
        let at = (!own.is_empty()).then(|| parts.iter().map(|p| p.1.as_str()).collect::<Vec<_>>().join(" + "));
        // the one rule of what an effect may move (`verdict::declared_moved`); the declared
        // model's own re-fit is judged as the answer (`distorted`), not here
        let moved = if matches!(c, Candidate::None) { Vec::new() } else { moved_declared(m0, &m) };
        let score = CandidateScore {
            effect,
            at,
            parameters: problem.report(c, &m),
            error_after: cost.sqrt(),
            score: bic(cost, nres, n_eff, fitted),
            fitted_parameters: fitted,
            implausible: !moved.is_empty(),
            implausible_because: moved,
            parts,
        };
        Some((score, m, rho, c, x, base_fitted))
    };
    let mut scored: Vec<Scored> =
        fits.into_iter().filter_map(|(i, x, cost, base)| score_fit(cands[i], x, cost, base)).collect();
    let none = scored
        .iter()
        .position(|s| s.0.effect == "none")
        .ok_or_else(|| IdentError::Data("re-fitting the declared model failed".into()))?;
    // an effect must beat the re-fitted declared model clearly: 10 % less error and a lower
    // score, its mechanics where it may move them
    let choose = |scored: &[Scored]| {
        let mut best = none;
        for (i, s) in scored.iter().enumerate() {
            if !s.0.implausible && clearly_beats(&s.0, &scored[best].0, &scored[none].0, predicted) {
                best = i;
            }
        }
        best
    };
    // entry `i`, only screened (the inertias and stiffnesses held at the declared values),
    // re-fitted with everything; kept where that is plausible and scores no worse (whether it was)
    let refit_whole = |i: usize, scored: &mut Vec<Scored>| -> bool {
        let c = scored[i].3;
        let (x, cost) = fit_all(c, &scored[i].4);
        match score_fit(c, x, cost, true) {
            Some(again) if !again.0.implausible && again.0.score <= scored[i].0.score => {
                scored[i] = again;
                true
            }
            _ => false,
        }
    };
    let mut best = choose(&scored);
    // an answer only screened is re-fitted with everything before anything is compared with it
    for _ in 0..ANSWER_REFITS {
        if scored[best].5 || !refit_whole(best, &mut scored) {
            break;
        }
        best = choose(&scored);
    }
    // leave-out: the declared model re-fitted again from the answer's inertias and stiffnesses
    // (its first re-fit may have stopped short of what the answer's found, and an effect that
    // adds nothing beside them is then no finding)
    if best != none && scored[best].5 {
        let (x, cost) = fit_all(Candidate::None, &scored[best].4[..nbase]);
        if cost < scored[none].0.error_after.powi(2) {
            if let Some(again) = score_fit(Candidate::None, x, cost, true) {
                scored[none] = again;
                best = choose(&scored);
            }
        }
    }
    let mut search_notes = Vec::new();
    // The second step of the forward selection from single effect `single` (an index into
    // `scored`, whose residual is structured): returns the answer, the single effect or a pair
    // added to `scored`.
    let second_step = |single: usize, scored: &mut Vec<Scored>, search_notes: &mut Vec<String>| -> usize {
        let Candidate::Effect(first) = scored[single].3 else {
            return single;
        };
        let mut best = single;
        // forward selection, second step, where the single effect leaves a residual structured
        // enough that another could beat it clearly (the torsional engine's rule): every effect
        // of another kind, at every element where it can act, added to the best single one (its
        // own size screened with the rest held, the SCREEN_KEEP best re-fitted); a pair must
        // beat the single effect as that beat the declared model. Beside a friction or a play a
        // second nonlinear effect (a play beside a friction, a friction beside a play) is
        // searched only where the pair is stepped whole (`plant::Dynamics::has_exact_steps`: a
        // play that engages at once; elsewhere RK4's fine steps throughout take minutes per
        // record)
        let nonlinear_first = first.is_nonlinear();
        let stepped_whole = |second: Effect| stepped_whole(m0, first, second);
        let x1 = scored[best].4.clone();
        let others: Vec<Effect> = cands
            .iter()
            .filter_map(|c| match *c {
                Candidate::Effect(e) if e.name() != first.name() => Some(e),
                _ => None,
            })
            .collect();
        let (seconds, not_stepped): (Vec<Effect>, Vec<Effect>) = others.into_iter().partition(|&e| stepped_whole(e));
        if !not_stepped.is_empty() {
            search_notes.push(format!(
                "beside {} {} not searched for: the pair has no whole steps in this model (minutes per record)",
                label(scored[best].3),
                if not_stepped.len() == 1 {
                    "a second friction or play was".to_string()
                } else {
                    format!("{} second frictions or plays were", not_stepped.len())
                }
            ));
        }
        let screen_second = |k: usize| -> (usize, Vec<f64>, f64) {
            let (x, cost) = problem.screen(Candidate::Pair(first, seconds[k]), &x1);
            (k, x, cost)
        };
        let mut screened2 = super::on_two_workers(seconds.len(), &screen_second);
        screened2.sort_by(|a, b| a.2.total_cmp(&b.2));
        // the SCREEN_KEEP best, and the best place of every other kind: the screens held the
        // mechanics at the single effect's re-fit, which bent them to stand in for what the
        // second effect does — alike for every place of one kind but not across kinds (as the
        // first step's screens held at an implausible declared re-fit)
        let mut kept2: Vec<(usize, Vec<f64>, f64)> = Vec::new();
        for (rank, s) in screened2.into_iter().enumerate() {
            if rank < SCREEN_KEEP || !kept2.iter().any(|k| seconds[k.0].name() == seconds[s.0].name()) {
                kept2.push(s);
            }
        }
        let screened2 = kept2;
        // the second effect as it was fitted alone (its size, and the mechanics of its fit): a
        // dead time's or a play's cost is rough, and beside the first effect's mechanics its
        // screen may stop in another valley
        let alone =
            |e: Effect| -> Option<&Vec<f64>> { scored.iter().find(|s| s.3 == Candidate::Effect(e)).map(|s| &s.4) };
        // the pair's re-fit: everything within the mechanics' tolerance, as a single effect's —
        // the single effect's re-fit moved the inertias and stiffnesses to stand in for what the
        // second effect does, and held there the pair could hardly beat it (a friction beside a
        // play: 0.110 → 0.103 held, 0.017 re-fitted). Beside a nonlinear first effect the two
        // sizes are fitted first with the mechanics held at the single effect's re-fit (the cost
        // of a play or a friction is rough: the sizes are found where the mechanics are known),
        // and everything from there.
        let fit_pair = |k: usize| -> (usize, Vec<f64>, f64) {
            let (j, x0, cost0) = &screened2[k];
            let c = Candidate::Pair(first, seconds[*j]);
            let mut x0 = x0.clone();
            if let Some(xs) = alone(seconds[*j]).filter(|xs| xs.len() == nbase + 1 && x0.len() == nbase + 2) {
                let (mut cost, size) = (*cost0, xs[nbase]);
                for start in [[&x0[..nbase + 1], &[size]].concat(), [&xs[..nbase], &[x0[nbase], size]].concat()] {
                    let c_start = problem.cost(c, &start);
                    if c_start < cost {
                        (x0, cost) = (start, c_start);
                    }
                }
            }
            let start = if nonlinear_first { fit_from(c, &x0, nbase).0 } else { x0 };
            let (x, cost) = fit_all(c, &start);
            (*j, x, cost)
        };
        for (j, x, cost) in super::on_two_workers(screened2.len(), &fit_pair) {
            if let Some(entry) = score_fit(Candidate::Pair(first, seconds[j]), x, cost, true) {
                scored.push(entry);
                let i = scored.len() - 1;
                if !scored[i].0.implausible
                    && clearly_beats(&scored[i].0, &scored[best].0, &scored[single].0, predicted)
                {
                    best = i;
                }
            }
        }
        // leave-out: the single effect re-fitted again from the pair's parameters without the
        // second effect; the pair stays only where it still beats that
        if best != single {
            let x = &scored[best].4;
            let (xs, cost) = fit_all(Candidate::Effect(first), &x[..x.len() - 1]);
            if cost < scored[single].0.error_after.powi(2) {
                if let Some(again) =
                    score_fit(Candidate::Effect(first), xs, cost, scored[single].5).filter(|a| !a.0.implausible)
                {
                    scored[single] = again;
                    if !clearly_beats(&scored[best].0, &scored[single].0, &scored[single].0, predicted) {
                        best = single;
                    }
                }
            }
        }
        best
    };
    // The answer `best` with one effect moved to each other place of its kind (beside the
    // answer's other parameters held): screened, the best of each effect's places re-fitted with
    // everything and kept in `scored` (an entry of that candidate replaced where the fit is
    // better); returns that entry where it is plausible and scores better than the answer.
    let swap_step = |best: usize, scored: &mut Vec<Scored>| -> Option<usize> {
        let (c, x) = (scored[best].3, scored[best].4.clone());
        // (the effect kept, the effect moved, the parameters held: the mechanics then the kept
        // effect's size)
        let moves: Vec<(Option<Effect>, Effect, Vec<f64>)> = match c {
            Candidate::Effect(e) if x.len() == nbase + 1 => vec![(None, e, x[..nbase].to_vec())],
            Candidate::Pair(a, b) if x.len() == nbase + 2 => {
                vec![(Some(a), b, x[..nbase + 1].to_vec()), (Some(b), a, [&x[..nbase], &x[nbase + 1..]].concat())]
            }
            _ => return None,
        };
        // (the move, the candidate, its held parameters)
        let mut trials: Vec<(usize, Candidate, Vec<f64>)> = Vec::new();
        for (m, (kept, moved, held)) in moves.iter().enumerate() {
            for alt in cands.iter().filter_map(|c| match *c {
                Candidate::Effect(e) if e.name() == moved.name() && e.at() != moved.at() => Some(e),
                _ => None,
            }) {
                match kept {
                    None => trials.push((m, Candidate::Effect(alt), held.clone())),
                    Some(k) if alt.at() != k.at() && stepped_whole(m0, *k, alt) => {
                        trials.push((m, Candidate::Pair(*k, alt), held.clone()))
                    }
                    Some(_) => {}
                }
            }
        }
        let screened = super::on_two_workers(trials.len(), &|t| {
            let (x, cost) = problem.screen(trials[t].1, &trials[t].2);
            (t, x, cost)
        });
        let mut found = None;
        for m in 0..moves.len() {
            // the best screen of this move's places
            let Some((t, x0, _)) =
                screened.iter().filter(|s| trials[s.0].0 == m && s.2.is_finite()).min_by(|a, b| a.2.total_cmp(&b.2))
            else {
                continue;
            };
            let alt = trials[*t].1;
            let (x, cost) = fit_all(alt, x0);
            let Some(entry) = score_fit(alt, x, cost, true) else { continue };
            let i = match scored.iter().position(|s| s.3 == alt) {
                Some(i) if scored[i].0.error_after <= entry.0.error_after => i,
                Some(i) => {
                    scored[i] = entry;
                    i
                }
                None => {
                    scored.push(entry);
                    scored.len() - 1
                }
            };
            let incumbent = found.unwrap_or(best);
            if !scored[i].0.implausible && scored[i].0.score < scored[incumbent].0.score {
                found = Some(i);
            }
        }
        found
    };
    // The answer `best`, which holds a compliance, re-fitted with everything (from the answer's
    // parameters) at the damping ratios of COMPLIANCE_DAMPING_RATIOS for the split's own mode,
    // then, at the best of them, at each motor share of COMPLIANCE_SHARES and at the vertex of the
    // parabola through the best share and its neighbours (the search held the share at one half
    // and the damping at the body's stiffness-proportional one): the best fit (added to `scored`)
    // and the profile (the share's 95 % interval where the information criterion rises by less
    // than PROFILE_CHI2_95, the stiffnesses fitted there); `None` where no share fits plausibly.
    let profile_share = |best: usize, scored: &mut Vec<Scored>| -> Option<(usize, ShareProfile)> {
        let (c, x) = (scored[best].3, scored[best].4.clone());
        let model = &scored[best].1;
        let own = &model.effects[model.effects.len() - c.effects().len()..];
        let Some(Effect::Compliance(found)) = own.iter().find(|e| matches!(e, Effect::Compliance(_))).copied() else {
            return None;
        };
        let inertia = model.line.bodies.get(found.body)?.inertia;
        // the damping of the split's own mode at ratio `zeta` (None: the body's proportional one)
        let damping = |zeta: Option<f64>, share: f64| {
            zeta.map(|z| 2.0 * z * (found.stiffness * share * (1.0 - share) * inertia).sqrt())
        };
        let fit_at = |share: f64, zeta: Option<f64>| -> Option<(f64, Scored)> {
            let at = c.with_compliance(share, damping(zeta, share));
            let (xs, cost) = fit_all(at, &x);
            score_fit(at, xs, cost, true).filter(|s| !s.0.implausible).map(|s| (share, s))
        };
        let cost = |s: &Scored| s.0.error_after.powi(2);
        let ratios: Vec<Option<f64>> =
            std::iter::once(None).chain(COMPLIANCE_DAMPING_RATIOS.iter().map(|&z| Some(z))).collect();
        // the index of the fit of least cost among `fits` (None: none fitted)
        let least = |fits: &[Option<(f64, Scored)>]| {
            (0..fits.len())
                .filter_map(|k| fits[k].as_ref().map(|p| (k, cost(&p.1))))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|p| p.0)
        };
        let by_damping = super::on_two_workers(ratios.len(), &|k| fit_at(found.motor_share, ratios[k]));
        let damped = least(&by_damping);
        let zeta = damped.and_then(|k| ratios[k]);
        // the share the search held was fitted at that damping already
        let grid = super::on_two_workers(COMPLIANCE_SHARES.len(), &|k| match damped {
            Some(d) if COMPLIANCE_SHARES[k] == found.motor_share => by_damping[d].clone(),
            _ => fit_at(COMPLIANCE_SHARES[k], zeta),
        });
        let mut profile: Vec<(f64, Scored)> = grid.iter().flatten().cloned().collect();
        let k = least(&grid)?;
        if let (Some(Some(lo)), Some(mid), Some(Some(hi))) =
            (k.checked_sub(1).map(|j| &grid[j]), &grid[k], grid.get(k + 1))
        {
            let (c0, c1, c2) = (cost(&lo.1), cost(&mid.1), cost(&hi.1));
            let curvature = c0 - 2.0 * c1 + c2;
            if curvature > 0.0 {
                let h = mid.0 - lo.0;
                let vertex = (mid.0 + 0.5 * h * (c0 - c2) / curvature).clamp(lo.0, hi.0);
                if let Some(v) = fit_at(vertex, zeta) {
                    profile.push(v);
                }
            }
        }
        profile.sort_by(|a, b| a.0.total_cmp(&b.0));
        let best_cost = profile.iter().map(|p| cost(&p.1)).fold(f64::INFINITY, f64::min);
        let accepted = |p: &(f64, Scored)| n_eff * (cost(&p.1) / best_cost).ln() <= PROFILE_CHI2_95;
        let first = profile.iter().position(accepted)?;
        let last = profile.iter().rposition(accepted)?;
        let share_interval = [profile[..first].last().map_or(0.0, |p| p.0), profile.get(last + 1).map_or(1.0, |p| p.0)];
        let (chosen_share, chosen) = profile.iter().find(|p| cost(&p.1) == best_cost)?.clone();
        let keys: Vec<String> = Effect::Compliance(found).parameters(&chosen.1).into_iter().map(|p| p.0).collect();
        let (stiffness_key, share_key) = (keys.first()?.clone(), keys.get(1)?.clone());
        // the stiffness over the shares the share's interval spans, its ends (the nearest
        // shares rejected) included as they are in that interval: the split's mode fixes
        // k/(s(1 − s)), so a share the interval holds moves the stiffness with it
        let ends = first.saturating_sub(1)..=(last + 1).min(profile.len() - 1);
        let stiffnesses: Vec<f64> =
            profile[ends].iter().filter_map(|p| p.1 .0.parameters.get(&stiffness_key).copied()).collect();
        let stiffness_range = [
            stiffnesses.iter().copied().fold(f64::INFINITY, f64::min),
            stiffnesses.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        ];
        let damped = match zeta {
            Some(z) => format!(
                "at {:.1} % of its own mode's critical damping (the best of {:?})",
                100.0 * z,
                COMPLIANCE_DAMPING_RATIOS
            ),
            None => {
                "with the body's stiffness-proportional damping (better than any of the damping ratios tried)".into()
            }
        };
        let note = format!(
            "the compliance {}: its motor share, held at one half by the search, profiled at {} shares from {} to {} {damped}: best {chosen_share:.3} (error {:.4}); the record gives it between {:.2} and {:.2} (the nearest shares whose information criterion rises by more than {PROFILE_CHI2_95}), and the stiffness {:.4e} … {:.4e} over the shares of that interval, its ends included, which the stiffness's interval includes",
            Element::Body(found.body).phrase(m0),
            profile.len(),
            COMPLIANCE_SHARES[0],
            COMPLIANCE_SHARES[COMPLIANCE_SHARES.len() - 1],
            chosen.0.error_after,
            share_interval[0],
            share_interval[1],
            stiffness_range[0],
            stiffness_range[1],
        );
        scored.push(chosen);
        let profile =
            ShareProfile { body: found.body, share_key, share_interval, stiffness_key, stiffness_range, note };
        Some((scored.len() - 1, profile))
    };
    // A compliance's motor share and damping are not among the searched sizes: a compliance
    // answer's are profiled before anything is added beside it (a friction beside a compliance
    // whose damping is off stands in for that damping).
    let mut share_profile: Option<ShareProfile> = None;
    let mut profile = |best: &mut usize, scored: &mut Vec<Scored>, search_notes: &mut Vec<String>| {
        let body = scored[*best].3.compliance_body();
        if *best == none || !scored[*best].5 || body.is_none() || share_profile.as_ref().map(|p| p.body) == body {
            return;
        }
        if let Some((i, p)) = profile_share(*best, scored) {
            *best = i;
            search_notes.push(p.note.clone());
            share_profile = Some(p);
        }
    };
    profile(&mut best, &mut scored, &mut search_notes);
    let structured = |s: &Scored| s.2.abs() >= WHITE_RESIDUAL_LAG1;
    if matches!(scored[best].3, Candidate::Effect(_)) && structured(&scored[best]) {
        best = second_step(best, &mut scored, &mut search_notes);
    }
    // The torsional engine's restart ([`super::torsional::RESTART_LEFT_FRACTION`]): an answer
    // that leaves more than that fraction of the declared model's error in a structured
    // residual may owe it to its first effect (one that explains much of the record alone, in
    // a wrong place or of a wrong kind, hides what belongs beside the right one). The second
    // step is run again from the best other plausible single effect that beats the declared
    // model clearly (re-fitted with everything first, as an answer only screened is), and its
    // answer is kept where it beats this one clearly.
    if best != none
        && scored[best].0.error_after > super::torsional::RESTART_LEFT_FRACTION * error_before
        && structured(&scored[best])
    {
        // the runner-up shares no effect and place with the answer, but for the second effect of
        // a pair beside a nonlinear first one: that pair's sizes were found with the mechanics at
        // the first's re-fit, and its second effect, as the first of a search, takes another path
        let mut answer_parts = scored[best].0.parts.clone();
        if matches!(scored[best].3, Candidate::Pair(first, _) if first.is_nonlinear()) {
            answer_parts.truncate(1);
        }
        let runner_up = (0..scored.len())
            .filter(|&i| matches!(scored[i].3, Candidate::Effect(_)) && i != best)
            .filter(|&i| !scored[i].0.parts.iter().any(|p| answer_parts.contains(p)))
            .filter(|&i| {
                !scored[i].0.implausible && clearly_beats(&scored[i].0, &scored[none].0, &scored[none].0, predicted)
            })
            .min_by(|&a, &b| scored[a].0.score.total_cmp(&scored[b].0.score));
        if let Some(r) = runner_up {
            if !scored[r].5 {
                refit_whole(r, &mut scored);
            }
            let alternative = if structured(&scored[r]) { second_step(r, &mut scored, &mut search_notes) } else { r };
            let kept = !scored[alternative].0.implausible
                && clearly_beats(&scored[alternative].0, &scored[best].0, &scored[best].0, predicted);
            search_notes.push(format!(
                "the answer left {:.0} % of the declared model's error in a structured residual: the search was run again from {} ({}, error {:.4}){}",
                100.0 * scored[best].0.error_after / error_before,
                label(scored[r].3),
                scored[alternative].0.effect,
                scored[alternative].0.error_after,
                if kept { ", which beats it clearly and is the answer" } else { ", which does not beat it clearly" }
            ));
            if kept {
                best = alternative;
            }
        }
    }
    // The swap step (the torsional engine's, for places): each effect of the answer is tried at
    // every other place where an effect of its kind can act, beside the answer's other
    // parameters — its mechanics and the pair's other effect. The places were ranked by screens
    // that held other mechanics (the declared ones where their re-fit was implausible, the single
    // effect's re-fit for a pair's second effect), and two places of one kind differ by little
    // beside mechanics bent to stand in for the other. The best place's screen is re-fitted with
    // everything, and it replaces the answer where it scores better, plausibly; where the two
    // explain the record alike, the verdict says the record does not tell where
    // (`verdict::undetermined`).
    if best != none && scored[best].5 {
        if let Some(swapped) = swap_step(best, &mut scored) {
            search_notes.push(format!(
                "swap: {} rather than {} (error {:.4} against {:.4}; the places compared beside the answer's re-fitted mechanics)",
                label(scored[swapped].3),
                label(scored[best].3),
                scored[swapped].0.error_after,
                scored[best].0.error_after
            ));
            best = swapped;
        }
    }
    profile(&mut best, &mut scored, &mut search_notes);
    // The declared model as the answer, its free re-fit beyond the tolerance: re-fitted within
    // it. Where the record does not prefer the free re-fit strongly
    // ([`super::verdict::moved_by_the_record`]), it does not determine what that moved, and
    // the declared model within its tolerance is the answer — where nothing ends at the
    // tolerance's edge (else it is distorted).
    let free_moved = moved_declared(m0, &scored[none].1);
    let mut held_at_declared: Vec<String> = Vec::new();
    if best == none && !free_moved.is_empty() {
        // from the free re-fit, which the fit moves into the box
        let bounds = tolerance_box(nbase, nbase);
        let within = |x: &[f64]| problem.residual(Candidate::None, x);
        let fit = lm::Fit::new(20, LM_REL_TOL).within(TRUST_RADIUS).boxed(&bounds);
        let (x, cost) = lm::minimise(&within, &scored[none].4, fit);
        if let Some(boxed) = score_fit(Candidate::None, x, cost, true) {
            let evidence = boxed.0.score - scored[none].0.score;
            let s = DeclaredSettings::default();
            if !super::verdict::moved_by_the_record(scored[none].0.score, boxed.0.score, &s) {
                search_notes.push(format!(
                    "the declared model's free re-fit moved {}; within the factor it fits as well (error {:.4} against {:.4}, information criterion {evidence:.1} apart, less than the {} that shows the record demands the move): the record does not determine them",
                    free_moved.join("; "),
                    boxed.0.error_after,
                    scored[none].0.error_after,
                    s.min_evidence
                ));
                let free_score = scored[none].0.score;
                scored[none] = boxed;
                held_at_declared =
                    hold_edges_at_declared(&problem, &bounds, &mut scored[none], free_score, &|x, cost| {
                        score_fit(Candidate::None, x, cost, true)
                    });
                if !held_at_declared.is_empty() {
                    search_notes.push(format!(
                        "held at their declared values, re-fitted without them: {} (the re-fit within the factor ended at its edge for them, and held at the declared values the declared model fits as well as its free re-fit: the record does not determine them)",
                        held_at_declared.join(", ")
                    ));
                }
            }
        }
    }
    // The answer on data its fit did not see ([`super::check_held_out`], as for the torsional
    // sweep): it and the re-fitted declared model (where its re-fit is plausible) fitted again
    // without each fold, from their own parameters (those the answer fitted: an effect kept from
    // the screen has the declared inertias and stiffnesses held), each scored on the fold it did
    // not see; a pair's `rivals` (each of its effects alone, as fitted) on the same folds.
    let none_moved = moved_declared(m0, &scored[none].1);
    let declared = |x: &[f64]| problem.residual(Candidate::None, x);
    let check_of = |answer: usize, rivals: &[usize]| -> super::HeldOutCheck {
        // the residual is the score's: the prediction's where the models are scored by it
        let model = &scored[answer].1;
        let scored_after = if predicted { problem.simulate(model) } else { problem.simulate_open(model) };
        let answer_residual = scored_after.map(|y| problem.residual_of(y));
        // an entry's residual over the parameters it fitted (an effect kept from the screen has
        // the declared inertias and stiffnesses held), and those
        let free = |i: usize| if scored[i].5 { 0 } else { nbase };
        let p = &problem;
        let residual_of_entry = |i: usize| {
            let (c, x, from) = (scored[i].3, &scored[i].4, free(i));
            move |s: &[f64]| p.residual(c, &[&x[..from], s].concat())
        };
        let fns: Vec<_> = std::iter::once(answer).chain(rivals.iter().copied()).map(residual_of_entry).collect();
        let jobs: Vec<(super::ResidualFn, &[f64])> = std::iter::once(answer)
            .chain(rivals.iter().copied())
            .zip(&fns)
            .map(|(i, f)| (f as super::ResidualFn, &scored[i].4[free(i)..]))
            .collect();
        let has_effects = scored[answer].3 != Candidate::None;
        super::check_held_out(
            len,
            dt,
            answer_residual.as_deref(),
            jobs[0],
            (has_effects && none_moved.is_empty())
                .then_some((&declared as super::ResidualFn, scored[none].4.as_slice())),
            &jobs[1..],
            has_effects,
            error_before,
        )
    };
    // A pair is chosen on the data its fits did not see as well (issue 32, item 3): where one of
    // its effects alone errs no more on the held-out folds than the pair, the other is not borne
    // out by the record — its gain on the fitted data is the fit's own freedom — and that effect
    // alone is the answer.
    let rivals: Vec<usize> = match scored[best].3 {
        Candidate::Pair(a, b) => [a, b].iter().filter_map(|e| best_alone(&scored, *e, true)).collect(),
        _ => Vec::new(),
    };
    let mut check = check_of(best, &rivals);
    let pair_held_out = check.held_out.error_held_out;
    if let Some((k, alone)) = check.rival_as_good() {
        search_notes.push(format!(
            "{} rather than {}: on the folds its fit did not see, it alone errs {alone:.4} against the pair's {pair_held_out:.4}",
            label(scored[rivals[k]].3),
            label(scored[best].3),
        ));
        best = rivals[k];
        check = check_of(best, &[]);
    }
    let (chosen, model, rho, chosen_candidate, chosen_x, base_fitted) = scored[best].clone();
    let free_from = if base_fitted { 0 } else { nbase };
    let moved_declared = moved_declared(m0, &model);
    let at_tolerance = judge_declared(m0, &model, super::verdict::declared_at_tolerance);
    // the traces are simulations over the whole record (the answer's FMU replays them)
    let after = problem.simulate_open(&model).map(|y| problem.per_output(y));
    let fold_parameters: Vec<BTreeMap<String, f64>> = check
        .answer_folds
        .iter()
        .map(|f| {
            problem
                .build(chosen_candidate, &[&chosen_x[..free_from], &f.x].concat())
                .map_or_else(BTreeMap::new, |m| problem.report(chosen_candidate, &m))
        })
        .collect();
    let mut intervals = super::fold_intervals(&chosen.parameters, &fold_parameters);
    // a quantity held at its declared value was not fitted: its folds' spread is no interval
    intervals.retain(|k, _| !held_at_declared.contains(k));
    // the folds held the compliance's motor share: its interval is the profile's, and the
    // stiffnesses over the shares of that interval widen the stiffness's
    if let Some(p) = share_profile.as_ref().filter(|p| chosen_candidate.compliance_body() == Some(p.body)) {
        intervals.insert(p.share_key.clone(), p.share_interval);
        if let Some([lo, hi]) = intervals.get(&p.stiffness_key).copied() {
            intervals.insert(p.stiffness_key.clone(), [lo.min(p.stiffness_range[0]), hi.max(p.stiffness_range[1])]);
        }
    }

    // the declared model as the answer: its mechanics neither beyond the factor nor at its
    // edge (re-fitted within it, where the record did not demand more: a quantity at the edge
    // is at its bound, no finding)
    let distorted = match (chosen.effect == "none", moved_declared.is_empty(), at_tolerance.is_empty()) {
        (true, false, _) => {
            Some(format!("the declared model fits only with its mechanics moved: {}", moved_declared.join("; ")))
        }
        (true, true, false) => Some(format!(
            "the declared model fits only with its mechanics at the edge of their tolerance: {}",
            at_tolerance.join("; ")
        )),
        _ => None,
    };
    let structured_residual = super::verdict::ResidualSettings::default().structured(rho, chosen.error_after);
    let before = problem.per_output(problem.simulate_open(m0).ok_or_else(cannot_simulate)?);
    let after = after.unwrap_or_else(|| before.clone());
    let traces = DriveTraces {
        time_s: (0..len).map(|k| k as f64 * dt).collect(),
        measured: problem.measured.clone(),
        before,
        after,
    };
    // a size the record bounds only from below (a play wider than every twist it meets), or a
    // friction that is a constant force (its body turns one way throughout), is no finding either
    let chosen_cost = chosen.error_after.powi(2);
    let min_evidence = PlaceSettings::default().min_evidence;
    let mut no_finding = problem.unbounded_above(chosen_candidate, &chosen_x, chosen_cost, n_eff, min_evidence);
    no_finding.extend(problem.one_way_offsets(chosen_candidate, &model));
    // each effect found, with what it explains: the error without it (the other of a pair
    // alone, its best fit; the re-fitted declared model for a single effect)
    let own = chosen_candidate.effects();
    let error_alone = |e: Effect| best_alone(&scored, e, false).map(|i| scored[i].0.error_after);
    let effects: Vec<FoundEffect> = model.effects[model.effects.len() - own.len()..]
        .iter()
        .zip(&own)
        .map(|(sized, placed)| {
            let parameters: BTreeMap<String, f64> = sized.parameters(&model).into_iter().collect();
            let intervals = parameters.keys().filter_map(|k| intervals.get(k).map(|v| (k.clone(), *v))).collect();
            let other = own.iter().find(|o| *o != placed).copied();
            let error_without = other.and_then(error_alone).unwrap_or(scored[none].0.error_after);
            let mut found = FoundEffect::new(
                sized.name().into(),
                Some(sized.element(&model)),
                parameters,
                intervals,
                error_without,
            );
            // a compliance's share is no size: what it leaves open is in the stiffness's interval
            if let Some(p) = &share_profile {
                found.not_determined.retain(|k| *k != p.share_key);
            }
            for (key, _) in no_finding.iter().filter(|(k, _)| found.parameters.contains_key(k)) {
                if !found.not_determined.contains(key) {
                    found.not_determined.push(key.clone());
                }
            }
            found
        })
        .collect();
    let mut candidates: Vec<CandidateScore> = scored.into_iter().map(|s| s.0).collect();
    candidates.sort_by(|a, b| a.score.total_cmp(&b.score));
    let undetermined = super::verdict::undetermined(&chosen, &candidates, &PlaceSettings::default());
    // an effect whose size the record does not determine is no finding; every such value is said
    let held_out_settings = super::HeldOutSettings::default();
    let mut not_determined = super::not_determined(&chosen.parameters, &intervals, &held_out_settings);
    let (mut effects, mut intervals) = (effects, intervals);
    super::drop_unmeasured_intervals(&check.held_out, &mut effects, &mut intervals);
    let unsupported = check
        .unsupported
        .or_else(|| {
            (!no_finding.is_empty()).then(|| no_finding.iter().map(|o| o.1.as_str()).collect::<Vec<_>>().join("; "))
        })
        .or_else(|| super::sizes_not_determined(&effects, &held_out_settings));
    for key in held_at_declared.into_iter().chain(no_finding.into_iter().map(|(key, _)| key)) {
        if !not_determined.contains(&key) {
            not_determined.push(key);
        }
    }
    let mut d = DriveDiagnosis {
        effect: chosen_candidate.name().to_string(),
        at: effects.first().and_then(|e| e.at.clone()),
        effects,
        search_notes,
        parameters: chosen.parameters,
        intervals,
        held_out: check.held_out,
        unsupported,
        not_determined,
        undetermined,
        error_before,
        error_after: chosen.error_after,
        candidates,
        structured_residual,
        moved_declared,
        at_tolerance,
        distorted,
        high_pass_hz,
        scored_by_prediction: predicted,
        model,
        verdict: super::verdict::Verdict::NotExplained,
        verdict_reasons: Vec::new(),
        notes: Vec::new(),
        traces,
    };
    d.notes = d.notes_in_words();
    (d.verdict, d.verdict_reasons) = d.judged(&rec);
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::line::{Coupling, Line, LineBody};

    /// The damping bound's critical damping of a coupling, 2√(k·J) with J the inertia its twist
    /// sees through its gear, against the eigenvalues of the two-mass line damped at a tenth of
    /// it: the mode's damping ratio is then 0.1 (one elastic mode, no drag).
    #[test]
    fn a_couplings_critical_damping_is_its_modes() {
        let body = |name: &str, inertia: f64| LineBody { name: name.into(), inertia, drag: 0.0 };
        let mut m = DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![body("motor", 0.02), body("load", 0.5)],
                couplings: vec![Coupling::new(800.0, 0.0, 3.0)],
            },
            inputs: vec![0],
            effects: vec![],
        };
        let critical = critical_damping(&m, 0);
        m.line.couplings[0].damping = 0.1 * critical;
        let poles = m.line.model().unwrap().state_space(&[]).unwrap().damp().unwrap();
        let elastic = poles.iter().find(|p| p.natural_hz > 1.0).expect("an elastic mode");
        assert!((elastic.damping_ratio.unwrap() - 0.1).abs() < 1e-9, "{poles:?}");
    }
}
