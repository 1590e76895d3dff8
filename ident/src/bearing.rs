//! Bearing and seal force coefficients from two shake tests (San Andrés 2011, slides 13–31).
//!
//! 1. **Impedances** (slides 15–19): DFT of forces and displacements of both tests; at every
//!    excited line H = [F1 F2][Z1 Z2]⁻¹. Periodic excitation is averaged over its periods;
//!    otherwise an H1-type estimate G = (Σ Z Fᴴ)(Σ F Fᴴ)⁻¹ over Hann-windowed segments, H = G⁻¹.
//!    The condition number of [Z1 Z2] per line tells whether the two tests are independent
//!    enough (slide 20).
//! 2. **Direct curve fit** (slide 21): Re H = (K + Kh) − ω²(M + Mh), Im H = ω(C + Ch) by least
//!    squares on the impedances.
//! 3. **Instrumental variable filter method** (slides 24–31, Fritzen 1985): G(ω_k) H(ω_k) = I + e
//!    is linear in the coefficients; least squares first (slide 28), then the instruments W built
//!    from the analytical, noise-free flexibilities of the last estimate replace the measured
//!    ones, p = (WᵀA)⁻¹ Wᵀ b, until the estimate settles (slide 29). The measured flexibility's
//!    noise enters AᵀA squared — a bias — but WᵀA only linearly (slide 30).
//!
//! The support is known (dry tests): the element's coefficients are fitted with the support's
//! impedance held fixed, so the declared structure (`KC` without inertia, `KCM` with; `direct`
//! or `full` coupling) constrains the element only.

use nalgebra::{DMatrix, DVector, Matrix2};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use crate::error::{IdentError, Result};
use plant::{Coefficients, Support};

/// One shake test: forces and displacements, uniformly sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct ShakeTest {
    /// Sample time, s.
    pub dt_s: f64,
    /// Force along x, N.
    pub force_x_n: Vec<f64>,
    /// Force along y, N.
    pub force_y_n: Vec<f64>,
    /// Displacement along x, m.
    pub disp_x_m: Vec<f64>,
    /// Displacement along y, m.
    pub disp_y_m: Vec<f64>,
}

/// How the spectra were averaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Averaging {
    /// Periodic excitation: the record's periods averaged.
    Periodic {
        /// Periods per record.
        periods: usize,
    },
    /// Other excitation: H1 over Hann-windowed, half-overlapping segments.
    H1 {
        /// Segments per test.
        segments: usize,
    },
    /// Spectra given directly.
    Given,
}

/// The measured impedances on the excited lines.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Impedances {
    /// Line frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// H at each line, N/m.
    pub h: Vec<Matrix2<Complex64>>,
    /// G = H⁻¹ at each line, m/N.
    pub g: Vec<Matrix2<Complex64>>,
    /// Condition number of [Z1 Z2] at each line (slide 20).
    pub condition: Vec<f64>,
    /// Averaging used.
    pub averaging: Averaging,
}

/// Above this condition number of [Z1 Z2] a line is flagged: the two tests' motions are too
/// alike to separate the four impedances (slide 20). 10 means the weaker direction carries a
/// tenth of the information of the stronger.
pub const CONDITION_WARNING: f64 = 10.0;

/// Above this condition number of [Z1 Z2] a line carries no usable information (the weaker
/// direction is a millionth of the stronger: below any sensor's resolution) and is left out.
/// Two tests that are one test twice, or a test that did not move, give infinity on every line;
/// when more than half of the lines are left out the identification refuses the data.
pub const CONDITION_UNUSABLE: f64 = 1e6;

fn cond2(z: &Matrix2<Complex64>) -> f64 {
    // singular values of a 2×2 complex matrix from the eigenvalues of ZᴴZ
    let h = z.adjoint() * z;
    let (a, d, b) = (h[(0, 0)].re, h[(1, 1)].re, h[(0, 1)].norm());
    let mean = 0.5 * (a + d);
    let r = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (hi, lo) = (mean + r, (mean - r).max(0.0));
    if lo == 0.0 {
        f64::INFINITY
    } else {
        (hi / lo).sqrt()
    }
}

