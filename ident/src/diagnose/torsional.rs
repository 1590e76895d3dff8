//! Diagnosis of a torsional record (a sweep, a multisine, steps, PRBS, a closed-loop record):
//! the declared rig simulated with the recorded drive torque, its speed residual, and the
//! effects of the rig file's `[effects]` (`plant::rig::DriveEffects`) added by forward selection — several at once where the data
//! lacks several — each kept effect checked by leaving it out. Offsets and drift are removed
//! below a corner set by the record's length, not by its excitation.

use std::collections::BTreeMap;

use plant::rig::DriveEffects;
use plant::rig::{RigParams, Variant};
use plant::{DriveModel, Dynamics, Quantity};
use serde::Serialize;

use super::verdict::{self, DeclaredSettings, Moves, Refitted};
use super::{
    bic, effective_count, lag1_autocorrelation, lm, rms, CandidateScore, HeldOut, FRICTION_SMOOTHING_FRACTION,
    LM_REL_TOL,
};
use crate::error::{IdentError, Result};
use crate::signal::{filtfilt_high_pass, filtfilt_high_pass_pair, rfft, Spectrogram};
use crate::sweep::Sweep;

/// What the residual shows before any candidate is fitted.
#[derive(Debug, Clone, Serialize)]
pub struct Evidence {
    /// Frequency of the residual's largest spectral line (M2 speed), Hz.
    pub residual_peak_hz: f64,
    /// Residual over measured amplitude at that line.
    pub residual_peak_ratio: f64,
    /// Lag of the largest input-residual cross-correlation (residual behind the torque
    /// positive), s.
    pub xcorr_lag_s: f64,
    /// Lag-1 autocorrelation of the residual (0 = white).
    pub residual_lag1: f64,
    /// Residual power at 2× and 3× the instantaneous excitation frequency relative to the
    /// residual power at 1× (harmonics: a nonlinearity).
    pub harmonic_ratio: f64,
}

/// A model to simulate: the rig, its variant and the effects.
#[derive(Debug, Clone, Serialize)]
pub struct TorsionalModel {
    /// Reduced rig parameters.
    pub rig: RigParams,
    /// Variant.
    pub variant: Variant,
    /// Effects in the drive path.
    pub effects: DriveEffects,
}

impl TorsionalModel {
    /// Its highest natural frequency, Hz (a compliance's mode where it has one; NaN where the
    /// model cannot be built).
    fn upper_mode_hz(&self) -> f64 {
        self.drive_model().map_or(f64::NAN, |m| highest_mode_hz(&m))
    }

    /// The rig's one drive model ([`DriveModel::paper_rig`]; `None` where it cannot be built).
    fn drive_model(&self) -> Option<DriveModel> {
        DriveModel::paper_rig(&self.rig, self.variant, &self.effects).ok()
    }
}

/// The highest undamped natural frequency of `m`, Hz (NaN where it has none): the eigenvalues
/// of J^{-1/2} K J^{-1/2}, as the torsional engine has always computed them. `plant::modes`
/// (Cholesky of J) agrees to the last digits, but those digits steer the compliance's fit: with
/// it, held-out test `held_out_a_stiffer_compliance_and_a_wider_play_about_3_nm` ends in
/// another optimum (play 5.3 mrad for 4).
fn highest_mode_hz(m: &DriveModel) -> f64 {
    let Ok(line) = m.line.model() else { return f64::NAN };
    let k = line.stiffness_matrix();
    let j = line.inertia.diagonal();
    let s = nalgebra::DMatrix::from_fn(k.nrows(), k.ncols(), |r, c| k[(r, c)] / (j[r] * j[c]).sqrt());
    s.symmetric_eigenvalues().iter().map(|&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)).fold(f64::NAN, f64::max)
}

/// The diagnosis of one record.
#[derive(Debug, Clone, Serialize)]
pub struct TorsionalDiagnosis {
    /// Other solutions that fit the record as well as the answer (BIC within
    /// [`EQUIVALENT_BIC`]) with its parameters elsewhere: each one's parameters and error. When
    /// there are any, the record does not determine the answer's parameters.
    pub equivalents: Vec<BTreeMap<String, f64>>,
    /// Why the answer is no finding although it fits: its re-fit moved what the declared model
    /// measured beyond what its effects explain ([`verdict::declared_moved`]; `None`: it did not).
    pub distorted: Option<String>,
    /// The first effect found (`none` if none).
    pub effect: String,
    /// The machine it acts at, if at one.
    pub at: Option<String>,
    /// Its parameters and the re-fitted j_drive and c_short.
    pub parameters: BTreeMap<String, f64>,
    /// 95 % intervals of `parameters` over the held-out folds ([`super::jackknife_interval`]
    /// of the answer fitted without each fold).
    pub intervals: BTreeMap<String, [f64; 2]>,
    /// The answer on data its fit did not see ([`super::HeldOutSettings`]).
    pub held_out: HeldOut,
    /// Why the answer is no finding although it fits the record: its effects do not predict
    /// the held-out folds better than the re-fitted declared model — or the record does not determine a
    /// size of theirs ([`super::sizes_not_determined`]; `None`: they do, and it determines them).
    pub unsupported: Option<String>,
    /// The keys of `parameters` the record does not determine ([`super::not_determined`];
    /// each effect's are in `effects`): reported, never a finding.
    pub not_determined: Vec<String>,
    /// Why the answer is no finding: another effect, or the same elsewhere, explains the record
    /// about as well ([`verdict::undetermined`], the rule of every engine; `None`: the record
    /// tells what and where).
    pub undetermined: Option<String>,
    /// Every effect found, in the order found, with its parameters in the final model.
    pub effects: Vec<FoundEffect>,
    /// The answer's path: declared (re-fitted) → +A → +A+B, the kept effects in the order
    /// that lowers the error most (each model re-fitted); the order of `effects`.
    pub path: Vec<PathStep>,
    /// What the search did: each model it moved to (effects added, left out, swapped; a restart
    /// from the first round's runner-up begins again at the declared model).
    pub search: Vec<PathStep>,
    /// Normalised error of the declared model (1 = no better than predicting nothing).
    pub error_before: f64,
    /// Normalised error of the extended model.
    pub error_after: f64,
    /// Every candidate.
    pub candidates: Vec<CandidateScore>,
    /// What the residual showed.
    pub evidence: Evidence,
    /// The best model still leaves a structured (non-white) residual.
    pub structured_residual: bool,
    /// Corner of the high-pass that removes offsets and drift, Hz.
    pub high_pass_hz: f64,
    /// The extended model.
    pub model: TorsionalModel,
    /// The answer in one word ([`verdict::judge`]: its parameters against the record's bounds,
    /// beside `distorted` and `unsupported`).
    pub verdict: verdict::Verdict,
    /// Why the verdict is what it is (a *not explained* always has a reason).
    pub verdict_reasons: Vec<String>,
    /// What a reader needs beside the numbers, in words.
    pub notes: Vec<String>,
    /// Time, measured speeds and model speeds before and after (high-passed), for plots.
    #[serde(skip)]
    pub traces: Traces,
}

impl TorsionalDiagnosis {
    /// What a reader needs beside the numbers: the fit's notes ([`verdict::fit_notes`]), the
    /// path and each effect's need when several were found, why implausible candidates were not
    /// chosen, and how a found friction is smoothed.
    fn notes_in_words(&self) -> Vec<String> {
        let mut notes =
            verdict::fit_notes(&self.effect, "the declared parameters", self.structured_residual, self.error_after);
        if self.effects.len() > 1 {
            let names: Vec<String> = self
                .path
                .iter()
                .map(|p| {
                    let m = if p.effects.is_empty() { "declared".to_string() } else { p.effects.join(" + ") };
                    format!("{m} ({:.4})", p.error)
                })
                .collect();
            notes.push(format!("{} effects found: {}", self.effects.len(), names.join(" → ")));
            let needed: Vec<String> = self
                .effects
                .iter()
                .map(|e| {
                    let at = e.at.as_ref().map(|a| format!(" at {a}")).unwrap_or_default();
                    if e.error_without.is_finite() {
                        format!("{}{at} {:.4}", e.effect, e.error_without)
                    } else {
                        format!("{}{at} (the model without it cannot be simulated)", e.effect)
                    }
                })
                .collect();
            notes.push(format!("error with each effect left out (the others re-fitted): {}", needed.join(", ")));
        }
        notes.extend(verdict::implausible_notes(&self.candidates));
        if self.model.effects.coulomb_friction_nm.iter().any(|&f| f > 0.0) {
            notes.push(format!(
                "Coulomb friction is smoothed as T_c·w/√(w² + v_s²) with v_s = {:.3e} rad/s (1 % of the load machines' RMS speed, or wider where the friction would be faster than the {} ms integration step resolves)",
                self.model.effects.friction_smoothing_radps,
                plant::preset::BACKLASH_STEP_S * 1e3
            ));
        }
        notes
    }

    /// The verdict on `sweep`: every found effect's parameters against the record's bounds
    /// (its largest drive torque, the load machines' larger RMS speed, its length and sample
    /// time; [`verdict::BoundSettings`]' defaults), beside `distorted` and `unsupported`.
    fn judged(&self, sweep: &Sweep) -> (verdict::Verdict, Vec<String>) {
        let scales = verdict::RecordScales {
            max_force: sweep.torque_nm.iter().fold(0.0, |a: f64, v| a.max(v.abs())),
            rms_speed: rms(&sweep.speed_m2_radps).max(rms(&sweep.speed_m3_radps)),
            duration_s: sweep.torque_nm.len() as f64 * sweep.dt_s,
            sample_time_s: sweep.dt_s,
        };
        let judged = std::iter::once(&self.parameters).chain(self.effects.iter().map(|e| &e.parameters));
        verdict::judge(
            &self.effect,
            self.structured_residual,
            judged,
            &scales,
            self.distorted.iter().chain(&self.unsupported).chain(&self.undetermined),
            &verdict::BoundSettings::default(),
        )
    }
}

/// Signals for plots.
#[derive(Debug, Clone, Default)]
pub struct Traces {
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Measured speeds [M2, M3] (high-passed as the error is), rad/s.
    pub measured: [Vec<f64>; 2],
    /// Declared model's speeds, rad/s.
    pub before: [Vec<f64>; 2],
    /// Extended model's speeds, rad/s.
    pub after: [Vec<f64>; 2],
}

