//! The natural frequency from a sine sweep (section 3), two ways, each with an uncertainty, and
//! which mode the rig showed (section 4.4).
//!
//! - **Paper** (section 3): high-pass 1 Hz, power of the speed signal in 1–30 Hz over time, the
//!   interval around the maximum where the power is ≥ 80 % of it, its centre mapped to the
//!   excitation frequency at that time (here read from the torque's zero crossings, so any
//!   sweep law works). Uncertainty: the interval taken as a uniform distribution,
//!   σ = (f_b − f_a)/(2√3). The response of a swept resonance peaks after the sweep has passed
//!   it, so this estimate is biased upwards by an amount that grows with the sweep rate.
//! - **Modal fit**: the frequency response H(iω) = Y(iω)/U(iω) from torque to each load
//!   machine's speed, from one DFT of the whole record (a sweep excites every line of its
//!   band, and no segment window biases it), fitted near its peak with
//!   H(s) = b0 + b1/s + q s/(s² + 2ζω_n s + ω_n²) — the shuffle mode plus the rigid body and the
//!   out-of-band modes as a low-order background — in the output domain,
//!   Y_k = H(s_k) U_k + T(s_k), where the smooth polynomial T takes up the leakage of the
//!   record's start and end transients (Pintelon & Schoukens' transient term: a polynomial plus
//!   the resonance's own poles). Then white
//!   output noise gives every line the same variance. b0, b1, q and T are linear and solved
//!   exactly for each (ω_n, ζ) (variable projection); (ω_n, ζ) by Levenberg–Marquardt; the
//!   noise level comes from the residual, σ(ω_n) from the covariance. The two machines give two
//!   estimates; their errors are as correlated as their residuals, and they are combined by
//!   generalised least squares with that correlation (σ widened if they disagree).
//!
//! Which mode: the residues q of the two machines are in phase for the shuffle (drive against
//! both outputs) and in antiphase for the outputs' mode.

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;

use crate::error::{IdentError, Result};
use crate::signal::{band_power_over_time, detrend, high_pass, interpolate, rfft, zero_crossing_frequency};

/// A torsional sine sweep: drive torque in, load-machine speeds out, uniformly sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// Sample time, s.
    pub dt_s: f64,
    /// Drive torque at the differential cage, Nm.
    pub torque_nm: Vec<f64>,
    /// Speed of load machine M2, rad/s.
    pub speed_m2_radps: Vec<f64>,
    /// Speed of load machine M3, rad/s.
    pub speed_m3_radps: Vec<f64>,
}

/// How the sweep is analysed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepSettings {
    /// Band searched for the natural frequency, Hz (section 3: 1–30 Hz).
    pub band_hz: (f64, f64),
    /// High-pass cut-off of the paper's method, Hz.
    pub high_pass_hz: f64,
    /// Fraction of the maximum power that bounds the paper's interval.
    pub power_fraction: f64,
    /// Frame length of the paper's power-over-time, s.
    pub window_s: f64,
    /// Frame step, s.
    pub hop_s: f64,
    /// Modal fit band as fractions of the peak frequency.
    pub fit_band: (f64, f64),
}

impl Default for SweepSettings {
    fn default() -> Self {
        SweepSettings {
            band_hz: (1.0, 30.0),
            high_pass_hz: 1.0,
            power_fraction: 0.8,
            window_s: 1.0,
            hop_s: 0.05,
            fit_band: (0.8, 1.25),
        }
    }
}

/// One estimate from one speed signal.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelEstimate {
    /// "speed_m2" or "speed_m3".
    pub signal: &'static str,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Its standard uncertainty, Hz.
    pub sigma_hz: f64,
}

/// A natural frequency with its uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrequencyEstimate {
    /// "paper" or "modal_fit".
    pub method: &'static str,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Standard uncertainty, Hz.
    pub sigma_hz: f64,
    /// Modal damping ratio (modal fit only).
    pub damping_ratio: Option<f64>,
    /// The estimate of each load machine.
    pub channels: Vec<ChannelEstimate>,
}