fn dft_lines(x: &[f64], window: &[f64], bins: &[usize]) -> Vec<Complex64> {
    // the few excited lines of one segment, summed directly: O(n · lines)
    let n = x.len();
    bins.iter()
        .map(|&k| {
            let w = -2.0 * PI * k as f64 / n as f64;
            x.iter()
                .zip(window)
                .enumerate()
                .fold(Complex64::new(0.0, 0.0), |acc, (i, (&v, &h))| acc + Complex64::from_polar(v * h, w * i as f64))
        })
        .collect()
}

impl ShakeTest {
    fn check(&self, name: &str) -> Result<usize> {
        let n = self.force_x_n.len();
        if [self.force_y_n.len(), self.disp_x_m.len(), self.disp_y_m.len()].iter().any(|&l| l != n) {
            return Err(IdentError::Data(format!("{name}: signals differ in length")));
        }
        if n < 64 {
            return Err(IdentError::Data(format!("{name}: {n} samples are too few")));
        }
        if self.dt_s.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(IdentError::Data(format!("{name}: sample time must be positive")));
        }
        let all = [&self.force_x_n, &self.force_y_n, &self.disp_x_m, &self.disp_y_m];
        if all.iter().any(|s| s.iter().any(|v| !v.is_finite())) {
            return Err(IdentError::Data(format!("{name}: a signal has a non-finite value")));
        }
        Ok(n)
    }

    fn primary_force(&self) -> &[f64] {
        let var = |s: &[f64]| {
            let m = s.iter().sum::<f64>() / s.len() as f64;
            s.iter().map(|v| (v - m) * (v - m)).sum::<f64>()
        };
        if var(&self.force_x_n) >= var(&self.force_y_n) {
            &self.force_x_n
        } else {
            &self.force_y_n
        }
    }

    /// Lines of the full-record DFT in the band where the primary force has at least 5 % of its
    /// largest amplitude there.
    fn excited_bins(&self, band: (f64, f64)) -> Vec<usize> {
        let x = crate::signal::detrend(self.primary_force());
        let spec = crate::signal::rfft(&x);
        let df = 1.0 / (x.len() as f64 * self.dt_s);
        // half a line of tolerance: time stamps rounded in a CSV move the lines a hair
        let inband: Vec<usize> =
            (1..spec.len()).filter(|&k| (band.0 - 0.5 * df..=band.1 + 0.5 * df).contains(&(k as f64 * df))).collect();
        let max = inband.iter().map(|&k| spec[k].norm()).fold(0.0, f64::max);
        inband.into_iter().filter(|&k| spec[k].norm() >= 0.05 * max && max > 0.0).collect()
    }

    /// Periods per record if the excitation is periodic: the excited lines share a divisor P
    /// and consecutive periods of the primary force repeat to within 10 % of its RMS.
    fn periods(&self, bins: &[usize]) -> Option<usize> {
        fn gcd(a: usize, b: usize) -> usize {
            if b == 0 {
                a
            } else {
                gcd(b, a % b)
            }
        }
        let n = self.force_x_n.len();
        let p = bins.iter().fold(0, |g, &k| gcd(g, k));
        if p < 2 || !n.is_multiple_of(p) {
            return None;
        }
        let len = n / p;
        let f = self.primary_force();
        let rms = (f.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let diff = (0..len * (p - 1)).map(|i| (f[i + len] - f[i]).powi(2)).sum::<f64>() / (len * (p - 1)) as f64;
        (diff.sqrt() <= 0.1 * rms).then_some(p)
    }
}