struct Problem<'a> {
    sweep: &'a Sweep,
    declared: RigParams,
    variant: Variant,
    /// The declared side shafts' stiffness in series on the differential's twist s, Nm/rad
    /// (eq. (A1)).
    c_s: f64,
    /// Effective count of the residual's values (the declared model's; set once it is known),
    /// which the information criterion counts.
    n_eff: f64,
    speed0: f64,
    measured: [Vec<f64>; 2],
    norm: f64,
    high_pass_hz: f64,
    /// Amplitude of the drive torque's variation (√2 × its high-passed RMS), Nm: the scale of
    /// the friction's starts and bound.
    torque_amplitude: f64,
    /// Friction smoothing speed: [`FRICTION_SMOOTHING_FRACTION`] of the load machines' RMS
    /// speed, rad/s.
    smoothing: f64,
    /// Short-time spectra of the speeds (both channels), their measured magnitudes and norm (0
    /// where the record is too short for frames).
    spectrogram: Spectrogram,
    measured_spectra: Vec<f64>,
    spectra_norm: f64,
}

impl Problem<'_> {
    fn simulate(&self, model: &TorsionalModel) -> Option<[Vec<f64>; 2]> {
        // Keep the search where the models are meaningful (and the matrix exponential cheap):
        // effects up to a second, a radian of play, a compliance mode below a tenth of the
        // sampling rate, frictions up to 100 times the torque's variation; declared
        // parameters within a factor 100.
        let e = &model.effects;
        let ratio = |a: f64, b: f64| (a / b).max(b / a);
        if e.time_delay_s > 1.0
            || e.actuator_lag_s > 1.0
            || e.backlash_rad > 1.0
            || e.coulomb_friction_nm.iter().any(|&f| f > 100.0 * self.torque_amplitude)
            || ratio(model.rig.j_drive, self.declared.j_drive) > 100.0
            || ratio(model.rig.c_short, self.declared.c_short) > 100.0
        {
            return None;
        }
        let m = model.drive_model()?;
        let d = Dynamics::paper_rig(&m).ok()?;
        // a nonlinear model faster than the record resolves (a lag or an overdamped pole far
        // below the sample time) would need thousands of RK4 steps per sample: not a candidate
        if model.effects.is_nonlinear()
            && d.integrator().counts(self.sweep.dt_s).is_none_or(|(coarse, _)| coarse > MAX_STEPS_PER_SAMPLE)
        {
            return None;
        }
        if e.compliance_stiffness_nm_per_rad > 0.0
            && highest_mode_hz(&m) > COMPLIANCE_TOP_PER_SAMPLE_RATE / self.sweep.dt_s
        {
            return None;
        }
        let speeds = [(Quantity::Speed, 0), (Quantity::Speed, 2)];
        let mut w =
            plant::simulate_record(&m, &d, &self.sweep.torque_nm, self.sweep.dt_s, self.speed0, &speeds).ok()?;
        let (mut b, mut a) = (w.pop()?, w.pop()?);
        if !a.iter().chain(&b).all(|v| v.is_finite()) {
            return None;
        }
        filtfilt_high_pass_pair(&mut a, &mut b, self.sweep.dt_s, self.high_pass_hz);
        Some([a, b])
    }

    /// The normalised residual, written over the simulation's first channel (the second
    /// appended), so a long record holds one buffer per fit, not three.
    fn residual(&self, model: &TorsionalModel) -> Option<Vec<f64>> {
        let [mut a, b] = self.simulate(model)?;
        for (y, m) in a.iter_mut().zip(&self.measured[0]) {
            *y = (m - *y) / self.norm;
        }
        a.reserve_exact(b.len());
        a.extend(b.iter().zip(&self.measured[1]).map(|(y, m)| (m - y) / self.norm));
        Some(a)
    }

    /// The normalised difference of the short-time spectral magnitudes of the simulated and
    /// the measured speeds (both channels): the response's amplitude over time and frequency
    /// without its phase ([`PHASE_FREE_WINDOW_S`]).
    fn spectral_residual(&self, model: &TorsionalModel) -> Option<Vec<f64>> {
        if self.spectra_norm <= 0.0 {
            return None;
        }
        let s = self.simulate(model)?;
        let mut r = Vec::with_capacity(self.measured_spectra.len());
        self.spectrogram.magnitudes(&s[0], &mut r);
        self.spectrogram.magnitudes(&s[1], &mut r);
        for (v, m) in r.iter_mut().zip(&self.measured_spectra) {
            *v = (*v - m) / self.spectra_norm;
        }
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    /// Normalised residual of simulated (high-passed) speeds, both channels.
    fn residual_of(&self, s: &[Vec<f64>; 2]) -> Vec<f64> {
        self.measured[0]
            .iter()
            .zip(&s[0])
            .chain(self.measured[1].iter().zip(&s[1]))
            .map(|(m, y)| (m - y) / self.norm)
            .collect()
    }

    /// Why fit `f` is no finding (empty: plausible): how it moved the declared mechanics beyond
    /// what its effects explain, by the one rule of [`verdict::declared_moved`], or a
    /// compliance's mode where the record does not excite the rig. The declared mechanics: j_drive is the drive's total
    /// inertia (a compliance splits it), c_short is judged with the compliance in series where
    /// there is one (eq. (A1): the drive torque reaches the twist s through k on the motor,
    /// so the pair's stiffness on s is 1/(1/c_s + 4/k)).
    fn moved(&self, f: &Fit) -> Vec<String> {
        let series_ratio = f.effects.iter().position(|c| c.moves() == Moves::SeriesSpring).map(|i| {
            let at = 2 + f.effects[..i].iter().map(|c| c.own_len()).sum::<usize>();
            let k = f.x[at].exp();
            1.0 / ((-f.x[1]).exp() + 4.0 * self.c_s / k)
        });
        let mut why = verdict::declared_moved(
            &[
                Refitted::Inertia { name: "j_drive", ratio: f.x[0].exp() },
                Refitted::Stiffness { name: "c_short", ratio: f.x[1].exp(), series_ratio },
            ],
            &DeclaredSettings::default(),
        );
        why.extend(self.mode_not_shown(f));
        why
    }

    /// Why fit `f`'s compliance is no finding: the record does not show its mode. Where the
    /// record does not excite the mode, only its series spring shows, and its frequency and
    /// motor share are not determined. Asked of the record itself, as the `drive_test` engine
    /// asks of a size (`unbounded_above`): the fit with the compliance's mode moved to the
    /// highest this engine simulates ([`COMPLIANCE_TOP_PER_SAMPLE_RATE`] of the sampling rate:
    /// the spring stiffer, the shafts softer so that the pair in series keeps its stiffness on
    /// the twist, eq. (A1): 1/(1/c_s + 4/k); everything else held) must err worse by the strong
    /// evidence that names a finding ([`verdict::PlaceSettings::min_evidence`]). A step or a
    /// broad band rings the mode and shows it; a sweep that stops well below it does not. (The
    /// rule before — the mode below the frequency under which 99 % of the drive torque's power
    /// lies — rejected the modes that steps ring: a step's power lies at low frequencies.)
    fn mode_not_shown(&self, f: &Fit) -> Option<String> {
        let i = f.effects.iter().position(|&c| c == Candidate::DriveCompliance)?;
        let at = 2 + f.effects[..i].iter().map(|c| c.own_len()).sum::<usize>();
        let upper = self.build(&f.effects, &f.x).upper_mode_hz();
        let top = COMPLIANCE_TOP_PER_SAMPLE_RATE / self.sweep.dt_s;
        let k = f.x[at].exp();
        // the mode grows as √k where the spring sets it: aimed at the top, then lowered by a
        // tenth until the model is one this engine simulates
        let moved = (0..8).find_map(|t| {
            let stiffer = k * ((top / upper).powi(2) * 0.9f64.powi(t)).max(1.0);
            // e^{-x1} + 4 c_s / k, the pair's compliance on the twist over c_s's, held
            let softer_shafts = (-f.x[1]).exp() + 4.0 * self.c_s / k - 4.0 * self.c_s / stiffer;
            let mut x = f.x.clone();
            (x[1], x[at]) = (-softer_shafts.ln(), stiffer.ln());
            let model = self.build(&f.effects, &x);
            let cost = self.residual(&model)?.iter().map(|v| v * v).sum::<f64>();
            Some((model.upper_mode_hz(), cost))
        });
        let min_evidence = verdict::PlaceSettings::default().min_evidence;
        let Some((moved_hz, cost)) = moved else {
            return Some(format!(
                "the record does not show the compliance's mode at {upper:.1} Hz: no model with the mode higher can be simulated to tell"
            ));
        };
        let evidence = self.n_eff * (cost / f.cost).ln();
        // NaN evidence (a cost that is not finite) shows nothing either
        let shown = evidence >= min_evidence;
        (upper.is_nan() || !shown).then(|| {
            format!(
                "the record does not show the compliance's mode at {upper:.1} Hz: with it at {moved_hz:.1} Hz (the spring stiffer, the shafts softer so that the pair's stiffness stays) the fit errs {:.4} against {:.4} (information criterion {evidence:.1} apart, less than the {min_evidence} that names a finding)",
                cost.sqrt(),
                f.cost.sqrt(),
            )
        })
    }

    /// Whether fit `f` keeps the declared mechanics where its effects allow ([`Problem::moved`]).
    fn plausible(&self, f: &Fit) -> bool {
        self.moved(f).is_empty()
    }

    /// The model of parameter vector `x` for `effects`: x[0], x[1] ln of j_drive and c_short
    /// relative to the declared values (c_long keeps its declared ratio to c_short), then each
    /// effect's own parameters in turn.
    fn build(&self, effects: &[Candidate], x: &[f64]) -> TorsionalModel {
        let (j, c) = (self.declared.j_drive * x[0].exp(), self.declared.c_short * x[1].exp());
        let mut rig = RigParams {
            j_drive: j,
            c_short: c,
            c_long: self.declared.c_long.map(|l| l * x[1].exp()),
            ..self.declared.clone()
        };
        let mut e = DriveEffects::default();
        let mut at = 2;
        for &cand in effects {
            let own = &x[at..at + cand.own_len()];
            at += cand.own_len();
            cand.apply(&mut rig, &mut e, own, self.variant);
        }
        // the friction's smoothing: a fraction of the machines' speeds, or wider where its
        // slope T_c/(v_s J) would be faster than the integration step resolves
        if let Ok(eff) = rig.effective(self.variant) {
            let j = [eff.j_m2, eff.j_drive, eff.j_m3];
            let widest = (0..3).map(|k| e.coulomb_friction_nm[k] / (j[k] * MAX_FRICTION_RATE)).fold(0.0, f64::max);
            e.friction_smoothing_radps = self.smoothing.max(widest);
        }
        TorsionalModel { rig, variant: self.variant, effects: e }
    }
}

/// Where friction acts: one machine of the rig, or both load machines (a rig's load machines
/// are alike: one step of the selection with a friction each).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Machine {
    /// Load machine M2 (short side shaft).
    M2,
    /// The drive (its motor when the drive is compliant).
    Drive,
    /// Load machine M3 (long side shaft).
    M3,
    /// Both load machines, each its own friction.
    Loads,
}

