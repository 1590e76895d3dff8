//! Continuous state space x' = A x + B u, y = C x + D u (eqs. (35)–(38)), in python-control's words.

use nalgebra::DMatrix;
use serde::Serialize;

use crate::error::{PlantError, Result};
use crate::modal::{damp, Pole};

/// A continuous-time linear state-space system with named signals (SI units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StateSpace {
    /// System matrix A.
    pub a: DMatrix<f64>,
    /// Input matrix B.
    pub b: DMatrix<f64>,
    /// Output matrix C.
    pub c: DMatrix<f64>,
    /// Feed-through matrix D.
    pub d: DMatrix<f64>,
    /// State names (`phi_*` in rad, `w_*` in rad/s).
    pub state_names: Vec<String>,
    /// Input names (`M_*` in Nm).
    pub input_names: Vec<String>,
    /// Output names.
    pub output_names: Vec<String>,
}

/// Largest ‖[A B]·dt‖₁ [`zoh`] takes: the matrix exponential scales it down by 2^s and squares s
/// times, and each squaring can double the relative round-off, so 2^30 keeps that below 1e-7
/// (and keeps a step far longer than the model's time scales from looking like a result).
pub const ZOH_MAX_NORM: f64 = (1u64 << 30) as f64;

/// Zero-order-hold discretisation of x' = A x + B u over `dt_s`: (Ad, Bd) from the exponential of
/// the augmented matrix [[A, B], [0, 0]]·dt. Refuses non-finite matrices and a step so long
/// against the model's time scales (‖[A B]‖₁·dt > [`ZOH_MAX_NORM`]) that the exponential would
/// be round-off, or — with non-finite entries — would square for ever.
pub fn zoh(a: &DMatrix<f64>, b: &DMatrix<f64>, dt_s: f64) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    crate::error::positive(|| "dt_s", dt_s, "s")?;
    let (n, m) = (a.nrows(), b.ncols());
    if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
        return Err(PlantError::Numerical("the state-space matrices have non-finite entries".into()));
    }
    let mut aug = DMatrix::zeros(n + m, n + m);
    aug.view_mut((0, 0), (n, n)).copy_from(&(a * dt_s));
    aug.view_mut((0, n), (n, m)).copy_from(&(b * dt_s));
    let e = block_exponential(&aug, dt_s)?;
    Ok((e.view((0, 0), (n, n)).into_owned(), e.view((0, n), (n, m)).into_owned()))
}

/// The exponential of an augmented matrix already scaled by the step `dt_s` (Van Loan's block
/// exponential: [`zoh`]'s, `integrate::ForcedMaps`'), refused where ‖·‖₁ exceeds
/// [`ZOH_MAX_NORM`] or the result overflows.
pub(crate) fn block_exponential(aug: &DMatrix<f64>, dt_s: f64) -> Result<DMatrix<f64>> {
    let norm = aug.column_iter().map(|c| c.lp_norm(1)).fold(0.0, f64::max);
    if norm.is_nan() || norm > ZOH_MAX_NORM {
        return Err(PlantError::Numerical(format!(
            "a step of {dt_s} s is {norm:.3e} times the model's fastest time scale: too long to discretise \
             exactly (at most {ZOH_MAX_NORM:.3e})"
        )));
    }
    let e = aug.exp();
    if e.iter().any(|v| !v.is_finite()) {
        return Err(PlantError::Numerical(format!("the discretisation over {dt_s} s overflows")));
    }
    Ok(e)
}

/// Least-squares solution of a x ≈ b by SVD (singular values at or below `eps` dropped), with
/// the SVD's iterations bounded: non-finite entries, or an SVD that does not converge (entries
/// so large that its intermediates overflow), are errors instead of an endless loop.
pub fn lstsq(a: &DMatrix<f64>, b: &nalgebra::DVector<f64>, eps: f64) -> Result<nalgebra::DVector<f64>> {
    if a.is_empty() || a.nrows() != b.len() {
        return Err(PlantError::Numerical(format!(
            "a least-squares problem of {}×{} with {} right-hand sides",
            a.nrows(),
            a.ncols(),
            b.len()
        )));
    }
    if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
        return Err(PlantError::Numerical("a least-squares problem has non-finite entries".into()));
    }
    let svd = nalgebra::SVD::try_new(a.clone(), true, true, f64::EPSILON, 10_000)
        .ok_or_else(|| PlantError::Numerical("the SVD of a least-squares problem did not converge".into()))?;
    let x = svd.solve(b, eps).map_err(|e| PlantError::Numerical(e.to_string()))?;
    if x.iter().any(|v| !v.is_finite()) {
        return Err(PlantError::Numerical("a least-squares solution is not finite".into()));
    }
    Ok(x)
}

impl StateSpace {
    /// Number of states.
    pub fn nstates(&self) -> usize {
        self.a.nrows()
    }

    /// Poles with natural frequency, damped frequency and damping ratio (python-control `damp`).
    pub fn damp(&self) -> Result<Vec<Pole>> {
        damp(&self.a)
    }
}

/// A discrete-time state space x[k+1] = Ad x[k] + Bd u[k], y[k] = C x[k] + D u[k].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiscreteStateSpace {
    /// State transition Ad = e^{A dt}.
    pub ad: DMatrix<f64>,
    /// Input matrix Bd = ∫₀^dt e^{Aτ} dτ B.
    pub bd: DMatrix<f64>,
    /// Output matrix.
    pub c: DMatrix<f64>,
    /// Feed-through.
    pub d: DMatrix<f64>,
    /// Sample time, s.
    pub dt_s: f64,
}

impl StateSpace {
    /// Zero-order-hold discretisation (python-control `c2d(sys, dt, 'zoh')`): the exponential
    /// of the augmented matrix [[A, B], [0, 0]]·dt holds Ad and Bd; exact for inputs held
    /// constant over each step.
    pub fn c2d(&self, dt_s: f64) -> Result<DiscreteStateSpace> {
        let (ad, bd) = zoh(&self.a, &self.b, dt_s)?;
        Ok(DiscreteStateSpace { ad, bd, c: self.c.clone(), d: self.d.clone(), dt_s })
    }

    /// Response to inputs sampled every `dt_s` and held between samples (python-control
    /// `lsim` with ZOH): `u` has one row per sample and one column per input; returns the
    /// outputs, one row per sample, starting from `x0`.
    pub fn lsim(&self, u: &DMatrix<f64>, dt_s: f64, x0: &nalgebra::DVector<f64>) -> Result<DMatrix<f64>> {
        Ok(self.c2d(dt_s)?.simulate(u, x0))
    }
}

impl DiscreteStateSpace {
    /// Outputs for the input rows `u`, from state `x0`.
    pub fn simulate(&self, u: &DMatrix<f64>, x0: &nalgebra::DVector<f64>) -> DMatrix<f64> {
        let mut x = x0.clone();
        let mut y = DMatrix::zeros(u.nrows(), self.c.nrows());
        for k in 0..u.nrows() {
            let uk = u.row(k).transpose();
            y.set_row(k, &(&self.c * &x + &self.d * &uk).transpose());
            x = &self.ad * &x + &self.bd * &uk;
        }
        y
    }
}