impl Impedances {
    /// From the two shake tests, on the lines excited in both within `band_hz`.
    pub fn from_tests(tests: [&ShakeTest; 2], band_hz: (f64, f64)) -> Result<Impedances> {
        let n = tests[0].check("test 1")?;
        if tests[1].check("test 2")? != n || (tests[0].dt_s - tests[1].dt_s).abs() > 1e-9 * tests[0].dt_s {
            return Err(IdentError::Data("the two tests differ in length or sample time".into()));
        }
        let dt = tests[0].dt_s;
        let bins = [tests[0].excited_bins(band_hz), tests[1].excited_bins(band_hz)];
        let periods = match (tests[0].periods(&bins[0]), tests[1].periods(&bins[1])) {
            (Some(a), Some(b)) if a == b => Some(a),
            _ => None,
        };
        // segments: the periods (rectangular window), or Hann segments of an eighth of the
        // record with half overlap
        let (seg_len, starts, window, averaging): (usize, Vec<usize>, Vec<f64>, Averaging) = match periods {
            Some(p) => {
                (n / p, (0..p).map(|i| i * n / p).collect(), vec![1.0; n / p], Averaging::Periodic { periods: p })
            }
            None => {
                let len = (n / 8).max(64);
                let starts: Vec<usize> = (0..).map(|i| i * len / 2).take_while(|s| s + len <= n).collect();
                let hann = (0..len).map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / len as f64).cos()).collect();
                let segs = starts.len();
                (len, starts, hann, Averaging::H1 { segments: segs })
            }
        };
        let scale = (n / seg_len) as f64; // full-record bin k ↔ segment bin k / scale
        let seg_bins: Vec<usize> = {
            let mut common: Vec<usize> = bins[0]
                .iter()
                .filter(|k| bins[1].contains(k))
                .map(|&k| (k as f64 / scale).round() as usize)
                .filter(|&k| k > 0)
                .collect();
            if periods.is_none() {
                // a segment's lines are coarser: every segment line in the band where both tests are excited
                let df = 1.0 / (seg_len as f64 * dt);
                common = (1..seg_len / 2).filter(|&k| (band_hz.0..=band_hz.1).contains(&(k as f64 * df))).collect();
            }
            common.sort_unstable();
            common.dedup();
            common
        };
        if seg_bins.is_empty() {
            return Err(IdentError::Data(format!(
                "no line in {}–{} Hz is excited by both tests",
                band_hz.0, band_hz.1
            )));
        }
        // per line: Σ Z Fᴴ, Σ F Fᴴ, Σ Z Zᴴ over segments; columns of F and Z are the two tests
        let m = seg_bins.len();
        let zero = Matrix2::<Complex64>::zeros();
        let (mut szf, mut sff, mut szz) = (vec![zero; m], vec![zero; m], vec![zero; m]);
        let mut zmean = vec![zero; m];
        for &s in &starts {
            let mut f = vec![zero; m];
            let mut z = vec![zero; m];
            for (t, test) in tests.iter().enumerate() {
                // no detrending: a period of a multisine has a slope of its own, and removing it
                // would distort the low lines; an offset only touches line 0
                let sig = |x: &[f64]| dft_lines(&x[s..s + seg_len], &window, &seg_bins);
                let (fx, fy, zx, zy) =
                    (sig(&test.force_x_n), sig(&test.force_y_n), sig(&test.disp_x_m), sig(&test.disp_y_m));
                for l in 0..m {
                    f[l][(0, t)] = fx[l];
                    f[l][(1, t)] = fy[l];
                    z[l][(0, t)] = zx[l];
                    z[l][(1, t)] = zy[l];
                }
            }
            for l in 0..m {
                szf[l] += z[l] * f[l].adjoint();
                sff[l] += f[l] * f[l].adjoint();
                szz[l] += z[l] * z[l].adjoint();
                zmean[l] += z[l];
            }
        }
        let df = 1.0 / (seg_len as f64 * dt);
        let mut out = Impedances { frequencies_hz: vec![], h: vec![], g: vec![], condition: vec![], averaging };
        for l in 0..m {
            // slide 20 for periodic data (the averaged [Z1 Z2]); the H1 analogue √cond(Σ Z Zᴴ)
            let condition = match periods {
                Some(_) => cond2(&zmean[l]),
                // Σ Z Zᴴ is Hermitian: its condition is the squared one of the motions
                None => cond2(&szz[l]).sqrt(),
            };
            if condition.is_nan() || condition > CONDITION_UNUSABLE {
                continue;
            }
            let Some(sffi) = sff[l].try_inverse() else { continue };
            let g = szf[l] * sffi;
            let Some(h) = g.try_inverse() else { continue };
            if g.iter().chain(h.iter()).any(|c| !(c.re.is_finite() && c.im.is_finite())) {
                continue;
            }
            out.frequencies_hz.push(seg_bins[l] as f64 * df);
            out.h.push(h);
            out.g.push(g);
            out.condition.push(condition);
        }
        if 2 * out.h.len() < m.max(1) {
            return Err(IdentError::Data(format!(
                "only {} of {m} excited lines separate the two tests (condition number of [Z1 Z2] at most {:.0e}): \
                 the tests are not independent — are they two different runs, each excited and moving?",
                out.h.len(),
                CONDITION_UNUSABLE
            )));
        }
        Ok(out)
    }

    /// From spectra given per line: forces F and displacements Z as 2×2 matrices whose columns
    /// are the two tests (slide 19).
    pub fn from_spectra(
        frequencies_hz: &[f64],
        f: &[Matrix2<Complex64>],
        z: &[Matrix2<Complex64>],
    ) -> Result<Impedances> {
        let mut out =
            Impedances { frequencies_hz: vec![], h: vec![], g: vec![], condition: vec![], averaging: Averaging::Given };
        for ((&fr, fl), zl) in frequencies_hz.iter().zip(f).zip(z) {
            let zi = zl.try_inverse().ok_or_else(|| IdentError::Data(format!("[Z1 Z2] is singular at {fr} Hz")))?;
            let h = fl * zi;
            out.frequencies_hz.push(fr);
            out.g.push(h.try_inverse().ok_or_else(|| IdentError::Data(format!("H is singular at {fr} Hz")))?);
            out.h.push(h);
            out.condition.push(cond2(zl));
        }
        Ok(out)
    }

    /// Largest condition number over the lines.
    pub fn condition_max(&self) -> f64 {
        self.condition.iter().copied().fold(0.0, f64::max)
    }

    /// Lines whose condition number exceeds [`CONDITION_WARNING`].
    pub fn ill_conditioned_hz(&self) -> Vec<f64> {
        self.frequencies_hz
            .iter()
            .zip(&self.condition)
            .filter(|(_, &c)| c > CONDITION_WARNING)
            .map(|(&f, _)| f)
            .collect()
    }
}