/// Which mode the sweep excited at the resonance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SeenMode {
    /// Both machines in phase: the shuffle.
    Shuffle,
    /// The machines against each other.
    OutputsAntiphase,
    /// Neither clearly.
    Unclear,
}

/// What one sweep says.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepAnalysis {
    /// The paper's procedure.
    pub paper: FrequencyEstimate,
    /// The modal fit.
    pub modal_fit: FrequencyEstimate,
    /// Phase of M2's speed relative to M3's at the resonance, degrees.
    pub phase_m2_m3_deg: f64,
    /// |M2 residue| / |M3 residue|.
    pub amplitude_ratio_m2_m3: f64,
    /// The mode seen.
    pub mode: SeenMode,
}

impl Sweep {
    fn check(&self) -> Result<usize> {
        let n = self.torque_nm.len();
        if self.speed_m2_radps.len() != n || self.speed_m3_radps.len() != n {
            return Err(IdentError::Data("torque and speed signals differ in length".into()));
        }
        if !(self.dt_s > 0.0 && self.dt_s.is_finite()) {
            return Err(IdentError::Data(format!("sample time {} s is not positive", self.dt_s)));
        }
        let all = self.torque_nm.iter().chain(&self.speed_m2_radps).chain(&self.speed_m3_radps);
        if let Some(bad) = all.clone().find(|v| !v.is_finite()) {
            return Err(IdentError::Data(format!("signals contain a non-finite value ({bad})")));
        }
        if (n as f64) * self.dt_s < 4.0 || n < 256 {
            return Err(IdentError::Data(format!(
                "{n} samples ({:.2} s) are too short for a sweep",
                n as f64 * self.dt_s
            )));
        }
        Ok(n)
    }

    /// Both estimates and the mode seen.
    pub fn analyse(&self, settings: &SweepSettings) -> Result<SweepAnalysis> {
        self.check()?;
        // the excitation is the same for both machines: its spectrum and its frequency over
        // time are computed once
        let u = rfft(&detrend(&self.torque_nm));
        if u.iter().skip(1).all(|c| c.norm() == 0.0) {
            return Err(IdentError::Data("the drive torque does not oscillate: no sweep to analyse".into()));
        }
        let excitation = zero_crossing_frequency(
            &high_pass(&detrend(&self.torque_nm), self.dt_s, 0.5 * settings.band_hz.0),
            self.dt_s,
        );
        if excitation.len() < 4 {
            return Err(IdentError::Data("the drive torque does not oscillate: no sweep to analyse".into()));
        }
        let fits = [
            self.modal_fit_channel(&u, &self.speed_m2_radps, "speed_m2", settings)?,
            self.modal_fit_channel(&u, &self.speed_m3_radps, "speed_m3", settings)?,
        ];
        // the two machines' errors are as correlated as their fit residuals (same lines)
        let rho = {
            let (a, b) = (&fits[0].residual, &fits[1].residual);
            if a.len() == b.len() && a.norm() > 0.0 && b.norm() > 0.0 {
                (a.dot(b) / (a.norm() * b.norm())).clamp(-0.99, 0.99)
            } else {
                0.99
            }
        };
        let modal_fit = combine(
            "modal_fit",
            &fits.iter().map(|f| f.estimate.clone()).collect::<Vec<_>>(),
            Some(rho),
            Some(0.5 * (fits[0].zeta + fits[1].zeta)),
        );
        // the paper's procedure reads both machines at the same moment of one sweep: treat its
        // two estimates as fully correlated
        let paper = combine(
            "paper",
            &[
                self.paper_channel(&excitation, &self.speed_m2_radps, "speed_m2", settings)?,
                self.paper_channel(&excitation, &self.speed_m3_radps, "speed_m3", settings)?,
            ],
            None,
            None,
        );
        let ratio = fits[0].residue / fits[1].residue;
        let phase = ratio.arg().to_degrees();
        let mode = if phase.abs() <= 45.0 {
            SeenMode::Shuffle
        } else if phase.abs() >= 135.0 {
            SeenMode::OutputsAntiphase
        } else {
            SeenMode::Unclear
        };
        Ok(SweepAnalysis { paper, modal_fit, phase_m2_m3_deg: phase, amplitude_ratio_m2_m3: ratio.norm(), mode })
    }