impl Machine {
    /// The indices in [`DriveEffects::coulomb_friction_nm`] it sets.
    pub fn indices(self) -> &'static [usize] {
        match self {
            Machine::M2 => &[0],
            Machine::Drive => &[1],
            Machine::M3 => &[2],
            Machine::Loads => &[0, 2],
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Machine::M2 => "M2",
            Machine::Drive => "drive",
            Machine::M3 => "M3",
            Machine::Loads => "M2 and M3",
        }
    }
}

/// Name of friction index `k` in reports.
const MACHINE_NAMES: [&str; 3] = ["M2", "drive", "M3"];

/// What a candidate adds to the declared model (the declared j_drive and c_short are re-fitted
/// beside it, and beside every effect found before it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Candidate {
    /// The side shafts' damping (as a damping ratio of the shuffle).
    ShaftDamping,
    /// A dead time of the drive torque.
    TimeDelay,
    /// A first-order lag of the drive torque.
    ActuatorLag,
    /// Play in the side shafts.
    Backlash,
    /// A compliance inside the drive (motor and cage).
    DriveCompliance,
    /// Coulomb friction at a machine.
    CoulombFriction(Machine),
}

impl Candidate {
    /// Every candidate.
    pub const ALL: [Candidate; 9] = [
        Candidate::ShaftDamping,
        Candidate::TimeDelay,
        Candidate::ActuatorLag,
        Candidate::Backlash,
        Candidate::DriveCompliance,
        Candidate::CoulombFriction(Machine::M2),
        Candidate::CoulombFriction(Machine::Drive),
        Candidate::CoulombFriction(Machine::M3),
        Candidate::CoulombFriction(Machine::Loads),
    ];

    /// The vocabulary name.
    pub fn name(self) -> &'static str {
        match self {
            Candidate::ShaftDamping => "shaft_damping",
            Candidate::TimeDelay => "time_delay",
            Candidate::ActuatorLag => "actuator_lag",
            Candidate::Backlash => "backlash",
            Candidate::DriveCompliance => "drive_compliance",
            Candidate::CoulombFriction(_) => "coulomb_friction",
        }
    }

    /// Where it acts, for effects at a machine.
    pub fn at(self) -> Option<String> {
        match self {
            Candidate::CoulombFriction(m) => Some(m.name().to_string()),
            _ => None,
        }
    }

    /// Its effects, each with where it acts ([`CandidateScore::parts`]): a friction at both load
    /// machines is a friction at each (each its own), so it contains one at either.
    fn parts(self) -> Vec<(String, String)> {
        match self {
            Candidate::CoulombFriction(m) => {
                m.indices().iter().map(|&k| (self.name().to_string(), MACHINE_NAMES[k].to_string())).collect()
            }
            _ => vec![(self.name().to_string(), String::new())],
        }
    }

    /// What it may change of the declared mechanics: a compliance splits j_drive and puts a
    /// spring in series with the side shafts; the others, as their effects state, nothing
    /// (damping changes no stiffness).
    pub fn moves(self) -> Moves {
        use plant::drive::EffectModel;
        match self {
            Candidate::DriveCompliance => Moves::SeriesSpring,
            Candidate::TimeDelay => plant::drive::TimeDelay::MOVES,
            Candidate::ActuatorLag => plant::drive::ActuatorLag::MOVES,
            Candidate::Backlash => plant::drive::Backlash::MOVES,
            Candidate::CoulombFriction(_) => plant::drive::CoulombFriction::MOVES,
            Candidate::ShaftDamping => Moves::Nothing,
        }
    }

    /// Indices into its starts ([`Candidate::starts`]) worth refining, given their `costs`: the
    /// best of each basin of its grid — per motor share for the compliance
    /// ([`best_per_share`]), the [`BACKLASH_REFINED`] deepest local minima of the play's
    /// profile, every local minimum of the others' few decades.
    fn basins(self, costs: &[f64]) -> Vec<usize> {
        match self {
            Candidate::DriveCompliance => best_per_share(costs),
            Candidate::Backlash => {
                let mut minima = super::local_minima(costs);
                minima.truncate(BACKLASH_REFINED);
                minima
            }
            _ => super::local_minima(costs),
        }
    }

    /// Number of its own parameters.
    fn own_len(self) -> usize {
        match self {
            Candidate::DriveCompliance => 2,
            Candidate::CoulombFriction(m) => m.indices().len(),
            _ => 1,
        }
    }

    /// Whether it sets what `other` sets (friction at a machine twice).
    fn overlaps(self, other: Candidate) -> bool {
        match (self, other) {
            (Candidate::CoulombFriction(a), Candidate::CoulombFriction(b)) => {
                a.indices().iter().any(|i| b.indices().contains(i))
            }
            _ => self == other,
        }
    }

    /// The candidates tried in its place once the selection has ended (the swap step): those
    /// that imitate it in a fit — a dead time and a lag (both a phase lag of the drive torque
    /// growing with frequency), friction at another machine — and the compliance itself,
    /// re-seated from its grid beside the effects found after it (its valleys are narrow in
    /// frequency, and those effects move them).
    fn alternatives(self) -> Vec<Candidate> {
        match self {
            Candidate::TimeDelay => vec![Candidate::ActuatorLag],
            Candidate::ActuatorLag => vec![Candidate::TimeDelay],
            Candidate::DriveCompliance => vec![Candidate::DriveCompliance],
            Candidate::CoulombFriction(m) => [Machine::M2, Machine::Drive, Machine::M3, Machine::Loads]
                .into_iter()
                .filter(|&o| o != m)
                .map(Candidate::CoulombFriction)
                .collect(),
            Candidate::ShaftDamping | Candidate::Backlash => Vec::new(),
        }
    }

    /// Adds it to a model: `own` its parameters (log space; the compliance's motor share as a
    /// logit).
    fn apply(self, rig: &mut RigParams, e: &mut DriveEffects, own: &[f64], variant: Variant) {
        let v = own[0].exp();
        match self {
            Candidate::ShaftDamping => {
                if let Ok(r) = rig.with_shaft_damping_ratio(v, variant) {
                    *rig = r;
                }
            }
            Candidate::TimeDelay => e.time_delay_s = v,
            Candidate::ActuatorLag => e.actuator_lag_s = v,
            Candidate::Backlash => e.backlash_rad = v,
            Candidate::DriveCompliance => {
                e.compliance_stiffness_nm_per_rad = v;
                e.compliance_motor_fraction = 1.0 / (1.0 + (-own[1]).exp());
            }
            Candidate::CoulombFriction(m) => {
                for (&k, p) in m.indices().iter().zip(own) {
                    e.coulomb_friction_nm[k] = p.exp();
                }
            }
        }
    }

    /// Its parameters in a fitted model, SI, keys with units.
    fn report(self, m: &TorsionalModel) -> BTreeMap<String, f64> {
        let mut b = BTreeMap::new();
        match self {
            Candidate::ShaftDamping => {
                let z = m.rig.effective(m.variant).ok().map(|e| {
                    let cs = e.c_left * e.c_right / (e.c_left + e.c_right);
                    let w = (cs * (1.0 / e.j_m2 + 4.0 / e.j_drive + 1.0 / e.j_m3)).sqrt();
                    0.5 * w * e.d_left / e.c_left
                });
                b.insert("damping_ratio".into(), z.unwrap_or(f64::NAN));
            }
            Candidate::TimeDelay => {
                b.insert("delay_s".into(), m.effects.time_delay_s);
            }
            Candidate::ActuatorLag => {
                b.insert("time_constant_s".into(), m.effects.actuator_lag_s);
            }
            Candidate::Backlash => {
                b.insert("backlash_rad".into(), m.effects.backlash_rad);
            }
            Candidate::DriveCompliance => {
                b.insert("stiffness_Nm_per_rad".into(), m.effects.compliance_stiffness_nm_per_rad);
                b.insert("frequency_hz".into(), m.upper_mode_hz());
                b.insert("motor_fraction".into(), m.effects.compliance_motor_fraction);
            }
            Candidate::CoulombFriction(machine) => {
                if let [k] = machine.indices() {
                    b.insert("friction_Nm".into(), m.effects.coulomb_friction_nm[*k]);
                } else {
                    for &k in machine.indices() {
                        b.insert(format!("friction_{}_Nm", MACHINE_NAMES[k]), m.effects.coulomb_friction_nm[k]);
                    }
                }
                b.insert("smoothing_speed_radps".into(), m.effects.friction_smoothing_radps);
            }
        }
        b
    }

    /// Starting values of its own parameters (log space) for a grid search: a profile for the
    /// play, a grid over the compliance's frequency and share, a few decades otherwise.
    fn starts(self, p: &Problem, shuffle_hz: f64) -> Vec<Vec<f64>> {
        let ln = f64::ln;
        match self {
            Candidate::ShaftDamping => [0.005, 0.02, 0.05, 0.15].iter().map(|&z| vec![ln(z)]).collect(),
            Candidate::TimeDelay | Candidate::ActuatorLag => {
                [0.001, 0.003, 0.01, 0.03].iter().map(|&t| vec![ln(t)]).collect()
            }
            // the error over the play is rough (contact comes and goes) with narrow basins: a
            // profile on a grid of BACKLASH_GRID_RATIO steps over four and a half decades
            Candidate::Backlash => {
                let steps = (BACKLASH_MAX_RAD / BACKLASH_MIN_RAD).ln() / BACKLASH_GRID_RATIO.ln();
                (0..=steps.ceil() as i32).map(|i| vec![ln(BACKLASH_MIN_RAD * BACKLASH_GRID_RATIO.powi(i))]).collect()
            }
            // stiffness placing the uncoupled motor-cage mode at 1.2 to 8 times the shuffle,
            // motor shares 0.3, 0.5, 0.7: the fit's valleys are narrow in frequency
            Candidate::DriveCompliance => (0..COMPLIANCE_GRID_STEPS)
                .flat_map(|i| {
                    let r = 1.2 * (8.0f64 / 1.2).powf(i as f64 / (COMPLIANCE_GRID_STEPS - 1) as f64);
                    COMPLIANCE_GRID_SHARES.map(move |f| (r, f))
                })
                .map(|(r, f)| {
                    let w = 2.0 * std::f64::consts::PI * shuffle_hz * r;
                    let k = w * w * p.declared.j_drive * f * (1.0 - f);
                    vec![ln(k), (f / (1.0 - f)).ln()]
                })
                .collect(),
            // the same share of the torque's variation at each machine it acts at
            Candidate::CoulombFriction(m) => [0.02, 0.05, 0.1, 0.2, 0.5]
                .iter()
                .map(|&f| vec![ln(f * p.torque_amplitude); m.indices().len()])
                .collect(),
        }
    }
}

/// The highest mode a compliance may put in the rig, a share of the sampling rate (a tenth:
/// the search stays where the models are meaningful and the matrix exponential cheap).
pub const COMPLIANCE_TOP_PER_SAMPLE_RATE: f64 = 0.1;