/// Which coefficients the element has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Structure {
    /// Stiffness and damping.
    KC,
    /// Stiffness, damping and inertia.
    KCM,
}

/// Which entries of the coefficient matrices are free.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Coupling {
    /// xx and yy only.
    Direct,
    /// All four.
    Full,
}

/// The estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Curve fit of the impedances (slide 21).
    Direct,
    /// Least squares on the flexibility equations G H = I (slide 28, IVFM's first step).
    LeastSquares,
    /// The instrumental variable filter method (slides 24–31).
    Ivfm,
}

/// Iteration limits of the IVFM.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IvfmSettings {
    /// Most iterations after the least-squares start.
    pub max_iterations: usize,
    /// Converged when no coefficient changes by more than this fraction of its scale.
    pub tolerance: f64,
}

impl Default for IvfmSettings {
    fn default() -> Self {
        IvfmSettings { max_iterations: 50, tolerance: 1e-10 }
    }
}

/// r² of the real and imaginary part of each impedance (slide 22).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct R2 {
    /// [re, im] of H_xx.
    #[serde(rename = "Hxx")]
    pub hxx: [f64; 2],
    /// [re, im] of H_xy.
    #[serde(rename = "Hxy")]
    pub hxy: [f64; 2],
    /// [re, im] of H_yx.
    #[serde(rename = "Hyx")]
    pub hyx: [f64; 2],
    /// [re, im] of H_yy.
    #[serde(rename = "Hyy")]
    pub hyy: [f64; 2],
}

impl R2 {
    /// The lowest r² of the direct impedances' parts (H_xx and H_yy, real and imaginary).
    pub fn lowest_direct(&self) -> f64 {
        [self.hxx[0], self.hxx[1], self.hyy[0], self.hyy[1]].into_iter().fold(f64::INFINITY, f64::min)
    }
}

/// The lowest r² of the direct impedances at which a fitted structure reproduces them
/// (`rigtwin bearing` names a structure that does where the fitted one does not).
pub const MIN_DIRECT_R2: f64 = 0.99;