    /// The paper's procedure on one speed signal; `excitation` is the torque's (time, frequency)
    /// from its zero crossings.
    fn paper_channel(
        &self,
        excitation: &[(f64, f64)],
        speed: &[f64],
        name: &'static str,
        st: &SweepSettings,
    ) -> Result<ChannelEstimate> {
        let dt = self.dt_s;
        let y = high_pass(&detrend(speed), dt, st.high_pass_hz);
        let window = ((st.window_s / dt).round() as usize).max(16);
        let hop = ((st.hop_s / dt).round() as usize).max(1);
        let (times, power) = band_power_over_time(&y, dt, window, hop, st.band_hz.0, st.band_hz.1);
        let kmax = (0..power.len())
            .max_by(|&a, &b| power[a].total_cmp(&power[b]))
            .ok_or_else(|| IdentError::Data("record shorter than one frame".into()))?;
        let limit = st.power_fraction * power[kmax];
        let (mut a, mut b) = (kmax, kmax);
        while a > 0 && power[a - 1] >= limit {
            a -= 1;
        }
        while b + 1 < power.len() && power[b + 1] >= limit {
            b += 1;
        }
        let f = |t: f64| interpolate(excitation, t).expect("non-empty");
        let (fa, fb) = (f(times[a]), f(times[b]));
        Ok(ChannelEstimate {
            signal: name,
            frequency_hz: f(0.5 * (times[a] + times[b])),
            sigma_hz: (fb - fa).abs() / (2.0 * 3f64.sqrt()),
        })
    }

    /// The modal fit of one speed signal; `u` is the torque's spectrum (non-zero, checked).
    fn modal_fit_channel(
        &self,
        u: &[Complex64],
        speed: &[f64],
        name: &'static str,
        st: &SweepSettings,
    ) -> Result<ChannelFit> {
        let n = speed.len();
        let df = 1.0 / (n as f64 * self.dt_s);
        let y = rfft(&detrend(speed));
        let umax = u.iter().skip(1).map(|c| c.norm()).fold(0.0, f64::max);
        // excited lines of the band: |U| at least 2 % of its largest value
        let excited: Vec<usize> = (1..u.len())
            .filter(|&k| {
                let f = k as f64 * df;
                f >= st.band_hz.0 && f <= st.band_hz.1 && u[k].norm() >= 0.02 * umax
            })
            .collect();
        if excited.len() < 16 {
            return Err(IdentError::Data(format!(
                "only {} DFT lines of {}–{} Hz are excited",
                excited.len(),
                st.band_hz.0,
                st.band_hz.1
            )));
        }
        // peak of |iω H| (torque → acceleration): the rigid body's 1/s trend removed
        let kpk = *excited
            .iter()
            .max_by(|&&a, &&b| {
                let g = |k: usize| (y[k] / u[k]).norm() * k as f64;
                g(a).total_cmp(&g(b))
            })
            .expect("non-empty");
        let fpk = kpk as f64 * df;
        let lines: Vec<usize> = excited
            .iter()
            .copied()
            .filter(|&k| {
                let f = k as f64 * df;
                f >= st.fit_band.0 * fpk && f <= st.fit_band.1 * fpk
            })
            .collect();
        if lines.len() < 12 {
            return Err(IdentError::Data(format!(
                "only {} lines around the peak at {fpk:.2} Hz: record too short for a modal fit",
                lines.len()
            )));
        }
        let (w_lo, w_hi) = (2.0 * PI * lines[0] as f64 * df, 2.0 * PI * lines[lines.len() - 1] as f64 * df);
        let data = FitData {
            s: lines.iter().map(|&k| Complex64::new(0.0, 2.0 * PI * k as f64 * df)).collect(),
            u: lines.iter().map(|&k| u[k]).collect(),
            y: lines.iter().map(|&k| y[k]).collect(),
            centre: 0.5 * (w_lo + w_hi),
            half_width: 0.5 * (w_hi - w_lo),
        };
        let fit = fit_resonance(&data, 2.0 * PI * fpk)?;
        Ok(ChannelFit {
            estimate: ChannelEstimate {
                signal: name,
                frequency_hz: fit.wn / (2.0 * PI),
                sigma_hz: fit.sigma_wn / (2.0 * PI),
            },
            zeta: fit.zeta,
            residue: fit.residue,
            residual: fit.residual,
        })
    }
}

