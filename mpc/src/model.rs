//! The prediction model: a plant state space, reduced to the part its outputs see, held by a
//! zero-order hold.

use nalgebra::DMatrix;
use plant::statespace::StateSpace;

use crate::error::{MpcError, Result};

/// x[k+1] = A x[k] + B u[k], y[k] = C x[k] in coordinates z = Vᵀ x_plant that the outputs
/// observe. The rig's absolute angles (and, with the open differential, the antiphase angle)
/// are seen by no speed or torque: they are integrators a Kalman filter cannot estimate and a
/// Riccati equation cannot stabilise, so they are removed — the unobservable subspace of
/// (A, C) is A-invariant, so z keeps the outputs' dynamics exactly.
#[derive(Debug, Clone)]
pub struct PredictionModel {
    /// Discrete system matrix.
    pub a: DMatrix<f64>,
    /// Discrete input matrix (inputs in the plant's units, Nm).
    pub b: DMatrix<f64>,
    /// All plant outputs in the reduced coordinates.
    pub c: DMatrix<f64>,
    /// Orthonormal basis V of the observable subspace: z = Vᵀ x_plant.
    pub basis: DMatrix<f64>,
    /// Sample time, s.
    pub dt_s: f64,
    /// The plant's input names.
    pub input_names: Vec<String>,
    /// The plant's output names.
    pub output_names: Vec<String>,
}

impl PredictionModel {
    /// Reduces `plant` to its observable part and discretises it by ZOH with `dt_s`.
    pub fn new(plant: &StateSpace, dt_s: f64) -> Result<Self> {
        let n = plant.nstates();
        if n == 0 || plant.c.nrows() == 0 || plant.b.ncols() == 0 {
            return Err(MpcError::Numerical("the plant has no states, inputs or outputs".into()));
        }
        // Observability matrix of (A τ, C_normalised): τ = 1/‖A‖ and unit output rows keep
        // the powers bounded, so a structural rank loss shows as σ ≈ 1e-16 against σ ≈ 1.
        let tau = 1.0 / plant.a.norm().max(1e-300);
        let a_n = &plant.a * tau;
        let mut c_n = plant.c.clone();
        for mut row in c_n.row_iter_mut() {
            let norm = row.norm();
            if norm > 0.0 {
                row /= norm;
            }
        }
        let p = c_n.nrows();
        let mut o = DMatrix::zeros(p * n, n);
        let mut block = c_n.clone();
        for k in 0..n {
            o.view_mut((k * p, 0), (p, n)).copy_from(&block);
            block = &block * &a_n;
        }
        let svd = o.svd(false, true);
        let vt = svd.v_t.ok_or_else(|| MpcError::Numerical("observability SVD failed".into()))?;
        let smax = svd.singular_values.max();
        let keep: Vec<usize> =
            (0..svd.singular_values.len()).filter(|&i| svd.singular_values[i] > 1e-9 * smax).collect();
        let basis = DMatrix::from_fn(n, keep.len(), |i, j| vt[(keep[j], i)]);
        let reduced = StateSpace {
            a: basis.transpose() * &plant.a * &basis,
            b: basis.transpose() * &plant.b,
            c: &plant.c * &basis,
            d: plant.d.clone(),
            state_names: (0..keep.len()).map(|i| format!("z{i}")).collect(),
            input_names: plant.input_names.clone(),
            output_names: plant.output_names.clone(),
        };
        let disc = reduced.c2d(dt_s)?;
        Ok(PredictionModel {
            a: disc.ad,
            b: disc.bd,
            c: reduced.c,
            basis,
            dt_s,
            input_names: plant.input_names.clone(),
            output_names: plant.output_names.clone(),
        })
    }

    /// Number of (reduced) states.
    pub fn nstates(&self) -> usize {
        self.a.nrows()
    }

    /// Number of inputs.
    pub fn ninputs(&self) -> usize {
        self.b.ncols()
    }

    /// Index of the input called `name`.
    pub fn input(&self, key: &str, name: &str) -> Result<usize> {
        find(key, "input", name, &self.input_names)
    }

    /// Index of the output called `name`.
    pub fn output(&self, key: &str, name: &str) -> Result<usize> {
        find(key, "output", name, &self.output_names)
    }
}

fn find(key: &str, kind: &'static str, name: &str, names: &[String]) -> Result<usize> {
    names.iter().position(|n| n == name).ok_or_else(|| MpcError::UnknownSignal {
        key: key.into(),
        kind,
        name: name.into(),
        available: names.join(", "),
    })
}