/// An identified element.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BearingFit {
    /// Estimator.
    pub method: Method,
    /// Structure fitted.
    pub structure: Structure,
    /// Coupling fitted.
    pub coupling: Coupling,
    /// The element's coefficients (support subtracted).
    pub element: Coefficients,
    /// r² of every impedance term (system model against measured H).
    pub r2: R2,
    /// IVFM iterations after the least-squares start (0 for the others).
    pub iterations: usize,
    /// Whether the IVFM settled within its limits.
    pub converged: bool,
}

/// The free coefficients: (matrix 0 = K, 1 = C, 2 = M; row; column).
pub(crate) fn unknowns(structure: Structure, coupling: Coupling) -> Vec<(usize, usize, usize)> {
    let entries: Vec<(usize, usize)> = match coupling {
        Coupling::Direct => vec![(0, 0), (1, 1)],
        Coupling::Full => vec![(0, 0), (0, 1), (1, 0), (1, 1)],
    };
    let mats: Vec<usize> = match structure {
        Structure::KC => vec![0, 1],
        Structure::KCM => vec![0, 1, 2],
    };
    mats.iter().flat_map(|&m| entries.iter().map(move |&(i, j)| (m, i, j))).collect()
}

/// The element impedance's derivative with respect to one unknown at ω: 1, iω or −ω² at (i, j).
fn basis(u: (usize, usize, usize), omega: f64) -> Matrix2<Complex64> {
    let mut b = Matrix2::zeros();
    b[(u.1, u.2)] = match u.0 {
        0 => Complex64::new(1.0, 0.0),
        1 => Complex64::new(0.0, omega),
        _ => Complex64::new(-omega * omega, 0.0),
    };
    b
}

pub(crate) fn coefficients(us: &[(usize, usize, usize)], p: &DVector<f64>) -> Coefficients {
    let mut c = Coefficients::default();
    for (u, &v) in us.iter().zip(p.iter()) {
        let m = match u.0 {
            0 => &mut c.k_n_per_m,
            1 => &mut c.c_ns_per_m,
            _ => &mut c.m_kg,
        };
        m[u.1][u.2] = v;
    }
    c
}

fn support_impedance(s: &Support, omega: f64) -> Matrix2<Complex64> {
    s.coefficients().impedance(omega)
}

/// Real rows (re and im of the four entries) of a list of 2×2 complex matrices.
fn rows(ms: &[Matrix2<Complex64>]) -> DVector<f64> {
    DVector::from_iterator(
        8 * ms.len(),
        ms.iter().flat_map(|m| [m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]].into_iter().flat_map(|c| [c.re, c.im])),
    )
}