/// Steps of the compliance's grid of uncoupled motor-cage frequencies, 1.2 to 8 times the
/// declared shuffle frequency.
pub const COMPLIANCE_GRID_STEPS: usize = 12;
/// Motor shares of the compliance's grid.
pub const COMPLIANCE_GRID_SHARES: [f64; 3] = [0.3, 0.5, 0.7];

/// Indices into the compliance's starts (frequency-major: [`COMPLIANCE_GRID_STEPS`] ×
/// `COMPLIANCE_GRID_SHARES`) worth refining, given their `costs`: per motor share, its lowest
/// finite point along the frequency.
fn best_per_share(costs: &[f64]) -> Vec<usize> {
    let shares = COMPLIANCE_GRID_SHARES.len();
    (0..shares)
        .filter_map(|s| {
            (s..costs.len())
                .step_by(shares)
                .filter(|&i| costs[i].is_finite())
                .min_by(|&a, &b| costs[a].total_cmp(&costs[b]))
        })
        .collect()
}

/// Two fits whose BIC differ by at most this fit a record equally well (Kass & Raftery 1995:
/// a difference below 2 is "not worth more than a bare mention").
pub const EQUIVALENT_BIC: f64 = 2.0;
/// Two fits' compliance stiffnesses this far apart (ln: 25 %) are different solutions.
pub const EQUIVALENT_APART_LN: f64 = 0.223_143_551_314_209_7;
/// Two fits' motor shares this far apart are different solutions.
pub const EQUIVALENT_APART_SHARE: f64 = 0.1;

/// The logistic function, 1/(1 + e^−v) (the compliance's motor share from its logit).
fn logistic(v: f64) -> f64 {
    1.0 / (1.0 + (-v).exp())
}

/// Lowest high-pass corner, Hz.
pub const HIGH_PASS_MIN_HZ: f64 = 0.05;

/// The high-pass corner for a record of `n` samples of `dt_s`, Hz.
pub fn high_pass_hz(n: usize, dt_s: f64) -> f64 {
    super::high_pass_corner_hz(n, dt_s, HIGH_PASS_MIN_HZ)
}

/// Smallest play of the backlash profile, rad.
pub const BACKLASH_MIN_RAD: f64 = 2e-5;
/// Largest play of the backlash profile, rad.
pub const BACKLASH_MAX_RAD: f64 = 0.05;
/// Ratio of neighbouring plays of the coarse profile (10 % apart): it finds the basins' region;
/// each of the best is then refined on a grid of [`BACKLASH_FINE_STEPS`].
pub const BACKLASH_GRID_RATIO: f64 = 1.1;
/// The play's profile beside effects found before is also taken from the declared j_drive and
/// c_short when theirs moved by more than this (ln): 1 %, far beyond what a profile point
/// resolves.
pub const PROFILE_BENT_LN: f64 = 0.01;
/// The profile's best points (in distinct basins) refined by the full fit.
pub const BACKLASH_REFINED: usize = 2;
/// Steps of the fine grid across one coarse step of the play's profile, either side of a
/// basin (1 % steps: the error over the play of a rattling rig changes within a few per cent,
/// and a fit cannot climb out of a wrong basin).
pub const BACKLASH_FINE_STEPS: usize = 10;

/// Fastest rate the friction's slope T_c/(v_s J) may have, 1/s: what RK4 steps of 0.25 ms
/// (`plant::Dynamics::paper_rig`: h·rate ≤ 0.5) resolve, four per millisecond.
pub const MAX_FRICTION_RATE: f64 = 0.5 / (2.0 * plant::preset::BACKLASH_STEP_S);

/// Most RK4 steps per sample within a smooth piece of a candidate with play or friction: a
/// model needing more has a time scale below an eighth of the sample time (a lag, an overdamped
/// pole) that the record cannot show, and is not simulated.
pub const MAX_STEPS_PER_SAMPLE: usize = 8;

/// A residual whose lag-1 autocorrelation is below this is white enough that no candidate can
/// beat the model clearly, and the selection stops. The residual is structured error s (the
/// modelled dynamics: below a tenth of the sampling rate, where the compliance's mode is held,
/// so its lag-1 autocorrelation is at least cos(2π·0.1)) plus white noise; its lag-1
/// autocorrelation ρ is then at least cos(2π·0.1) times the structured share of its energy.
/// Beating the model asks 10 % less error, 19 % less energy (1 − 0.9²), which even a candidate
/// explaining all of s cannot reach where ρ < 0.19 cos(2π·0.1) = 0.154. Coloured sensor noise
/// raises ρ and only keeps the selection going.
pub const WHITE_RESIDUAL_LAG1: f64 = 0.19 * 0.809_016_994_374_947_5;

/// Length of the frames of the phase-free fit's short-time spectra, s (a power of two of
/// samples near it): about 2 Hz lines, fine enough for the rig's modes, short enough to follow
/// a sweep.
///
/// With play the error over the parameters is a train of narrow notches, not a basin: the
/// impacts' timing decides the phase of everything after them, and a stiffness 8 % off can
/// raise the error from 0.02 to 0.4 where 2 % off gives 0.05–0.09 (the held-out compliance + play
/// record of `tests/diagnose_several.rs`). The magnitudes of short-time spectra keep where and
/// how strongly the rig responds and drop the phase; over the same parameters they fall
/// smoothly to the truth (0.22, 0.14, 0.12, 0.06, 0.011 for stiffness 20, 12, 8, 4, 0 % low).
/// So a model with play is polished also from a fit to them (a start for the fit to the
/// speeds, which then decides).
pub const PHASE_FREE_WINDOW_S: f64 = 0.5;

/// Most effects the forward selection adds.
pub const MAX_EFFECTS: usize = 3;

/// Levenberg–Marquardt iterations of a fit (the re-fitted declared model, the polish of an
/// accepted model, the leave-one-out checks).
pub const LM_ITERATIONS: usize = 12;
/// Levenberg–Marquardt iterations of the re-fitted declared model (`none`), the model every
/// candidate must beat: fitted to its minimum (it stops earlier when a step gains less than
/// [`LM_REL_TOL`]). Its two parameters' valley can be long and curved: the declared model of a
/// play record needs 24 steps to reach the cost scipy's `least_squares` reaches
/// (`scripts/refit_check.py`), where [`LM_ITERATIONS`] left it at twice that cost.
pub const DECLARED_REFIT_ITERATIONS: usize = 60;
/// Levenberg–Marquardt iterations of a candidate's fit in a round of the selection: enough to
/// rank the candidates (their starts come from a grid); the accepted one is then polished with
/// [`LM_ITERATIONS`].
pub const SCREEN_ITERATIONS: usize = 6;

/// A found effect.
#[derive(Debug, Clone, Serialize)]
pub struct FoundEffect {
    /// Its name.
    pub effect: String,
    /// The machine it acts at, if at one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<String>,
    /// Its parameters in the final model.
    pub parameters: BTreeMap<String, f64>,
    /// 95 % intervals of its parameters over the held-out folds.
    pub intervals: BTreeMap<String, [f64; 2]>,
    /// The answer's error with this effect left out and the others re-fitted (the declared
    /// model re-fitted for a single effect): what the effect explains.
    pub error_without: f64,
    /// Its parameters the record does not determine ([`super::not_determined`]): with one, the
    /// effect is no finding ([`super::sizes_not_determined`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub not_determined: Vec<String>,
}

impl FoundEffect {
    /// An effect found with its `parameters` and their `intervals`, judged by
    /// [`super::HeldOutSettings`]' defaults for what the record does not determine.
    pub(crate) fn new(
        effect: String,
        at: Option<String>,
        parameters: BTreeMap<String, f64>,
        intervals: BTreeMap<String, [f64; 2]>,
        error_without: f64,
    ) -> FoundEffect {
        let not_determined = super::not_determined(&parameters, &intervals, &super::HeldOutSettings::default());
        FoundEffect { effect, at, parameters, intervals, error_without, not_determined }
    }
}

/// One step of the forward selection.
#[derive(Debug, Clone, Serialize)]
pub struct PathStep {
    /// The effects of the model at this step, in the order found.
    pub effects: Vec<String>,
    /// Its normalised error.
    pub error: f64,
    /// Its score (BIC).
    pub score: f64,
}

/// A fitted model: its effects, parameter vector, cost and score.
#[derive(Debug, Clone)]
struct Fit {
    effects: Vec<Candidate>,
    x: Vec<f64>,
    cost: f64,
    score: f64,
}

impl Fit {
    fn error(&self) -> f64 {
        self.cost.sqrt()
    }

    /// This fit as a step of the selection's path.
    fn step(&self) -> PathStep {
        PathStep { effects: self.effects.iter().map(|c| label(*c)).collect(), error: self.error(), score: self.score }
    }

    /// This fit with its effects (and their parameters) in `order` (indices of its effects).
    fn reordered(&self, order: &[usize]) -> Fit {
        let mut at = vec![2];
        for c in &self.effects {
            at.push(at.last().expect("not empty") + c.own_len());
        }
        let mut x = self.x[..2].to_vec();
        for &k in order {
            x.extend_from_slice(&self.x[at[k]..at[k + 1]]);
        }
        Fit { effects: order.iter().map(|&k| self.effects[k]).collect(), x, ..self.clone() }
    }

    /// This fit without its `i`-th effect (its parameters dropped, the others as fitted; cost
    /// and score unknown).
    fn without(&self, i: usize) -> Fit {
        let order: Vec<usize> = (0..self.effects.len()).filter(|&k| k != i).collect();
        Fit { cost: f64::NAN, score: f64::NAN, ..self.reordered(&order) }
    }

    /// Whether this fit beats `other` clearly ([`super::clearly_beats`]: strong evidence and 10 % less error).
    fn beats(&self, other: &Fit) -> bool {
        super::clearly_beats(self.score, self.error(), other.score, (other.score, other.error()))
    }
}