struct ChannelFit {
    estimate: ChannelEstimate,
    zeta: f64,
    residue: Complex64,
    residual: DVector<f64>,
}

/// Combines two channel estimates. With the correlation `rho` of their errors known, the
/// generalised least-squares mean (var = 1/(1ᵀΣ⁻¹1)); without it (`None`), the errors are taken
/// as fully correlated: the inverse-variance mean with the channels' mean σ. Either way σ is
/// widened to half the channels' spread if they disagree by more.
fn combine(
    method: &'static str,
    ch: &[ChannelEstimate],
    rho: Option<f64>,
    damping_ratio: Option<f64>,
) -> FrequencyEstimate {
    let (lo, hi) = ch
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(c.frequency_hz), hi.max(c.frequency_hz)));
    let usable = ch.len() == 2 && ch.iter().all(|c| c.sigma_hz > 0.0 && c.sigma_hz.is_finite());
    let (f, sigma) = match rho {
        Some(r) if usable => {
            let (s1, s2) = (ch[0].sigma_hz, ch[1].sigma_hz);
            let cov = Matrix2::new(s1 * s1, r * s1 * s2, r * s1 * s2, s2 * s2);
            let inv = cov.try_inverse().expect("|ρ| < 1 keeps Σ regular");
            let w = inv * Vector2::new(1.0, 1.0);
            let total = w.sum();
            ((w[0] * ch[0].frequency_hz + w[1] * ch[1].frequency_hz) / total, total.recip().sqrt())
        }
        _ => {
            let weight = |c: &ChannelEstimate| if c.sigma_hz > 0.0 { 1.0 / (c.sigma_hz * c.sigma_hz) } else { 1.0 };
            let w: f64 = ch.iter().map(weight).sum();
            let f = ch.iter().map(|c| c.frequency_hz * weight(c)).sum::<f64>() / w;
            (f, ch.iter().map(|c| c.sigma_hz).sum::<f64>() / ch.len() as f64)
        }
    };
    FrequencyEstimate {
        method,
        frequency_hz: f,
        sigma_hz: sigma.max(0.5 * (hi - lo)),
        damping_ratio,
        channels: ch.to_vec(),
    }
}

/// The lines of the fit: Laplace variable, input and output spectra, and the band centre
/// that scales the transient polynomial.
struct FitData {
    s: Vec<Complex64>,
    u: Vec<Complex64>,
    y: Vec<Complex64>,
    centre: f64,
    half_width: f64,
}

/// Complex linear coefficients of the fit: b0, b1 and the residue q of H, and the transient
/// term: the polynomial t0 + t1 x + t2 x² (x the line's position in the band, −1..1) plus the
/// two terms through the resonance's own poles, (r0 ω_n² + r1 ω_n s)/(s² + 2ζω_n s + ω_n²).
const LINEAR: usize = 8;

struct Resonance {
    wn: f64,
    zeta: f64,
    sigma_wn: f64,
    residue: Complex64,
    residual: DVector<f64>,
}

