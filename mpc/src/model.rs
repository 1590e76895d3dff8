//! The prediction model: a plant state space, reduced to the part its outputs see, held by a
//! zero-order hold.

use nalgebra::DMatrix;
use plant::statespace::StateSpace;

use crate::error::{MpcError, Result};

/// x[k+1] = A x[k] + B u[k], y[k] = C x[k] in coordinates z = Vᵀ x_plant that the outputs
/// observe, followed by the inputs' dead-time buffers (the past inputs still on their way to
/// the plant). The rig's absolute angles (and, with the open differential, the antiphase angle)
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
    /// Orthonormal basis V of the observable subspace: z = Vᵀ x_plant (the first
    /// `basis.ncols()` states; the dead-time buffers follow).
    pub basis: DMatrix<f64>,
    /// For each dead-time buffer state (after the plant's), the input whose past value it holds.
    pub buffer_inputs: Vec<usize>,
    /// Dead time of each input, s.
    pub input_delays_s: Vec<f64>,
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
        Self::with_input_delays(plant, dt_s, &[])
    }

    /// As [`PredictionModel::new`], with input j reaching the plant `input_delays_s[j]` later
    /// (empty: none). A dead time τ = m·dt + f (0 ≤ f < dt) is exact for inputs held over each
    /// sample: u[k−m] acts over the last dt − f of the sample and u[k−m−1] over its first f,
    /// x[k+1] = Ad x[k] + B₀ u[k−m] + B₁ u[k−m−1] with B₀ = ∫₀^{dt−f} e^{As} ds b and
    /// B₁ = e^{A(dt−f)} ∫₀^f e^{As} ds b — the split the FMU makes where the delayed input
    /// changes. The m (+1 when f > 0) past inputs become buffer states.
    pub fn with_input_delays(plant: &StateSpace, dt_s: f64, input_delays_s: &[f64]) -> Result<Self> {
        let n = plant.nstates();
        let mu = plant.b.ncols();
        if !input_delays_s.is_empty() && input_delays_s.len() != mu {
            return Err(MpcError::Numerical(format!(
                "{} input dead times given for {mu} inputs",
                input_delays_s.len()
            )));
        }
        if let Some(d) = input_delays_s.iter().find(|d| !(d.is_finite() && **d >= 0.0 && **d <= 1e4 * dt_s)) {
            return Err(MpcError::Numerical(format!(
                "input dead time {d} s: expected a finite value between 0 and 10^4 samples"
            )));
        }
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
        let delays: Vec<f64> = if input_delays_s.is_empty() { vec![0.0; mu] } else { input_delays_s.to_vec() };
        // whole samples m and fraction f of each dead time (f within 1e-9 dt of 0 or dt rounds)
        let split: Vec<(usize, f64)> = delays
            .iter()
            .map(|&d| {
                let r = d / dt_s;
                let m = (r + 1e-9).floor();
                let f = (r - m) * dt_s;
                (m as usize, if f > 1e-9 * dt_s { f } else { 0.0 })
            })
            .collect();
        let buffers: Vec<usize> = split.iter().map(|&(m, f)| m + usize::from(f > 0.0)).collect();
        let nz = basis.ncols();
        let nb: usize = buffers.iter().sum();
        let na = nz + nb;
        let mut a = DMatrix::zeros(na, na);
        let mut b = DMatrix::zeros(na, mu);
        a.view_mut((0, 0), (nz, nz)).copy_from(&disc.ad);
        let mut buffer_inputs = Vec::with_capacity(nb);
        let mut next = nz;
        for j in 0..mu {
            let (m, f) = split[j];
            let bj = reduced.b.columns(j, 1).into_owned();
            if buffers[j] == 0 {
                b.view_mut((0, j), (nz, 1)).copy_from(&disc.bd.column(j));
                continue;
            }
            // buffer states next.. hold u[k−1], u[k−2], …: the first is fed by u[k]
            let first = next;
            for i in 0..buffers[j] {
                buffer_inputs.push(j);
                if i == 0 {
                    b[(first, j)] = 1.0;
                } else {
                    a[(first + i, first + i - 1)] = 1.0;
                }
            }
            next += buffers[j];
            let (ad_rest, b0) = plant::statespace::zoh(&reduced.a, &bj, dt_s - f)?;
            // u[k−m]: the input itself (m = 0) or buffer state m
            if m == 0 {
                b.view_mut((0, j), (nz, 1)).copy_from(&b0);
            } else {
                a.view_mut((0, first + m - 1), (nz, 1)).copy_from(&b0);
            }
            if f > 0.0 {
                let b1 = ad_rest * plant::statespace::zoh(&reduced.a, &bj, f)?.1;
                a.view_mut((0, first + m), (nz, 1)).copy_from(&b1);
            }
        }
        let mut c = DMatrix::zeros(reduced.c.nrows(), na);
        c.view_mut((0, 0), (reduced.c.nrows(), nz)).copy_from(&reduced.c);
        Ok(PredictionModel {
            a,
            b,
            c,
            basis,
            buffer_inputs,
            input_delays_s: delays,
            dt_s,
            input_names: plant.input_names.clone(),
            output_names: plant.output_names.clone(),
        })
    }

    /// Number of states of the plant's observable part (the buffers follow them).
    pub fn plant_states(&self) -> usize {
        self.basis.ncols()
    }

    /// The model state of plant state `x_plant` with every past input equal to `u`.
    pub fn state_of(&self, x_plant: &nalgebra::DVector<f64>, u: &[f64]) -> nalgebra::DVector<f64> {
        let mut z = nalgebra::DVector::zeros(self.nstates());
        z.rows_mut(0, self.plant_states()).copy_from(&(self.basis.transpose() * x_plant));
        for (k, &j) in self.buffer_inputs.iter().enumerate() {
            z[self.plant_states() + k] = u[j];
        }
        z
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
