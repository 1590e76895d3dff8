//! Diagnosis of a torsional sweep: the declared rig simulated with the recorded drive torque,
//! its speed residual, and the drive-path effects of `plant::effects` fitted one by one.

use std::collections::BTreeMap;

use plant::effects::{DriveEffects, Powertrain};
use plant::rig::{RigParams, Variant};
use serde::Serialize;

use super::{bic, effective_count, lag1_autocorrelation, lm, CandidateScore};
use crate::error::{IdentError, Result};
use crate::signal::{filtfilt_high_pass, filtfilt_high_pass_in_place, rfft};
use crate::sweep::Sweep;

/// The torsional vocabulary.
pub const EFFECTS: [&str; 6] = ["none", "shaft_damping", "time_delay", "actuator_lag", "backlash", "drive_compliance"];

/// Offsets and drift are removed below this frequency (the sweeps start at 1 Hz).
pub const HIGH_PASS_HZ: f64 = 0.5;

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

/// The diagnosis of one sweep.
#[derive(Debug, Clone, Serialize)]
pub struct TorsionalDiagnosis {
    /// The chosen effect.
    pub effect: String,
    /// Its parameters.
    pub parameters: BTreeMap<String, f64>,
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
    /// The extended model.
    pub model: TorsionalModel,
    /// Time, measured speeds and model speeds before and after (high-passed), for plots.
    #[serde(skip)]
    pub traces: Traces,
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
    speed0: f64,
    measured: [Vec<f64>; 2],
    norm: f64,
}

impl Problem<'_> {
    fn simulate(&self, model: &TorsionalModel) -> Option<[Vec<f64>; 2]> {
        // Keep the search where the models are meaningful (and the matrix exponential cheap):
        // effects up to a second, a radian of play, a compliance mode below a tenth of the
        // sampling rate; declared parameters within a factor 100.
        let e = &model.effects;
        let ratio = |a: f64, b: f64| (a / b).max(b / a);
        if e.time_delay_s > 1.0
            || e.actuator_lag_s > 1.0
            || e.backlash_rad > 1.0
            || ratio(model.rig.j_drive, self.declared.j_drive) > 100.0
            || ratio(model.rig.c_short, self.declared.c_short) > 100.0
        {
            return None;
        }
        let p = Powertrain::new(&model.rig, model.variant, &model.effects).ok()?;
        if e.compliance_stiffness_nm_per_rad > 0.0
            && p.frequencies_hz().last().copied().unwrap_or(0.0) > 0.1 / self.sweep.dt_s
        {
            return None;
        }
        let (mut a, mut b) = p.simulate(&self.sweep.torque_nm, self.sweep.dt_s, self.speed0).ok()?;
        if !a.iter().chain(&b).all(|v| v.is_finite()) {
            return None;
        }
        filtfilt_high_pass_in_place(&mut a, self.sweep.dt_s, HIGH_PASS_HZ);
        filtfilt_high_pass_in_place(&mut b, self.sweep.dt_s, HIGH_PASS_HZ);
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

    /// Normalised residual of simulated (high-passed) speeds, both channels.
    fn residual_of(&self, s: &[Vec<f64>; 2]) -> Vec<f64> {
        self.measured[0]
            .iter()
            .zip(&s[0])
            .chain(self.measured[1].iter().zip(&s[1]))
            .map(|(m, y)| (m - y) / self.norm)
            .collect()
    }
}

/// Candidate parameterisation: x (log space) ↔ model.
struct Candidate {
    name: &'static str,
    /// Starting values of the effect's own parameters (log space) to try.
    starts: Vec<Vec<f64>>,
    build: fn(&Problem, &[f64]) -> TorsionalModel,
    report: fn(&TorsionalModel) -> BTreeMap<String, f64>,
}

fn with_declared(p: &Problem, x: &[f64]) -> RigParams {
    // x[0], x[1]: ln of j_drive and c_short relative to the declared values; c_long keeps
    // its declared ratio to c_short.
    let (j, c) = (p.declared.j_drive * x[0].exp(), p.declared.c_short * x[1].exp());
    RigParams { j_drive: j, c_short: c, c_long: p.declared.c_long.map(|l| l * x[1].exp()), ..p.declared.clone() }
}