/// Residual of Y_k − H(s_k) U_k − T(s_k) for the best linear coefficients at (ω_n, ζ), and the
/// coefficients. Output noise that is white gives every line the same variance here, so no
/// weights are needed; T absorbs the leakage of the record's start and end transients — a
/// rational function with the system's poles, smooth over the band except through the
/// resonance — which would otherwise pass for noise.
fn projected(d: &FitData, wn: f64, zeta: f64) -> (DVector<f64>, [Complex64; LINEAR]) {
    let m = d.s.len();
    let mut a = DMatrix::zeros(2 * m, 2 * LINEAR);
    let mut b = DVector::zeros(2 * m);
    for k in 0..m {
        let s = d.s[k];
        let u = d.u[k];
        let x = (s.im - d.centre) / d.half_width;
        let den = s * s + 2.0 * zeta * wn * s + wn * wn;
        let basis = [
            u,
            u / s,
            u * s / den,
            Complex64::new(1.0, 0.0),
            Complex64::new(x, 0.0),
            Complex64::new(x * x, 0.0),
            wn * wn / den,
            wn * s / den,
        ];
        for (j, p) in basis.iter().enumerate() {
            // (a + ib)·φ = (a Re φ − b Im φ) + i (a Im φ + b Re φ)
            a[(2 * k, 2 * j)] = p.re;
            a[(2 * k, 2 * j + 1)] = -p.im;
            a[(2 * k + 1, 2 * j)] = p.im;
            a[(2 * k + 1, 2 * j + 1)] = p.re;
        }
        b[2 * k] = d.y[k].re;
        b[2 * k + 1] = d.y[k].im;
    }
    let x = plant::lstsq(&a, &b, 1e-12).unwrap_or_else(|_| DVector::zeros(2 * LINEAR));
    let r = &a * &x - b;
    let mut coef = [Complex64::new(0.0, 0.0); LINEAR];
    for (j, c) in coef.iter_mut().enumerate() {
        *c = Complex64::new(x[2 * j], x[2 * j + 1]);
    }
    (r, coef)
}

fn fit_resonance(d: &FitData, wn0: f64) -> Result<Resonance> {
    let rss = |wn: f64, z: f64| projected(d, wn, z).0.norm_squared();
    // start: the best damping ratio of a coarse grid at the peak frequency
    let mut p = Vector2::new(wn0, 0.02);
    let mut best = f64::INFINITY;
    for z in [0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2] {
        let v = rss(wn0, z);
        if v < best {
            best = v;
            p[1] = z;
        }
    }
    let jac = |p: &Vector2<f64>| {
        let (hw, hz) = (1e-6 * p[0], 1e-6 * p[1].max(1e-3));
        let c0 = (projected(d, p[0] + hw, p[1]).0 - projected(d, p[0] - hw, p[1]).0) / (2.0 * hw);
        let c1 = (projected(d, p[0], p[1] + hz).0 - projected(d, p[0], p[1] - hz).0) / (2.0 * hz);
        DMatrix::from_columns(&[c0, c1])
    };
    let mut lambda = 1e-3;
    let mut r = projected(d, p[0], p[1]).0;
    let mut cost = r.norm_squared();
    for _ in 0..200 {
        let j = jac(&p);
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        let mut improved = false;
        let mut converged = false;
        for _ in 0..30 {
            let m = Matrix2::new(jtj[(0, 0)] * (1.0 + lambda), jtj[(0, 1)], jtj[(1, 0)], jtj[(1, 1)] * (1.0 + lambda));
            let Some(inv) = m.try_inverse() else {
                lambda *= 10.0;
                continue;
            };
            let step = -(inv * Vector2::new(g[0], g[1]));
            let trial = Vector2::new(p[0] + step[0], (p[1] + step[1]).clamp(1e-6, 2.0));
            let rt = projected(d, trial[0], trial[1]).0;
            let ct = rt.norm_squared();
            if ct < cost {
                converged = (cost - ct) <= 1e-12 * cost;
                p = trial;
                r = rt;
                cost = ct;
                lambda = (lambda / 3.0).max(1e-12);
                improved = true;
                break;
            }
            lambda *= 4.0;
        }
        if !improved || converged {
            break;
        }
    }
    let j = jac(&p);
    let dof = (r.len() as f64 - 2.0 * LINEAR as f64 - 2.0).max(1.0);
    let s2 = cost / dof;
    let cov =
        (j.transpose() * &j).try_inverse().ok_or_else(|| IdentError::Data("the resonance fit is singular".into()))?
            * s2;
    let (_, coef) = projected(d, p[0], p[1]);
    if !(p[0] > 0.0 && cov[(0, 0)].is_finite()) {
        return Err(IdentError::Data("the resonance fit did not converge".into()));
    }
    Ok(Resonance { wn: p[0], zeta: p[1], sigma_wn: cov[(0, 0)].sqrt(), residue: coef[2], residual: r })
}
