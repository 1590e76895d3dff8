//! The discrete algebraic Riccati equation (python-control `dare`): the MPC's terminal cost and
//! Kalman filter, and a drive model's one-step-ahead predictor ([`crate::predictor`]).

use nalgebra::DMatrix;

use crate::error::{PlantError, Result};

/// Solution of X = AᵀXA − AᵀXB(R + BᵀXB)⁻¹BᵀXA + Q with its gain K = (R + BᵀXB)⁻¹BᵀXA
/// (u = −K x is the infinite-horizon LQR law).
#[derive(Debug, Clone)]
pub struct Dare {
    /// The stabilising solution X.
    pub x: DMatrix<f64>,
    /// The gain K.
    pub k: DMatrix<f64>,
}

/// Solves the DARE by the structure-preserving doubling algorithm (Chu, Fan, Lin 2005):
/// A₀ = A, G₀ = B R⁻¹ Bᵀ, H₀ = Q; W = I + G H; A ← A W⁻¹ A, G ← G + A W⁻¹ G Aᵀ,
/// H ← H + Aᵀ H W⁻¹ A; H converges quadratically to X. Needs (A, B) stabilisable and
/// (A, Q^½) detectable; eigenvalues on the unit circle that are detectable (the rig's rigid
/// body) are fine. The result is checked by its residual.
pub fn dare(a: &DMatrix<f64>, b: &DMatrix<f64>, q: &DMatrix<f64>, r: &DMatrix<f64>) -> Result<Dare> {
    let n = a.nrows();
    let rinv =
        r.clone().cholesky().ok_or_else(|| PlantError::Numerical("dare: R is not positive definite".into()))?.inverse();
    let mut ak = a.clone();
    let mut g = b * &rinv * b.transpose();
    let mut h = q.clone();
    let eye = DMatrix::<f64>::identity(n, n);
    let mut converged = false;
    for _ in 0..200 {
        let w = (&eye + &g * &h)
            .lu()
            .try_inverse()
            .ok_or_else(|| PlantError::Numerical("dare: I + G H is singular".into()))?;
        let winv_a = &w * &ak;
        let h_next = &h + ak.transpose() * &h * &winv_a;
        let g_next = &g + &ak * &w * &g * ak.transpose();
        ak = &ak * &winv_a;
        let change = (&h_next - &h).norm();
        h = (&h_next + h_next.transpose()) * 0.5;
        g = (&g_next + g_next.transpose()) * 0.5;
        if !h.iter().all(|v| v.is_finite()) {
            break;
        }
        if change <= 1e-13 * h.norm().max(1e-300) {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(PlantError::Numerical(
            "dare: doubling did not converge ((A, B) not stabilisable or (A, Q) not detectable)".into(),
        ));
    }
    let x = h;
    let btx = b.transpose() * &x;
    let k = (r + &btx * b)
        .cholesky()
        .ok_or_else(|| PlantError::Numerical("dare: R + BᵀXB is not positive definite".into()))?
        .solve(&(&btx * a));
    let residual = a.transpose() * &x * a - a.transpose() * &x * b * &k + q - &x;
    if residual.norm() > 1e-8 * x.norm().max(1.0) {
        return Err(PlantError::Numerical(format!("dare: residual {:.3e} too large", residual.norm())));
    }
    Ok(Dare { x, k })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar DARE x = a²x − a²x²b²/(r + b²x) + q is the quadratic
    /// b²x² − (q b² + a² r − r) x − q r = 0, whose positive root is the stabilising solution.
    #[test]
    fn scalar_matches_quadratic_formula() {
        for &(a, b, q, r) in &[(1.0, 1.0, 1.0, 1.0), (1.2, 0.5, 2.0, 0.3), (0.9, 2.0, 0.1, 5.0), (1.0, 1e-3, 1.0, 1e-6)]
        {
            let s = dare(
                &DMatrix::from_element(1, 1, a),
                &DMatrix::from_element(1, 1, b),
                &DMatrix::from_element(1, 1, q),
                &DMatrix::from_element(1, 1, r),
            )
            .unwrap();
            let (qa, qb, qc) = (b * b, -(q * b * b + a * a * r - r), -q * r);
            let x = (-qb + (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa);
            approx::assert_relative_eq!(s.x[(0, 0)], x, max_relative = 1e-10);
            approx::assert_relative_eq!(s.k[(0, 0)], a * b * x / (r + b * b * x), max_relative = 1e-10);
        }
    }

    /// A double integrator (eigenvalues on the unit circle) gives a stabilising gain.
    #[test]
    fn double_integrator_is_stabilised() {
        let dt = 0.01;
        let a = DMatrix::from_row_slice(2, 2, &[1.0, dt, 0.0, 1.0]);
        let b = DMatrix::from_row_slice(2, 1, &[0.5 * dt * dt, dt]);
        let s = dare(&a, &b, &DMatrix::identity(2, 2), &DMatrix::from_element(1, 1, 0.1)).unwrap();
        let cl = &a - &b * &s.k;
        let radius = cl.complex_eigenvalues().iter().map(|l| l.norm()).fold(0.0, f64::max);
        assert!(radius < 1.0, "closed-loop spectral radius {radius}");
    }
}