/// Diagnoses `sweep` against the declared `rig` in `variant` by forward selection: every
/// candidate is fitted beside the effects found so far (all parameters re-fitted), the one that
/// improves the information criterion most (and the error by 10 %) is added, until none does;
/// then each kept effect is checked by leaving it out. `progress` is told each candidate's
/// name as it finishes.
pub fn diagnose(
    sweep: &Sweep,
    rig: &RigParams,
    variant: Variant,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<TorsionalDiagnosis> {
    let n = sweep.torque_nm.len();
    if n < 1000 || sweep.speed_m2_radps.len() != n || sweep.speed_m3_radps.len() != n {
        return Err(IdentError::Data(format!("a sweep of {n} samples is too short to diagnose (need 1000)")));
    }
    let dt = sweep.dt_s;
    let high_pass = high_pass_hz(n, dt);
    let measured = [
        filtfilt_high_pass(&sweep.speed_m2_radps, dt, high_pass),
        filtfilt_high_pass(&sweep.speed_m3_radps, dt, high_pass),
    ];
    let norm = measured.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    if norm.is_nan() || norm <= 0.0 {
        return Err(IdentError::Data("the load-machine speeds do not oscillate: nothing to compare".into()));
    }
    let torque_hp = filtfilt_high_pass(&sweep.torque_nm, dt, high_pass);
    let torque_amplitude = (2.0 * torque_hp.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    if torque_amplitude.is_nan() || torque_amplitude <= 0.0 {
        return Err(IdentError::Data("the drive torque does not vary: nothing excites the rig".into()));
    }
    drop(torque_hp);
    let smoothing =
        (FRICTION_SMOOTHING_FRACTION * 0.5 * (rms(&sweep.speed_m2_radps) + rms(&sweep.speed_m3_radps))).max(1e-6);
    let speed0 = 0.5 * (sweep.speed_m2_radps[0] + sweep.speed_m3_radps[0]);
    // frames of about PHASE_FREE_WINDOW_S (a power of two of samples, at most a quarter of the
    // record), lines up to a tenth of the sampling rate (where the compliance's mode is held)
    let window = ((PHASE_FREE_WINDOW_S / dt).max(4.0) as usize).next_power_of_two().min(1 << (n / 4).max(1).ilog2());
    let spectrogram = Spectrogram::new(window, (0.1 * window as f64) as usize);
    let mut measured_spectra = Vec::new();
    spectrogram.magnitudes(&measured[0], &mut measured_spectra);
    spectrogram.magnitudes(&measured[1], &mut measured_spectra);
    let spectra_norm = measured_spectra.iter().map(|v| v * v).sum::<f64>().sqrt();
    let spectra_norm = if spectra_norm.is_finite() { spectra_norm } else { 0.0 };
    let shafts = rig.effective(variant).map_err(|e| IdentError::Data(format!("the declared model: {e}")))?;
    let mut problem = Problem {
        sweep,
        declared: rig.clone(),
        variant,
        c_s: shafts.c_left * shafts.c_right / (shafts.c_left + shafts.c_right),
        n_eff: f64::NAN,
        speed0,
        measured,
        norm,
        high_pass_hz: high_pass,
        torque_amplitude,
        smoothing,
        spectrogram,
        measured_spectra,
        spectra_norm,
    };
    let declared = TorsionalModel { rig: rig.clone(), variant, effects: DriveEffects::default() };
    let sim0 = problem
        .simulate(&declared)
        .ok_or_else(|| IdentError::Data("the declared model cannot be simulated (check its parameters)".into()))?;
    let r0 = problem.residual_of(&sim0);
    let error_before = r0.iter().map(|v| v * v).sum::<f64>().sqrt();
    let evidence = evidence(&problem, &r0);
    let declared_model = DriveModel::paper_rig(rig, variant, &DriveEffects::default())
        .map_err(|e| IdentError::Data(format!("the declared model: {e}")))?;
    let shuffle_hz = Some(highest_mode_hz(&declared_model)).filter(|f| f.is_finite()).unwrap_or(10.0);
    // One effective count for all (the declared model's residual), so the scores compare.
    let nres = 2 * n;
    let n_eff = effective_count(nres, evidence.residual_lag1.max(lag1_autocorrelation(&r0)));
    problem.n_eff = n_eff;
    drop(r0);
    let score = |cost: f64, k: usize| bic(cost * norm * norm, nres, n_eff, k);

    // What the data can show. Play only shows where a side shaft's torque changes sign — at
    // resonance that happens well away from zero drive torque — so the declared model's shaft
    // torque decides (with the measured torque's variation as margin for its error); friction
    // shows only where a machine's speed reverses.
    let shaft = Dynamics::paper_rig(&declared_model)
        .and_then(|d| {
            plant::simulate_record(&declared_model, &d, &sweep.torque_nm, dt, speed0, &[(Quantity::CouplingForce, 0)])
        })
        .map_err(|e| IdentError::Data(format!("the declared model: {e}")))?
        .swap_remove(0);
    let crosses = |v: &[f64]| v.iter().any(|&x| x > 0.0) && v.iter().any(|&x| x < 0.0);
    let backlash_excitable = crosses(&shaft);
    drop(shaft);
    let mean_speed: Vec<f64> =
        sweep.speed_m2_radps.iter().zip(&sweep.speed_m3_radps).map(|(a, b)| 0.5 * (a + b)).collect();
    let reverses = [crosses(&sweep.speed_m2_radps), crosses(&mean_speed), crosses(&sweep.speed_m3_radps)];
    drop(mean_speed);
    let excitable = |c: Candidate| match c {
        Candidate::Backlash => backlash_excitable,
        Candidate::CoulombFriction(m) => m.indices().iter().all(|&k| reverses[k]),
        _ => true,
    };

    let fit_with = |effects: Vec<Candidate>, x0: Vec<f64>, iterations: usize| -> Fit {
        let f = |x: &[f64]| problem.residual(&problem.build(&effects, x));
        let (x, cost) = lm::minimise(&f, &x0, lm::Fit::new(iterations, LM_REL_TOL));
        let k = x.len();
        Fit { effects, x, cost, score: score(cost, k) }
    };
    // Where `base` is an implausible single effect (it bent j_drive or c_short to imitate what
    // it lacks), that effect re-seated with the declared j_drive and c_short: its value was
    // fitted without the candidate that explains the rest. It is re-seated at the basins of its
    // own grid there ([`Candidate::basins`] of its starts alone, one per motor share for a
    // compliance): a candidate beside it changes how deep its valleys are, not where the record
    // puts them, and crossing every start with every start of the candidate's grid (a play's
    // profile beside a compliance's 36 starts) is most of a pair's run time. A basin where the
    // effect alone errs no less than the declared model as declared is no seat of it: there it
    // explains nothing of the record, and the fits beside it ended where they would have started
    // from the declared model. Empty otherwise.
    let declared_cost = error_before * error_before;
    let reseated_at = |base: &Fit| -> Vec<Vec<f64>> {
        let [own] = base.effects[..] else { return Vec::new() };
        if problem.plausible(base) {
            return Vec::new();
        }
        let points: Vec<Vec<f64>> = own
            .starts(&problem, shuffle_hz)
            .into_iter()
            .map(|s| {
                let mut x = base.x.clone();
                x[..2].fill(0.0);
                x[2..2 + s.len()].copy_from_slice(&s);
                x
            })
            .collect();
        let costs = super::on_two_workers(points.len(), &|i| {
            problem
                .residual(&problem.build(&[own], &points[i]))
                .map_or(f64::INFINITY, |r| r.iter().map(|v| v * v).sum())
        });
        own.basins(&costs).into_iter().filter(|&i| costs[i] < declared_cost).map(|i| points[i].clone()).collect()
    };
    // `base` plus candidate `c`: its starts on a grid (the others at base's values), the best
    // (for the play: the best of distinct basins of its profile) refined by a fit of all;
    // `reseated` the re-seatings of base's effect ([`reseated_at`]).
    let extend = |base: &Fit, c: Candidate, reseated: &[Vec<f64>]| -> Fit {
        let mut effects = base.effects.clone();
        effects.push(c);
        let f = |x: &[f64]| problem.residual(&problem.build(&effects, x));
        // beside the effects found so far at their fitted values; the first effect from the
        // declared j_drive and c_short (the re-fitted `none` may have bent them to imitate the
        // very effect); the play's profile beside an effect also from the declared j_drive and
        // c_short (the effects found may have bent them to imitate the play), and beside an
        // implausible model (one followed a round ahead) also from the declared ones — unless
        // its effect is re-seated there (`reseated`: the same base at the declared mechanics,
        // its effect at the basins of its own grid rather than where the bent fit left it)
        let mut bases: Vec<Vec<f64>> = Vec::new();
        let bent = base.x[..2].iter().any(|v| v.abs() > PROFILE_BENT_LN);
        let implausible_unseated = !problem.plausible(base) && reseated.is_empty();
        if base.effects.is_empty() || (c == Candidate::Backlash && bent) || implausible_unseated {
            let mut x = base.x.clone();
            x[..2].fill(0.0);
            bases.push(x);
        }
        if !base.effects.is_empty() {
            bases.push(base.x.clone());
        }
        // beside base's effect re-seated at its basins ([`reseated_at`])
        bases.extend_from_slice(reseated);
        let starts = c.starts(&problem, shuffle_hz);
        let points: Vec<Vec<f64>> =
            bases.iter().flat_map(|b| starts.iter().map(move |s| [b.as_slice(), s].concat())).collect();
        // a long grid (the play's profile) is shared by both workers: the cheap linear
        // candidates are done long before it; a short one where a core is idle
        let cost_at = |i: usize| f(&points[i]).map_or(f64::INFINITY, |r| r.iter().map(|v| v * v).sum::<f64>());
        let costs: Vec<f64> = if points.len() > 20 || super::spare_core() {
            super::on_two_workers(points.len(), &cost_at)
        } else {
            (0..points.len()).map(cost_at).collect()
        };
        let grid: Vec<(Vec<f64>, f64)> = points.into_iter().zip(costs).collect();
        let mut best: Vec<usize> = if c == Candidate::Backlash {
            // the basins of each profile ([`Candidate::basins`]), the deepest first
            let len = starts.len();
            let costs: Vec<f64> = grid.iter().map(|g| g.1).collect();
            let mut minima: Vec<usize> = costs
                .chunks(len)
                .enumerate()
                .flat_map(|(b, profile)| c.basins(profile).into_iter().map(move |k| b * len + k))
                .collect();
            minima.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]));
            minima.truncate(BACKLASH_REFINED);
            minima
        } else {
            // the best start beside each base (the re-seatings are its effect's basins already)
            (0..bases.len())
                .filter_map(|b| {
                    (b * starts.len()..(b + 1) * starts.len())
                        .filter(|&i| grid[i].1.is_finite())
                        .min_by(|&a, &b| grid[a].1.total_cmp(&grid[b].1))
                })
                .collect()
        };
        best.dedup();
        let mut chosen: Vec<Vec<f64>> = best.iter().map(|&i| grid[i].0.clone()).collect();
        if c == Candidate::Backlash {
            // each basin refined on a grid ten times finer across a coarse step either side:
            // the basins are narrower than the coarse step (the error over a play of a rattling
            // rig changes within a few per cent), and the fit cannot climb out of a wrong one
            let fine: Vec<(usize, Vec<f64>)> = chosen
                .iter()
                .enumerate()
                .flat_map(|(m, x)| {
                    (-(BACKLASH_FINE_STEPS as i32)..=BACKLASH_FINE_STEPS as i32).filter(|&j| j != 0).map(move |j| {
                        let mut x = x.clone();
                        let last = x.len() - 1;
                        x[last] += j as f64 * BACKLASH_GRID_RATIO.ln() / BACKLASH_FINE_STEPS as f64;
                        (m, x)
                    })
                })
                .collect();
            let costs = super::on_two_workers(fine.len(), &|i| {
                f(&fine[i].1).map_or(f64::INFINITY, |r| r.iter().map(|v| v * v).sum::<f64>())
            });
            for (m, x) in chosen.iter_mut().enumerate() {
                let mut lowest = grid[best[m]].1;
                for ((owner, candidate), cost) in fine.iter().zip(&costs) {
                    if *owner == m && *cost < lowest {
                        lowest = *cost;
                        *x = candidate.clone();
                    }
                }
            }
        }
        let fits =
            super::on_two_workers(chosen.len(), &|k| fit_with(effects.clone(), chosen[k].clone(), SCREEN_ITERATIONS));
        let best = fits.into_iter().min_by(|a, b| a.cost.total_cmp(&b.cost)).unwrap_or(Fit {
            effects: effects.clone(),
            x: Vec::new(),
            cost: f64::INFINITY,
            score: f64::INFINITY,
        });
        // a compliance trades its spring against the shafts it is in series with (the pair is
        // what the declared c_short measured): its fit with them free may end in a valley of
        // its own beside the one at the declared mechanics, so both are fitted and the lower
        // kept
        let trades = effects.iter().any(|c| c.moves() == Moves::SeriesSpring);
        if !best.cost.is_finite() {
            return best;
        }
        // judged once: for a compliance, plausibility simulates its mode moved
        let best_plausible = problem.plausible(&best);
        if best_plausible && !trades {
            return best;
        }
        // The fit bent j_drive or c_short beyond the plausible factor (or, for a compliance,
        // may have found the valley of its own): the candidate is fitted again with them held
        // at their declared values, from the best grid point beside them.
        // Two effects that share a mode (damping and a compliance) can often explain a record
        // either way; the declared mechanics are kept unless bending them is clearly better.
        let Some(start) = grid
            .iter()
            .filter(|(x, cost)| cost.is_finite() && x[..2] == [0.0, 0.0])
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(x, _)| x[2..].to_vec())
        else {
            return best;
        };
        let held = |y: &[f64]| problem.residual(&problem.build(&effects, &[&[0.0, 0.0], y].concat()));
        let (y, cost) = lm::minimise(&held, &start, lm::Fit::new(LM_ITERATIONS, LM_REL_TOL));
        let pinned =
            Fit { effects: effects.clone(), x: [vec![0.0, 0.0], y].concat(), cost, score: score(cost, start.len()) };
        if best_plausible {
            // the compliance's other valley: from its fit at the declared mechanics, with them
            // free again; the lowest plausible of the three
            let released = fit_with(effects.clone(), pinned.x.clone(), LM_ITERATIONS);
            return [pinned, released]
                .into_iter()
                .filter(|f| f.cost.is_finite() && problem.plausible(f))
                .fold(best, |a, b| if b.cost < a.cost { b } else { a });
        }
        if pinned.cost.is_finite() && !best.beats(&pinned) {
            pinned
        } else {
            best
        }
    };

    // with play, a fit continued from a fit to the short-time spectra (the phase-free fit,
    // [`PHASE_FREE_WINDOW_S`]): where the speeds' error is a train of notches, theirs leads
    // into the right one
    let phase_free = |effects: &[Candidate]| effects.contains(&Candidate::Backlash) && problem.spectra_norm > 0.0;
    let phase_free_fit = |effects: &[Candidate], x0: &[f64]| -> Fit {
        let spectral = |x: &[f64]| problem.spectral_residual(&problem.build(effects, x));
        let (located, cost) = lm::minimise(&spectral, x0, lm::Fit::new(LM_ITERATIONS, LM_REL_TOL));
        if cost.is_finite() {
            fit_with(effects.to_vec(), located, LM_ITERATIONS)
        } else {
            Fit { effects: effects.to_vec(), x: located, cost: f64::INFINITY, score: f64::INFINITY }
        }
    };
    // the accepted model polished: its fit continued, one restarted from the declared j_drive
    // and c_short (those of the model before may have been bent to imitate the effect just
    // found), and the phase-free fit; the lowest plausible kept (the lowest if none is)
    let polish = |b: Fit| -> Fit {
        let mut restart = b.x.clone();
        restart[..2].fill(0.0);
        // a fit already at the declared values (a pinned one) is only continued: the restart
        // would repeat it
        let starts = if restart == b.x { vec![restart] } else { vec![b.x.clone(), restart] };
        let jobs = starts.len() + usize::from(phase_free(&b.effects));
        let polished = super::on_two_workers(jobs, &|i| match starts.get(i) {
            Some(start) => fit_with(b.effects.clone(), start.clone(), LM_ITERATIONS),
            None => phase_free_fit(&b.effects, &b.x),
        });
        let fits: Vec<Fit> = polished.into_iter().filter(|f| f.cost.is_finite()).chain(std::iter::once(b)).collect();
        let lowest = |plausible: bool| {
            fits.iter().filter(|f| !plausible || problem.plausible(f)).min_by(|a, b| a.cost.total_cmp(&b.cost)).cloned()
        };
        lowest(true).or_else(|| lowest(false)).expect("the accepted fit is there")
    };
    // one round of the selection: every excitable candidate that sets nothing `base` sets,
    // fitted beside it
    let round = |base: &Fit| -> Vec<Fit> {
        let todo: Vec<Candidate> = Candidate::ALL
            .into_iter()
            .filter(|c| !base.effects.iter().any(|f| f.overlaps(*c)) && excitable(*c))
            .collect();
        // the costliest first (the play's profile, then the frictions: nonlinear simulations),
        // so that the two workers finish together
        let mut order: Vec<usize> = (0..todo.len()).collect();
        order.sort_by_key(|&i| match todo[i] {
            Candidate::Backlash => 0,
            Candidate::CoulombFriction(_) => 1,
            _ => 2,
        });
        let reseated = reseated_at(base);
        let fits = super::on_two_workers(todo.len(), &|k| {
            let fit = extend(base, todo[order[k]], &reseated);
            if base.effects.is_empty() {
                progress(todo[order[k]].name());
            }
            fit
        });
        // back in the vocabulary's order
        let mut fits: Vec<(usize, Fit)> = order.into_iter().zip(fits).collect();
        fits.sort_by_key(|f| f.0);
        fits.into_iter().map(|f| f.1).collect()
    };
    // the best fit of `fits` (plausible or not) that beats `base` clearly
    let best_beating = |fits: &[Fit], base: &Fit, plausible: bool| -> Option<Fit> {
        fits.iter()
            .filter(|f| f.cost.is_finite() && problem.plausible(f) == plausible && f.beats(base))
            .min_by(|a, b| a.score.total_cmp(&b.score))
            .cloned()
    };
    // each kept effect checked by leaving it out: one that the others do not need clearly
    // (the full model does not beat the model without it) goes, the least needed first.
    // Returns the models on the way and, for the model it ends at, each model without one of
    // its effects (re-fitted; none for a single effect).
    // `fit` without each of its effects in turn, re-fitted from its values
    let each_left_out = |fit: &Fit| -> Vec<Fit> {
        super::on_two_workers(fit.effects.len(), &|i| {
            let w = fit.without(i);
            fit_with(w.effects, w.x, LM_ITERATIONS)
        })
    };
    let leave_out = |mut current: Fit| -> (Vec<Fit>, Vec<Fit>) {
        let mut steps = Vec::new();
        while current.effects.len() >= 2 {
            let refitted = each_left_out(&current);
            let weakest = refitted
                .iter()
                .filter(|w| w.cost.is_finite() && problem.plausible(w) && !current.beats(w))
                .min_by(|a, b| a.score.total_cmp(&b.score));
            match weakest {
                Some(w) => {
                    current = w.clone();
                    steps.push(current.clone());
                }
                None => return (steps, refitted),
            }
        }
        (steps, Vec::new())
    };

    // the declared model re-fitted: `none`
    // to its minimum: its cost is smooth ([`lm::Fit::smooth`])
    let none = {
        let f = |x: &[f64]| problem.residual(&problem.build(&[], x));
        let (x, cost) = lm::minimise(&f, &[0.0, 0.0], lm::Fit::new(DECLARED_REFIT_ITERATIONS, LM_REL_TOL).smooth(true));
        Fit { effects: Vec::new(), score: score(cost, x.len()), x, cost }
    };
    if !none.cost.is_finite() {
        return Err(IdentError::Data("re-fitting the declared model failed".into()));
    }
    progress("none");
    let skipped: Vec<Candidate> = Candidate::ALL.into_iter().filter(|c| !excitable(*c)).collect();
    // whether a fit's residual is white ([`WHITE_RESIDUAL_LAG1`]: nothing left that a candidate
    // could explain clearly), `None` where it cannot be simulated
    let white = |f: &Fit| {
        problem.residual(&problem.build(&f.effects, &f.x)).map(|r| lag1_autocorrelation(&r) < WHITE_RESIDUAL_LAG1)
    };
    // the selection from `start` (the re-fitted declared model, or a first effect), `search`
    // the steps that led there: forward rounds, the leave-out check and the swap step
    let select = |start: Fit, mut search: Vec<PathStep>| -> Selection {
        let mut current = start;
        let mut first_round: Vec<Fit> = Vec::new();
        // every candidate's screening fit of the forward selection, for the swap step
        let mut tried: Vec<Fit> = Vec::new();
        // forward selection: the best plausible candidate that beats the model so far is added.
        // An implausible one that scores better (it bends the declared mechanics to imitate an
        // effect, as damping missing beside a compliance does) is followed one round ahead: it is
        // taken only if a plausible model one effect later beats the plausible step. Every model
        // kept is plausible.
        while current.effects.len() < MAX_EFFECTS {
            if !current.effects.is_empty() && white(&current) == Some(true) {
                break;
            }
            let fits = round(&current);
            let plausible = best_beating(&fits, &current, true);
            let implausible =
                best_beating(&fits, &current, false).filter(|i| plausible.as_ref().is_none_or(|p| i.score < p.score));
            tried.extend(fits.iter().cloned());
            if current.effects.is_empty() {
                first_round = fits;
            }
            let mut steps: Option<Vec<Fit>> = None;
            if let Some(i) = implausible.filter(|_| current.effects.len() + 1 < MAX_EFFECTS) {
                let i = polish(i);
                let ahead = round(&i);
                tried.extend(ahead.iter().cloned());
                if let Some(next) =
                    best_beating(&ahead, &i, true).filter(|n| plausible.as_ref().is_none_or(|p| n.beats(p)))
                {
                    steps = Some(vec![i, polish(next)]);
                }
            }
            match steps.or_else(|| plausible.map(|p| vec![polish(p)])) {
                Some(steps) => {
                    for s in steps {
                        search.push(s.step());
                        current = s;
                    }
                }
                None => break,
            }
        }
        let (steps, mut leaving_out) = leave_out(current.clone());
        for s in steps {
            search.push(s.step());
            current = s;
        }
        // the swap step: each kept effect replaced by the candidates that can imitate it
        // ([`Candidate::alternatives`]: forward selection may have taken a dead time for a lag
        // before the other effects were there to tell them apart). The alternative is fitted in
        // its place beside the other effects at their values (from its own starts, all parameters
        // re-fitted). Only near-ties are tried: an alternative that the effect beat clearly beside
        // the same effects in the selection (lower score and 10 % less error) is not. A swap that
        // lowers the score is kept, then the effects are checked by leaving each out again.
        let near_tie = |fit: &Fit, i: usize, a: Candidate| -> bool {
            let screened = |c: Candidate| {
                tried
                    .iter()
                    .find(|f| f.effects.len() == i + 1 && f.effects[..i] == fit.effects[..i] && f.effects[i] == c)
            };
            match (screened(fit.effects[i]), screened(a)) {
                (Some(chosen), Some(other)) => !chosen.beats(other),
                _ => true,
            }
        };
        // `fit` with its `i`-th effect replaced by `a`, beside the others' re-seatings
        // (`reseated`: [`reseated_at`] of `fit` without it, shared by its alternatives)
        let swap = |fit: &Fit, i: usize, a: Candidate, reseated: &[Vec<f64>]| -> Fit {
            let f = extend(&fit.without(i), a, reseated);
            // polished only where it is a near-tie of the model it would replace (within the 10 %
            // that "beats" asks of the error), as the selection polishes only its winner
            if f.cost.is_finite() && 0.9 * f.error() <= fit.error() {
                polish(f)
            } else {
                f
            }
        };
        for _ in 0..MAX_EFFECTS {
            let trials: Vec<(usize, Candidate)> = current
                .effects
                .iter()
                .enumerate()
                .flat_map(|(i, c)| c.alternatives().into_iter().map(move |a| (i, a)))
                .filter(|&(i, a)| {
                    excitable(a)
                        && !current.effects.iter().enumerate().any(|(k, o)| k != i && o.overlaps(a))
                        && near_tie(&current, i, a)
                })
                .collect();
            let reseatings: Vec<Vec<Vec<f64>>> = (0..current.effects.len())
                .map(|i| if trials.iter().any(|t| t.0 == i) { reseated_at(&current.without(i)) } else { Vec::new() })
                .collect();
            let swapped: Vec<Fit> = super::on_two_workers(trials.len(), &|t| {
                let (i, a) = trials[t];
                swap(&current, i, a, &reseatings[i])
            });
            let best = swapped
                .into_iter()
                .filter(|f| f.cost.is_finite() && problem.plausible(f) && f.score < current.score)
                .min_by(|a, b| a.score.total_cmp(&b.score));
            match best {
                Some(b) => {
                    current = polish(b);
                    search.push(current.step());
                    let (steps, left_out) = leave_out(current.clone());
                    for s in steps {
                        search.push(s.step());
                        current = s;
                    }
                    leaving_out = left_out;
                }
                None => break,
            }
        }
        Selection { current, search, leaving_out, first_round }
    };
    let main = select(none.clone(), vec![none.step()]);
    // An answer that leaves more than [`RESTART_LEFT_FRACTION`] of the declared model's error
    // in a structured residual may owe it to its first step: an effect that explains most of
    // the record alone in a wrong place (a play twice too wide imitating a compliance) hides
    // the effects that belong beside its right place. The selection is run again from the
    // first round's best other effect, and its answer is kept if it beats this one clearly.
    let stuck = main.current.error() > RESTART_LEFT_FRACTION * error_before && white(&main.current) == Some(false);
    let runner_up = main
        .first_round
        .iter()
        .filter(|f| f.cost.is_finite() && problem.plausible(f) && f.beats(&none))
        .filter(|f| f.effects.iter().all(|c| !main.current.effects.iter().any(|m| m.overlaps(*c))))
        .min_by(|a, b| a.score.total_cmp(&b.score))
        .cloned();
    let Selection { mut current, search, leaving_out, first_round } = match runner_up.filter(|_| stuck) {
        Some(r) => {
            let r = polish(r);
            let alt = select(r.clone(), vec![none.step(), r.step()]);
            if alt.current.beats(&main.current) {
                // the search reports both runs: the first, then the restart from the declared model
                let search = main.search.into_iter().chain(alt.search).collect();
                Selection { first_round: main.first_round, search, ..alt }
            } else {
                main
            }
        }
        None => main,
    };

    // Other basins of the compliance that fit as well: the load machines' speeds alone may not
    // tell a soft spring with most of the drive's inertia on the motor from a stiff one with
    // most on the cage and stiffer shafts. Each motor share of the grid is fitted from its best
    // start (beside the declared and the answer's j_drive and c_short); a fit within
    // EQUIVALENT_BIC of the answer with the compliance elsewhere is an equivalent solution: the
    // record does not determine the compliance's parameters, and the report says so. A fit
    // better than the answer becomes the answer.
    let mut equivalent_fits: Vec<Fit> = Vec::new();
    if let Some(i) = current.effects.iter().position(|&c| c == Candidate::DriveCompliance) {
        let at = 2 + current.effects[..i].iter().map(|c| c.own_len()).sum::<usize>();
        let effects = current.effects.clone();
        let f = |x: &[f64]| problem.residual(&problem.build(&effects, x));
        let cost_at = |x: &[f64]| f(x).map_or(f64::INFINITY, |r| r.iter().map(|v| v * v).sum::<f64>());
        let starts = Candidate::DriveCompliance.starts(&problem, shuffle_hz);
        let mut seeds: Vec<Vec<f64>> = Vec::new();
        for declared_mechanics in [true, false] {
            let points: Vec<Vec<f64>> = starts
                .iter()
                .map(|s| {
                    let mut x = current.x.clone();
                    if declared_mechanics {
                        x[..2].fill(0.0);
                    }
                    x[at..at + 2].copy_from_slice(s);
                    x
                })
                .collect();
            let costs = super::on_two_workers(points.len(), &|k| cost_at(&points[k]));
            seeds.extend(best_per_share(&costs).into_iter().map(|k| points[k].clone()));
        }
        // each seed fitted directly and, with play, also by the phase-free fit (the notch the
        // answer's play sits in need not be the one of another basin)
        let routes = 1 + usize::from(phase_free(&effects));
        let fits = super::on_two_workers(seeds.len() * routes, &|k| match k % routes {
            0 => fit_with(effects.clone(), seeds[k / routes].clone(), LM_ITERATIONS),
            _ => phase_free_fit(&effects, &seeds[k / routes]),
        });
        let apart = |a: &Fit, b: &Fit| {
            (a.x[at] - b.x[at]).abs() > EQUIVALENT_APART_LN
                || (logistic(a.x[at + 1]) - logistic(b.x[at + 1])).abs() > EQUIVALENT_APART_SHARE
        };
        // a fit better than the answer (the selection's valley was not the deepest) is the answer
        let mut fits: Vec<Fit> = fits.into_iter().filter(|f| f.cost.is_finite() && problem.plausible(f)).collect();
        if let Some(k) = (0..fits.len()).min_by(|&a, &b| fits[a].score.total_cmp(&fits[b].score)) {
            if fits[k].score < current.score {
                let better = fits.swap_remove(k);
                fits.push(std::mem::replace(&mut current, better));
            }
        }
        for fit in fits {
            let equivalent = fit.score <= current.score + EQUIVALENT_BIC;
            if equivalent && apart(&fit, &current) && equivalent_fits.iter().all(|e| apart(e, &fit)) {
                equivalent_fits.push(fit);
            }
        }
    }

    // An answer of several effects is chosen on the data its fits did not see as well (as the
    // `drive_test` engine's pairs; issue 32, item 3): where the answer without one of its
    // effects (the leave-out check's re-fit) errs no more on the held-out folds than the answer,
    // that effect's gain on the fitted data is the fit's own freedom, not the record's, and the
    // answer goes without it. The check of the answer kept gives its intervals (below).
    let declared = |x: &[f64]| problem.residual(&problem.build(&[], x));
    let check_of = |fit: &Fit, rivals: &[Fit]| -> super::HeldOutCheck {
        let p = &problem;
        let of = |effects: &[Candidate]| {
            let effects = effects.to_vec();
            move |x: &[f64]| p.residual(&p.build(&effects, x))
        };
        let answer = of(&fit.effects);
        let rival_fns: Vec<_> = rivals.iter().map(|r| of(&r.effects)).collect();
        let jobs: Vec<(super::ResidualFn, &[f64])> =
            rival_fns.iter().zip(rivals).map(|(f, r)| (f as super::ResidualFn, r.x.as_slice())).collect();
        let has_effects = !fit.effects.is_empty();
        super::check_held_out(
            n,
            dt,
            answer(&fit.x).as_deref(),
            (&answer, &fit.x),
            (has_effects && problem.plausible(&none)).then_some((&declared as super::ResidualFn, none.x.as_slice())),
            &jobs,
            has_effects,
            error_before,
        )
    };
    let (mut search, mut leaving_out) = (search, leaving_out);
    let mut held_out_notes: Vec<String> = Vec::new();
    let check = loop {
        let rivals: Vec<Fit> = leaving_out
            .iter()
            .filter(|f| f.effects.len() + 1 == current.effects.len() && f.cost.is_finite() && problem.plausible(f))
            .cloned()
            .collect();
        let check = check_of(&current, &rivals);
        let answer_held_out = check.held_out.error_held_out;
        let Some((k, alone)) = check.rival_as_good() else {
            break check;
        };
        let name = |f: &Fit| f.effects.iter().map(|c| label(*c)).collect::<Vec<_>>().join(" + ");
        held_out_notes.push(format!(
            "{} rather than {}: on the folds its fit did not see, it errs {alone:.4} against {answer_held_out:.4}",
            name(&rivals[k]),
            name(&current)
        ));
        current = rivals[k].clone();
        search.push(current.step());
        leaving_out = if current.effects.len() >= 2 { each_left_out(&current) } else { Vec::new() };
    };
    // the effects in the order the check fitted them (the path below may reorder the answer's)
    let checked_effects = current.effects.clone();

    // The answer's own path, declared → +A → +A+B: where the search reached the answer only
    // by additions, its steps; otherwise (an effect left out or swapped) the nested models
    // re-fitted, each adding the kept effect that lowers the error most, and the answer's
    // effects put in that order.
    let additive = search.len() == current.effects.len() + 1
        && search.windows(2).all(|w| w[1].effects.len() == w[0].effects.len() + 1);
    let mut path: Vec<PathStep> = if additive {
        search.clone()
    } else {
        // nested[k]: the best model of all but k kept effects; built down from the answer by
        // leaving out the effect that costs least (the first level is the leave-out check's)
        let lowest =
            |fits: &[Fit]| fits.iter().filter(|f| f.cost.is_finite()).min_by(|a, b| a.cost.total_cmp(&b.cost)).cloned();
        let mut nested = vec![current.clone()];
        nested.extend(lowest(&leaving_out));
        while nested.len() > 1 && nested.last().is_some_and(|f| f.effects.len() > 1) {
            match lowest(&each_left_out(nested.last().expect("not empty"))) {
                Some(f) => nested.push(f),
                None => break,
            }
        }
        nested.reverse();
        // the answer's effects in the order they join
        let mut order: Vec<usize> = Vec::new();
        for f in &nested {
            for c in &f.effects {
                let k = current.effects.iter().position(|e| e == c).expect("a kept effect");
                if !order.contains(&k) {
                    order.push(k);
                }
            }
        }
        order.extend((0..current.effects.len()).filter(|k| !order.contains(k)).collect::<Vec<_>>());
        current = current.reordered(&order);
        // each step's effects named in the answer's order
        let rank = |c: &Candidate| current.effects.iter().position(|e| e == c);
        std::iter::once(none.step())
            .chain(nested.iter().map(|f| {
                let mut effects = f.effects.clone();
                effects.sort_by_key(rank);
                PathStep { effects: effects.iter().map(|c| label(*c)).collect(), ..f.step() }
            }))
            .collect()
    };

    // the path ends at the answer: its error and score (a better fit of the same effects may
    // have replaced the selection's, above)
    if let Some(last) = path.last_mut() {
        last.error = current.error();
        last.score = current.score;
    }

    // a fit as a row of the candidates' table: a single effect by its name and place, a set
    // by its labels
    let entry = |f: &Fit| -> CandidateScore {
        let why = problem.moved(f);
        let m = problem.build(&f.effects, &f.x);
        let mut parameters = declared_keys(&m);
        for c in &f.effects {
            parameters.extend(c.report(&m));
        }
        let (effect, at) = match f.effects.as_slice() {
            [] => ("none".to_string(), None),
            [c] => (c.name().to_string(), c.at()),
            many => (many.iter().map(|c| label(*c)).collect::<Vec<_>>().join(" + "), None),
        };
        let parts = if f.effects.is_empty() {
            vec![("none".to_string(), String::new())]
        } else {
            f.effects.iter().flat_map(|c| c.parts()).collect()
        };
        CandidateScore {
            effect,
            at,
            parameters,
            error_after: f.error(),
            score: f.score,
            fitted_parameters: f.x.len(),
            implausible: !why.is_empty(),
            implausible_because: why,
            parts,
        }
    };
    // the first round's table: every candidate beside the declared parameters
    let mut candidates: Vec<CandidateScore> =
        std::iter::once(&none).chain(first_round.iter().filter(|f| f.cost.is_finite())).map(entry).collect();
    // A candidate the data cannot show scores as the re-fitted declared model with one more
    // parameter (its own, at zero).
    let none_moved = problem.moved(&none);
    for c in skipped {
        let mut parameters = declared_keys(&problem.build(&[], &none.x));
        for k in c.report(&problem.build(&[], &none.x)).keys() {
            parameters.insert(k.clone(), 0.0);
        }
        candidates.push(CandidateScore {
            effect: c.name().into(),
            at: c.at(),
            parameters,
            error_after: none.error(),
            score: none.score + n_eff.max(2.0).ln(),
            fitted_parameters: none.x.len() + 1,
            // it is the re-fitted declared model, judged as that
            implausible: !none_moved.is_empty(),
            implausible_because: none_moved.clone(),
            parts: c.parts(),
        });
    }
    candidates.sort_by(|a, b| a.score.total_cmp(&b.score));
    // the answer against every candidate fitted beside the declared model: no finding where
    // another explains the record about as well
    let undetermined = verdict::undetermined(&entry(&current), &candidates, &verdict::PlaceSettings::default());

    let model = problem.build(&current.effects, &current.x);
    // The answer on data its fit did not see (`check`, above): the answer's fold fits give its
    // parameters' intervals.
    let after = problem.simulate(&model);
    let answer_residual = after.as_ref().map(|a| problem.residual_of(a));
    let fold_models: Vec<TorsionalModel> =
        check.answer_folds.iter().map(|f| problem.build(&checked_effects, &f.x)).collect();
    let intervals_of = |of: &dyn Fn(&TorsionalModel) -> BTreeMap<String, f64>| {
        super::fold_intervals(&of(&model), &fold_models.iter().map(of).collect::<Vec<_>>())
    };
    let effects: Vec<FoundEffect> = current
        .effects
        .iter()
        .map(|c| {
            // the answer without it, the others re-fitted (the leave-out check's fits)
            let error_without = if current.effects.len() == 1 {
                none.error()
            } else {
                leaving_out
                    .iter()
                    .find(|f| !f.effects.contains(c) && f.effects.len() + 1 == current.effects.len())
                    .map_or(f64::NAN, |f| f.error())
            };
            FoundEffect::new(c.name().into(), c.at(), c.report(&model), intervals_of(&|m| c.report(m)), error_without)
        })
        .collect();
    let mut parameters = declared_keys(&model);
    let mut intervals = intervals_of(&declared_keys);
    if let Some(first) = effects.first() {
        parameters.extend(first.parameters.clone());
        intervals.extend(first.intervals.clone());
    }
    let after = after.unwrap_or_else(|| [vec![0.0; n], vec![0.0; n]]);
    let rho = lag1_autocorrelation(&answer_residual.unwrap_or_else(|| problem.residual_of(&after)));
    let structured_residual = verdict::ResidualSettings::default().structured(rho, current.error());
    let traces = Traces {
        time_s: (0..n).map(|k| k as f64 * dt).collect(),
        measured: problem.measured.clone(),
        before: sim0,
        after,
    };
    // the answer's re-fit of the declared mechanics, judged by the rule every candidate is
    let moved = problem.moved(&current);
    let distorted = (!moved.is_empty())
        .then(|| format!("the model fits only with the declared mechanics moved: {}", moved.join("; ")));
    let equivalents: Vec<BTreeMap<String, f64>> = equivalent_fits
        .iter()
        .map(|f| {
            let m = problem.build(&f.effects, &f.x);
            let mut p = declared_keys(&m);
            for c in &f.effects {
                p.extend(c.report(&m));
            }
            p.insert("error".into(), f.error());
            p
        })
        .collect();
    // an effect whose size the record does not determine is no finding; every such value is said
    let held_out_settings = super::HeldOutSettings::default();
    let not_determined = super::not_determined(&parameters, &intervals, &held_out_settings);
    let (mut effects, mut intervals) = (effects, intervals);
    super::drop_unmeasured_intervals(&check.held_out, &mut effects, &mut intervals);
    let unsupported = check.unsupported.or_else(|| super::sizes_not_determined(&effects, &held_out_settings));
    let mut d = TorsionalDiagnosis {
        distorted,
        equivalents,
        effect: effects.first().map_or_else(|| "none".to_string(), |e| e.effect.clone()),
        at: effects.first().and_then(|e| e.at.clone()),
        parameters,
        intervals,
        held_out: check.held_out,
        unsupported,
        not_determined,
        undetermined,
        effects,
        path,
        search,
        error_before,
        error_after: current.error(),
        candidates,
        evidence,
        structured_residual,
        high_pass_hz: high_pass,
        model,
        verdict: verdict::Verdict::NotExplained,
        verdict_reasons: Vec::new(),
        notes: Vec::new(),
        traces,
    };
    d.notes = d.notes_in_words();
    d.notes.extend(held_out_notes);
    (d.verdict, d.verdict_reasons) = d.judged(sweep);
    Ok(d)
}

