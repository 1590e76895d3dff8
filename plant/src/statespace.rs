//! Continuous state space x' = A x + B u, y = C x + D u (eqs. (35)–(38)), in python-control's words.

use nalgebra::DMatrix;
use serde::Serialize;

use crate::error::Result;
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
        crate::error::positive(|| "dt_s", dt_s, "s")?;
        let (n, m) = (self.a.nrows(), self.b.ncols());
        let mut aug = DMatrix::zeros(n + m, n + m);
        aug.view_mut((0, 0), (n, n)).copy_from(&(&self.a * dt_s));
        aug.view_mut((0, n), (n, m)).copy_from(&(&self.b * dt_s));
        let e = aug.exp();
        Ok(DiscreteStateSpace {
            ad: e.view((0, 0), (n, n)).into_owned(),
            bd: e.view((0, n), (n, m)).into_owned(),
            c: self.c.clone(),
            d: self.d.clone(),
            dt_s,
        })
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
