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