fn model(p: &Problem, rig: RigParams, effects: DriveEffects) -> TorsionalModel {
    TorsionalModel { rig, variant: p.variant, effects }
}

fn declared_keys(m: &TorsionalModel) -> BTreeMap<String, f64> {
    let mut b = BTreeMap::new();
    b.insert("j_drive".to_string(), m.rig.j_drive);
    b.insert("c_short".to_string(), m.rig.c_short);
    b
}

fn candidates(p: &Problem, shuffle_hz: f64) -> Vec<Candidate> {
    let ln = |v: f64| v.ln();
    vec![
        Candidate {
            name: "none",
            starts: vec![vec![]],
            build: |p, x| model(p, with_declared(p, x), DriveEffects::default()),
            report: declared_keys,
        },
        Candidate {
            name: "shaft_damping",
            starts: [0.005, 0.02, 0.05, 0.15].iter().map(|&z| vec![ln(z)]).collect(),
            build: |p, x| {
                let rig = with_declared(p, x);
                let rig = rig.with_shaft_damping_ratio(x[2].exp(), p.variant).unwrap_or(rig);
                model(p, rig, DriveEffects::default())
            },
            report: |m| {
                let mut b = declared_keys(m);
                let e = m.rig.effective(m.variant).ok();
                let z = e.map(|e| {
                    let cs = e.c_left * e.c_right / (e.c_left + e.c_right);
                    let w = (cs * (1.0 / e.j_m2 + 4.0 / e.j_drive + 1.0 / e.j_m3)).sqrt();
                    0.5 * w * e.d_left / e.c_left
                });
                b.insert("damping_ratio".into(), z.unwrap_or(f64::NAN));
                b
            },
        },
        Candidate {
            name: "time_delay",
            starts: [0.001, 0.003, 0.01, 0.03].iter().map(|&t| vec![ln(t)]).collect(),
            build: |p, x| {
                model(p, with_declared(p, x), DriveEffects { time_delay_s: x[2].exp(), ..Default::default() })
            },
            report: |m| {
                let mut b = declared_keys(m);
                b.insert("delay_s".into(), m.effects.time_delay_s);
                b
            },
        },
        Candidate {
            name: "actuator_lag",
            starts: [0.001, 0.003, 0.01, 0.03].iter().map(|&t| vec![ln(t)]).collect(),
            build: |p, x| {
                model(p, with_declared(p, x), DriveEffects { actuator_lag_s: x[2].exp(), ..Default::default() })
            },
            report: |m| {
                let mut b = declared_keys(m);
                b.insert("time_constant_s".into(), m.effects.actuator_lag_s);
                b
            },
        },
        Candidate {
            name: "backlash",
            // The fit in the play is rough (contact comes and goes): a dense start grid.
            starts: (0..16).map(|i| vec![ln(1e-4 * 1.5f64.powi(i))]).collect(),
            build: |p, x| {
                model(p, with_declared(p, x), DriveEffects { backlash_rad: x[2].exp(), ..Default::default() })
            },
            report: |m| {
                let mut b = declared_keys(m);
                b.insert("backlash_rad".into(), m.effects.backlash_rad);
                b
            },
        },
        Candidate {
            name: "drive_compliance",
            // Stiffness placing the uncoupled motor-cage mode at 1.2 to 8 times the shuffle,
            // motor shares 0.3, 0.5, 0.7: the fit's valleys are narrow in frequency.
            starts: (0..12)
                .flat_map(|i| {
                    let r = 1.2 * (8.0f64 / 1.2).powf(i as f64 / 11.0);
                    [0.3f64, 0.5, 0.7].map(move |f| (r, f))
                })
                .map(|(r, f)| {
                    let w = 2.0 * std::f64::consts::PI * shuffle_hz * r;
                    let k = w * w * p.declared.j_drive * f * (1.0 - f);
                    vec![ln(k), (f / (1.0 - f)).ln()]
                })
                .collect(),
            build: |p, x| {
                let f = 1.0 / (1.0 + (-x[3]).exp());
                model(
                    p,
                    with_declared(p, x),
                    DriveEffects {
                        compliance_stiffness_nm_per_rad: x[2].exp(),
                        compliance_motor_fraction: f,
                        ..Default::default()
                    },
                )
            },
            report: |m| {
                let mut b = declared_keys(m);
                b.insert("stiffness_Nm_per_rad".into(), m.effects.compliance_stiffness_nm_per_rad);
                let f = Powertrain::new(&m.rig, m.variant, &m.effects).map(|p| p.frequencies_hz()).unwrap_or_default();
                b.insert("frequency_hz".into(), f.last().copied().unwrap_or(f64::NAN));
                b.insert("motor_fraction".into(), m.effects.compliance_motor_fraction);
                b
            },
        },
    ]
}