/// What a run of the selection ends at.
struct Selection {
    /// The answer.
    current: Fit,
    /// Each model it moved to.
    search: Vec<PathStep>,
    /// The answer without each of its effects, re-fitted (none for a single effect).
    leaving_out: Vec<Fit>,
    /// Every candidate fitted beside the re-fitted declared model (empty for a run that starts
    /// from an effect).
    first_round: Vec<Fit>,
}

/// An answer leaving more than this fraction of the declared model's error, in a structured
/// residual, is searched for again from the first round's best other effect.
pub const RESTART_LEFT_FRACTION: f64 = 0.1;

/// A found effect as the path names it ("backlash", "coulomb_friction at M2").
fn label(c: Candidate) -> String {
    match c.at() {
        Some(a) => format!("{} at {a}", c.name()),
        None => c.name().to_string(),
    }
}

fn declared_keys(m: &TorsionalModel) -> BTreeMap<String, f64> {
    let mut b = BTreeMap::new();
    b.insert("j_drive_kgm2".to_string(), m.rig.j_drive);
    b.insert("c_short_Nm_per_rad".to_string(), m.rig.c_short);
    b
}

fn evidence(p: &Problem, r: &[f64]) -> Evidence {
    let n = p.sweep.torque_nm.len();
    let dt = p.sweep.dt_s;
    let res: Vec<f64> = r[..n].to_vec();
    let rs = rfft(&res);
    let ms = rfft(&p.measured[0].iter().map(|v| v / p.norm).collect::<Vec<_>>());
    let df = 1.0 / (n as f64 * dt);
    // from twice the high-pass corner up (its pass band), inside the spectrum
    let lo = ((2.0 * p.high_pass_hz / df) as usize).max(1).min(rs.len() - 1);
    let (k, _) =
        rs.iter().enumerate().skip(lo).fold((lo, 0.0), |b, (k, c)| if c.norm() > b.1 { (k, c.norm()) } else { b });
    let residual_peak_ratio = rs[k].norm() / ms[k].norm().max(1e-300);
    // Cross-correlation of the high-passed torque with the residual, lags within ±0.1 s (and
    // within the record), by FFT
    let u = filtfilt_high_pass(&p.sweep.torque_nm, dt, p.high_pass_hz);
    let max_lag = (0.1 / dt).min(n as f64) as usize;
    let best = crate::signal::cross_correlation(&u, &res, max_lag).into_iter().fold((0isize, 0.0f64), |b, (lag, c)| {
        if c.abs() > b.1.abs() {
            (lag, c)
        } else {
            b
        }
    });
    // Harmonics: residual spectrum at 2f and 3f of the torque's spectrum-weighted lines.
    let us = rfft(&u);
    let (mut p1, mut p23) = (0.0, 0.0);
    for (k, c) in us.iter().enumerate().skip(lo) {
        let w = c.norm_sqr();
        p1 += w * rs.get(k).map_or(0.0, |c| c.norm_sqr());
        p23 += w * (rs.get(2 * k).map_or(0.0, |c| c.norm_sqr()) + rs.get(3 * k).map_or(0.0, |c| c.norm_sqr()));
    }
    Evidence {
        residual_peak_hz: k as f64 * df,
        residual_peak_ratio,
        xcorr_lag_s: best.0 as f64 * dt,
        residual_lag1: lag1_autocorrelation(&res),
        harmonic_ratio: p23 / p1.max(1e-300),
    }
}
