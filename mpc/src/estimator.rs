//! Steady-state Kalman filter with an input-disturbance model for offset-free tracking.

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use plant::riccati::dare;

/// x̂ = [x; d] with x[k+1] = A x + B (u + E d), d[k+1] = d (+ noise), y = C_meas x (+ noise),
/// E selecting the inputs that carry a disturbance. The gain comes from the filter Riccati
/// equation (the dual of the control one). The augmented pair must be detectable: no constant
/// (x, d) may satisfy (A − I) x + B E d = 0 with C x = 0. On the rig, with speeds measured,
/// disturbances on all three machines violate it — a static twist balanced by three torques
/// moves no speed — so the default puts them on the load machines only.
#[derive(Debug, Clone)]
pub struct Estimator {
    e: DMatrix<f64>,
    d_full: DVector<f64>,
    a_aug: DMatrix<f64>,
    b_aug: DMatrix<f64>,
    c_aug: DMatrix<f64>,
    gain: DMatrix<f64>,
    /// Prior estimate x̂[k|k−1].
    prior: DVector<f64>,
    /// Posterior estimate x̂[k|k].
    posterior: DVector<f64>,
    innovation: DVector<f64>,
    scratch: DVector<f64>,
    n: usize,
}

impl Estimator {
    /// Builds the filter: `w_x` and `w_d` process-noise variances of the states and
    /// disturbances, `v` measurement-noise variances.
    pub fn new(
        a: &DMatrix<f64>,
        b: &DMatrix<f64>,
        disturbed: &[usize],
        c_meas: &DMatrix<f64>,
        w_x: &DVector<f64>,
        w_d: &DVector<f64>,
        v: &DVector<f64>,
    ) -> Result<Self> {
        let (n, mu, m) = (a.nrows(), b.ncols(), disturbed.len());
        let e = DMatrix::from_fn(mu, m, |i, j| if disturbed[j] == i { 1.0 } else { 0.0 });
        let be = b * &e;
        // Detectability of the constant disturbances (Pannocchia & Rawlings 2003).
        let mut test = DMatrix::zeros(n + c_meas.nrows(), n + m);
        test.view_mut((0, 0), (n, n)).copy_from(&(DMatrix::identity(n, n) - a));
        test.view_mut((0, n), (n, m)).copy_from(&(-&be));
        test.view_mut((n, 0), (c_meas.nrows(), n)).copy_from(c_meas);
        let sv = test.singular_values();
        if sv.iter().filter(|&&s| s > 1e-9 * sv.max()).count() < n + m {
            return Err(crate::error::MpcError::Numerical(
                "the input disturbances cannot be told apart from the states by the measured outputs: \
                 model fewer disturbances (disturbance_std_nm = 0) or measure more outputs"
                    .into(),
            ));
        }
        let na = n + m;
        let mut a_aug = DMatrix::zeros(na, na);
        a_aug.view_mut((0, 0), (n, n)).copy_from(a);
        a_aug.view_mut((0, n), (n, m)).copy_from(&be);
        a_aug.view_mut((n, n), (m, m)).fill_with_identity();
        let mut b_aug = DMatrix::zeros(na, mu);
        b_aug.view_mut((0, 0), (n, mu)).copy_from(b);
        let mut c_aug = DMatrix::zeros(c_meas.nrows(), na);
        c_aug.view_mut((0, 0), (c_meas.nrows(), n)).copy_from(c_meas);
        let mut w = DVector::zeros(na);
        w.rows_mut(0, n).copy_from(w_x);
        w.rows_mut(n, m).copy_from(w_d);
        // Filter DARE: the prior covariance P solves the control DARE of (Aᵀ, Cᵀ, W, V);
        // L = P Cᵀ (C P Cᵀ + V)⁻¹ is the measurement-update gain.
        let sol =
            dare(&a_aug.transpose(), &c_aug.transpose(), &DMatrix::from_diagonal(&w), &DMatrix::from_diagonal(v))?;
        let p = sol.x;
        let s = &c_aug * &p * c_aug.transpose() + DMatrix::from_diagonal(v);
        let gain = s
            .cholesky()
            .ok_or_else(|| crate::error::MpcError::Numerical("estimator: C P Cᵀ + V is not positive definite".into()))?
            .solve(&(&c_aug * &p))
            .transpose();
        Ok(Estimator {
            e,
            d_full: DVector::zeros(mu),
            a_aug,
            b_aug,
            c_aug,
            gain,
            prior: DVector::zeros(na),
            posterior: DVector::zeros(na),
            innovation: DVector::zeros(c_meas.nrows()),
            scratch: DVector::zeros(na),
            n,
        })
    }

    /// Starts from state `x` with no disturbance.
    pub fn reset(&mut self, x: &DVector<f64>) {
        self.prior.fill(0.0);
        self.prior.rows_mut(0, self.n).copy_from(x);
        self.posterior.copy_from(&self.prior);
        self.d_full.fill(0.0);
    }

    /// Measurement update with `y` (the measured outputs, in order).
    pub fn correct(&mut self, y: &[f64]) {
        for (i, v) in y.iter().enumerate() {
            self.innovation[i] = *v;
        }
        self.innovation.gemv(-1.0, &self.c_aug, &self.prior, 1.0);
        self.posterior.copy_from(&self.prior);
        self.posterior.gemv(1.0, &self.gain, &self.innovation, 1.0);
        let n = self.n;
        self.d_full.gemv(1.0, &self.e, &self.posterior.rows(n, self.e.ncols()), 0.0);
    }

    /// Time update with the applied input `u`.
    pub fn predict(&mut self, u: &DVector<f64>) {
        self.scratch.gemv(1.0, &self.a_aug, &self.posterior, 0.0);
        self.scratch.gemv(1.0, &self.b_aug, u, 1.0);
        self.prior.copy_from(&self.scratch);
    }

    /// Posterior state estimate x̂[k|k] (reduced coordinates).
    pub fn state(&self) -> nalgebra::DVectorView<'_, f64> {
        self.posterior.rows(0, self.n)
    }

    /// Posterior input-disturbance estimate on every input (zero where none is modelled), Nm.
    pub fn disturbance(&self) -> &DVector<f64> {
        &self.d_full
    }

    /// Length of [`Estimator::save`]'s record: prior and posterior estimates, disturbances.
    pub fn state_len(&self) -> usize {
        2 * self.prior.len() + self.d_full.len()
    }

    /// Writes the filter's state into `out` (length [`Estimator::state_len`]); no allocation.
    pub fn save(&self, out: &mut [f64]) {
        let na = self.prior.len();
        out[..na].copy_from_slice(self.prior.as_slice());
        out[na..2 * na].copy_from_slice(self.posterior.as_slice());
        out[2 * na..].copy_from_slice(self.d_full.as_slice());
    }

    /// Restores a state written by [`Estimator::save`].
    pub fn restore(&mut self, s: &[f64]) {
        let na = self.prior.len();
        self.prior.as_mut_slice().copy_from_slice(&s[..na]);
        self.posterior.as_mut_slice().copy_from_slice(&s[na..2 * na]);
        self.d_full.as_mut_slice().copy_from_slice(&s[2 * na..]);
    }

    /// The gain L.
    pub fn gain(&self) -> &DMatrix<f64> {
        &self.gain
    }
}