/// Diagnoses `sweep` against the declared `rig` in `variant`. `progress` is told each
/// candidate's name as it finishes.
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
    let measured = [
        filtfilt_high_pass(&sweep.speed_m2_radps, dt, HIGH_PASS_HZ),
        filtfilt_high_pass(&sweep.speed_m3_radps, dt, HIGH_PASS_HZ),
    ];
    let norm = measured.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    if norm.is_nan() || norm <= 0.0 {
        return Err(IdentError::Data("the load-machine speeds do not oscillate: nothing to compare".into()));
    }
    let speed0 = 0.5 * (sweep.speed_m2_radps[0] + sweep.speed_m3_radps[0]);
    let problem = Problem { sweep, declared: rig.clone(), variant, speed0, measured, norm };
    let declared = TorsionalModel { rig: rig.clone(), variant, effects: DriveEffects::default() };
    let sim0 = problem
        .simulate(&declared)
        .ok_or_else(|| IdentError::Data("the declared model cannot be simulated (check its parameters)".into()))?;
    let r0 = problem.residual_of(&sim0);
    let error_before = r0.iter().map(|v| v * v).sum::<f64>().sqrt();
    let evidence = evidence(&problem, &r0);
    let shuffle_hz = Powertrain::new(rig, variant, &DriveEffects::default())
        .map(|p| p.frequencies_hz().last().copied().unwrap_or(10.0))
        .unwrap_or(10.0);

    let cands = candidates(&problem, shuffle_hz);
    let fit_one = |i: usize| -> (usize, Vec<f64>, f64) {
        let c = &cands[i];
        let problem = &problem;
        // Play only shows when the shaft torque changes sign: with a drive torque that never
        // does, backlash cannot be seen and is not fitted.
        let t = &problem.sweep.torque_nm;
        let crosses = t.iter().any(|&v| v > 0.0) && t.iter().any(|&v| v < 0.0);
        if c.name == "backlash" && !crosses {
            progress(c.name);
            return (i, Vec::new(), f64::NAN);
        }
        let f = |x: &[f64]| problem.residual(&(c.build)(problem, x));
        // Grid over the effect's own parameters with the declared ones, then LM on all.
        let cost_at = |s: &Vec<f64>| {
            let mut x = vec![0.0, 0.0];
            x.extend(s);
            let cost = f(&x).map(|r| r.iter().map(|v| v * v).sum::<f64>());
            (x, cost.unwrap_or(f64::INFINITY))
        };
        let best = c.starts.iter().map(cost_at).filter(|g| g.1.is_finite()).min_by(|p, q| p.1.total_cmp(&q.1));
        let (x, cost) = match best {
            Some((x0, _)) => lm::minimise(&f, &x0, 12),
            None => (vec![], f64::INFINITY),
        };
        progress(c.name);
        (i, x, cost)
    };
    let fits: Vec<(usize, Vec<f64>, f64)> = super::on_two_workers(cands.len(), &fit_one);

    let nres = 2 * n;
    let mut scored = Vec::new();
    let mut models = Vec::new();
    let mut skipped = Vec::new();
    for (i, x, cost) in fits {
        if cost.is_nan() {
            skipped.push(cands[i].name.to_string());
            continue;
        }
        if !cost.is_finite() {
            continue;
        }
        let c = &cands[i];
        let m = (c.build)(&problem, &x);
        // One simulation per fitted candidate: its residual's whiteness (the best one's
        // traces are simulated once more below, so no candidate keeps a record-long trace).
        let rho = problem.simulate(&m).map_or(0.0, |s| lag1_autocorrelation(&problem.residual_of(&s)));
        scored.push(CandidateScore {
            at: None,
            effect: c.name.to_string(),
            parameters: (c.report)(&m),
            error_after: cost.sqrt(),
            score: 0.0,
            fitted_parameters: x.len(),
        });
        models.push((m, rho, cost));
    }
    // One effective count for all (the declared model's residual), so the scores compare.
    let n_eff = effective_count(nres, evidence.residual_lag1.max(lag1_autocorrelation(&r0)));
    for (s, (_, _, cost)) in scored.iter_mut().zip(&models) {
        s.score = bic(*cost * problem.norm * problem.norm, nres, n_eff, s.fitted_parameters);
    }
    let none = scored
        .iter()
        .position(|s| s.effect == "none")
        .ok_or_else(|| IdentError::Data("re-fitting the declared model failed".into()))?;
    let mut best = none;
    for (i, s) in scored.iter().enumerate() {
        // An effect must beat the re-fitted declared model clearly: 10 % less error and a
        // lower score.
        if s.score < scored[best].score && s.error_after < 0.9 * scored[none].error_after {
            best = i;
        }
    }
    let (model, rho, _) = models.swap_remove(best);
    let structured_residual = rho.abs() > 0.5 && scored[best].error_after > 0.02;
    let after = problem.simulate(&model).unwrap_or_else(|| [vec![0.0; n], vec![0.0; n]]);
    let traces = Traces {
        time_s: (0..n).map(|k| k as f64 * dt).collect(),
        measured: problem.measured.clone(),
        before: sim0,
        after,
    };
    let mut candidates = scored.clone();
    // A candidate the data cannot show scores as the re-fitted declared model with one more
    // parameter (its own, at zero).
    for name in skipped {
        let none = &scored[none];
        let mut parameters = none.parameters.clone();
        parameters.insert("backlash_rad".into(), 0.0);
        candidates.push(CandidateScore {
            at: None,
            effect: name,
            parameters,
            error_after: none.error_after,
            score: none.score + n_eff.max(2.0).ln(),
            fitted_parameters: none.fitted_parameters + 1,
        });
    }
    candidates.sort_by(|a, b| a.score.total_cmp(&b.score));
    Ok(TorsionalDiagnosis {
        effect: scored[best].effect.clone(),
        parameters: scored[best].parameters.clone(),
        error_before,
        error_after: scored[best].error_after,
        candidates,
        evidence,
        structured_residual,
        model,
        traces,
    })
}

fn evidence(p: &Problem, r: &[f64]) -> Evidence {
    let n = p.sweep.torque_nm.len();
    let dt = p.sweep.dt_s;
    let res: Vec<f64> = r[..n].to_vec();
    let rs = rfft(&res);
    let ms = rfft(&p.measured[0].iter().map(|v| v / p.norm).collect::<Vec<_>>());
    let df = 1.0 / (n as f64 * dt);
    // from 1 Hz up (the high-pass's band), inside the spectrum
    let lo = ((1.0 / df) as usize).min(rs.len() - 1);
    let (k, _) =
        rs.iter().enumerate().skip(lo).fold((lo, 0.0), |b, (k, c)| if c.norm() > b.1 { (k, c.norm()) } else { b });
    let residual_peak_ratio = rs[k].norm() / ms[k].norm().max(1e-300);
    // Cross-correlation of the high-passed torque with the residual, lags within ±0.1 s (and
    // within the record), by FFT
    let u = filtfilt_high_pass(&p.sweep.torque_nm, dt, HIGH_PASS_HZ);
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