/// Solves the column-scaled linear least-squares problem a p ≈ b.
pub(crate) fn least_squares(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>> {
    let scale = DVector::from_iterator(a.ncols(), a.column_iter().map(|c| c.norm().max(1e-300)));
    let mut an = a.clone();
    for (j, mut c) in an.column_iter_mut().enumerate() {
        c /= scale[j];
    }
    let q = plant::lstsq(&an, b, 1e-12).map_err(|e| IdentError::Data(format!("least squares failed: {e}")))?;
    Ok(q.component_div(&scale))
}

/// Fits the element's coefficients to the impedances.
pub fn fit(
    imp: &Impedances,
    support: &Support,
    structure: Structure,
    coupling: Coupling,
    method: Method,
    settings: &IvfmSettings,
) -> Result<BearingFit> {
    let us = unknowns(structure, coupling);
    let n = imp.h.len();
    if 8 * n < us.len() + 1 {
        return Err(IdentError::Data(format!("{n} lines are too few for {} coefficients", us.len())));
    }
    let omegas: Vec<f64> = imp.frequencies_hz.iter().map(|f| 2.0 * PI * f).collect();
    // the linear system: one column per unknown, 8 real rows per line
    let build = |g: Option<&[Matrix2<Complex64>]>| -> DMatrix<f64> {
        let mut a = DMatrix::zeros(8 * n, us.len());
        for (j, &u) in us.iter().enumerate() {
            let col: Vec<Matrix2<Complex64>> = (0..n)
                .map(|k| {
                    let b = basis(u, omegas[k]);
                    match g {
                        Some(g) => g[k] * b, // flexibility equations: G·∂H
                        None => b,           // impedance equations: ∂H
                    }
                })
                .collect();
            a.set_column(j, &rows(&col));
        }
        a
    };
    let (p, iterations, converged) = match method {
        Method::Direct => {
            // slide 21: H_meas − H_support = H_element(p)
            let rhs: Vec<Matrix2<Complex64>> =
                (0..n).map(|k| imp.h[k] - support_impedance(support, omegas[k])).collect();
            (least_squares(&build(None), &rows(&rhs))?, 0, true)
        }
        Method::LeastSquares | Method::Ivfm => {
            // slides 25–28: G (H_support + H_element(p)) = I  →  G ∂H p = I − G H_support
            let a = build(Some(&imp.g));
            let rhs: Vec<Matrix2<Complex64>> =
                (0..n).map(|k| Matrix2::identity() - imp.g[k] * support_impedance(support, omegas[k])).collect();
            let b = rows(&rhs);
            let mut p = least_squares(&a, &b)?;
            let mut iterations = 0;
            let mut converged = method == Method::LeastSquares;
            if method == Method::Ivfm {
                let scale = DVector::from_iterator(a.ncols(), a.column_iter().map(|c| c.norm().max(1e-300)));
                for _ in 0..settings.max_iterations {
                    // slide 29: instruments from the analytical flexibilities of the last estimate
                    let element = coefficients(&us, &p);
                    let ganalytic: Option<Vec<Matrix2<Complex64>>> = (0..n)
                        .map(|k| (element.impedance(omegas[k]) + support_impedance(support, omegas[k])).try_inverse())
                        .collect();
                    let Some(ga) = ganalytic else { break };
                    let w = build(Some(&ga));
                    let (mut ws, mut as_) = (w.clone(), a.clone());
                    for j in 0..a.ncols() {
                        ws.column_mut(j).scale_mut(1.0 / scale[j]);
                        as_.column_mut(j).scale_mut(1.0 / scale[j]);
                    }
                    let lhs = ws.transpose() * &as_;
                    let Some(q) = lhs.lu().solve(&(ws.transpose() * &b)) else { break };
                    let next = q.component_div(&scale);
                    iterations += 1;
                    let change = (&next - &p)
                        .component_div(&next.map(|v| v.abs()).sup(&p.map(|v| v.abs())).map(|v| v.max(1e-300)))
                        .amax();
                    p = next;
                    if change < settings.tolerance {
                        converged = true;
                        break;
                    }
                }
            }
            (p, iterations, converged)
        }
    };
    let element = coefficients(&us, &p);
    Ok(BearingFit { method, structure, coupling, r2: r2(imp, support, &element), element, iterations, converged })
}

/// r² = 1 − Σ(y − ŷ)²/Σ(y − ȳ)² of the system impedance's real and imaginary parts.
pub fn r2(imp: &Impedances, support: &Support, element: &Coefficients) -> R2 {
    let model: Vec<Matrix2<Complex64>> = imp
        .frequencies_hz
        .iter()
        .map(|f| {
            let w = 2.0 * PI * f;
            element.impedance(w) + support_impedance(support, w)
        })
        .collect();
    r2_against(imp, &model)
}

/// r² of every impedance term of `model` (one matrix per line) against the measured ones.
pub fn r2_against(imp: &Impedances, model: &[Matrix2<Complex64>]) -> R2 {
    let term = |i: usize, j: usize| -> [f64; 2] {
        let one = |part: fn(&Complex64) -> f64| {
            let y: Vec<f64> = imp.h.iter().map(|h| part(&h[(i, j)])).collect();
            let yh: Vec<f64> = model.iter().map(|h| part(&h[(i, j)])).collect();
            let mean = y.iter().sum::<f64>() / y.len() as f64;
            let ss_tot: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
            let ss_res: f64 = y.iter().zip(&yh).map(|(a, b)| (a - b).powi(2)).sum();
            if ss_tot > 0.0 {
                1.0 - ss_res / ss_tot
            } else {
                f64::NAN
            }
        };
        [one(|c| c.re), one(|c| c.im)]
    };
    R2 { hxx: term(0, 0), hxy: term(0, 1), hyx: term(1, 0), hyy: term(1, 1) }
}
