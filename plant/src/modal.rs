//! Modal analysis: undamped natural frequencies and mode shapes of (J, C), and the poles of a
//! damped system (section 2.2, 4.3). Library eigensolvers only (nalgebra).

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;

use crate::error::{PlantError, Result};

/// Undamped modes, sorted by frequency.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Modes {
    /// Natural frequencies f = ω/2π, Hz; rigid-body modes are exactly 0.
    pub frequencies_hz: Vec<f64>,
    /// Mode shapes, one per frequency, scaled so the largest component is +1.
    pub shapes: Vec<DVector<f64>>,
}

/// Eigenvalues within this many machine epsilons of the largest are round-off of a zero one:
/// a symmetric eigensolver's absolute error is of order ε‖A‖ (backward stable), so a rigid-body
/// mode comes out as ±(a few ε‖A‖), never as a physical frequency.
const ROUNDOFF_EPS: f64 = 64.0;

/// Natural frequencies and mode shapes of J q̈ + C q = 0 (eq. (15) for any size):
/// with J = L Lᵀ, the symmetric problem L⁻¹ C L⁻ᵀ ψ = ω² ψ, then φ = L⁻ᵀ ψ.
pub fn modes(inertia: &DMatrix<f64>, stiffness: &DMatrix<f64>) -> Result<Modes> {
    let n = inertia.nrows();
    if inertia.shape() != (n, n) || stiffness.shape() != (n, n) {
        return Err(PlantError::Invalid("inertia and stiffness matrices must be square and of one size".into()));
    }
    let chol = inertia
        .clone()
        .cholesky()
        .ok_or_else(|| PlantError::Numerical("inertia matrix is not positive definite".into()))?;
    let l = chol.l();
    let linv = l.clone().try_inverse().ok_or_else(|| PlantError::Numerical("inertia matrix is singular".into()))?;
    let mut sym = &linv * stiffness * linv.transpose();
    sym = (&sym + sym.transpose()) * 0.5; // remove round-off asymmetry
    let eig = SymmetricEigen::new(sym);
    let scale = eig.eigenvalues.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let floor = ROUNDOFF_EPS * f64::EPSILON * scale;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let mut psi = DMatrix::from_fn(n, n, |i, j| eig.eigenvectors[(i, order[j])]);
    let zeros = order.iter().filter(|&&k| eig.eigenvalues[k] <= floor).count();
    rigid_body_first(&mut psi, zeros, &l, stiffness);
    let mut frequencies_hz = Vec::with_capacity(n);
    let mut shapes = Vec::with_capacity(n);
    for (col, &k) in order.iter().enumerate() {
        let w2 = eig.eigenvalues[k];
        if w2 < -floor {
            return Err(PlantError::Numerical(format!(
                "negative eigenvalue ω² = {w2:.3e} rad²/s²: the stiffness matrix is not positive semi-definite"
            )));
        }
        frequencies_hz.push(if w2 <= floor { 0.0 } else { w2.sqrt() / (2.0 * PI) });
        let phi = linv.transpose() * psi.column(col);
        shapes.push(normalise(phi));
    }
    Ok(Modes { frequencies_hz, shapes })
}

/// The eigenvectors of a repeated zero eigenvalue are any basis of the null space. Where the
/// system is free (C·1 = 0, every free torsional system), make the basis deterministic: the
/// rigid-body motion first, then the J-orthogonal rest (e.g. the outputs' antiphase motion of
/// the open differential). Works on ψ = Lᵀφ, the columns `0..zeros` of `psi`.
fn rigid_body_first(psi: &mut DMatrix<f64>, zeros: usize, l: &DMatrix<f64>, stiffness: &DMatrix<f64>) {
    let n = psi.nrows();
    let ones = DVector::from_element(n, 1.0);
    if zeros == 0 || !turns_freely_as_one(stiffness) {
        return;
    }
    let mut basis = DMatrix::zeros(n, zeros + 1);
    basis.set_column(0, &(l.transpose() * &ones));
    basis.view_mut((0, 1), (n, zeros)).copy_from(&psi.columns(0, zeros));
    let q = basis.qr().q();
    psi.view_mut((0, 0), (n, zeros)).copy_from(&q.columns(0, zeros));
}

/// Whether every body turning by the same angle twists nothing (K·1 = 0 to round-off of K's
/// size): a free line without gears, as the paper rig is. A gear stage makes the free motion
/// turn its bodies at the ratio instead, and a spring to ground allows none.
pub fn turns_freely_as_one(stiffness: &DMatrix<f64>) -> bool {
    let n = stiffness.nrows();
    let ones = DVector::from_element(n, 1.0);
    (stiffness * &ones).norm() <= 1e-9 * stiffness.norm() * (n as f64).sqrt()
}

/// Scales a shape so its largest-magnitude component is +1.
fn normalise(phi: DVector<f64>) -> DVector<f64> {
    let k = phi.iamax();
    let m = phi[k];
    if m == 0.0 {
        return phi;
    }
    // components at round-off level of the largest one are zero (e.g. a node of a symmetric mode)
    (phi / m).map(|v| if v.abs() < 1e-12 { 0.0 } else { v })
}

/// One pole of a linear system, as python-control's `damp` reports it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pole {
    /// The eigenvalue λ of A, 1/s.
    pub eigenvalue: Complex64,
    /// Natural frequency |λ|/2π, Hz.
    pub natural_hz: f64,
    /// Damped frequency |Im λ|/2π, Hz.
    pub damped_hz: f64,
    /// Damping ratio −Re λ / |λ|; `None` for a pole at the origin.
    pub damping_ratio: Option<f64>,
}

/// Poles of `a` (eigenvalues via nalgebra's real Schur form), one per conjugate pair (Im ≥ 0),
/// sorted by natural frequency. Poles within round-off of the origin are reported as 0.
pub fn damp(a: &DMatrix<f64>) -> Result<Vec<Pole>> {
    if !a.is_square() {
        return Err(PlantError::Invalid("damp needs a square matrix".into()));
    }
    let eig = a.complex_eigenvalues();
    let scale = a.norm();
    // The eigenvalues of a Jordan block at 0 (rigid-body angle + speed) are perturbed by
    // √(ε‖A‖) — a defective eigenvalue is only half as well conditioned.
    let floor = (ROUNDOFF_EPS * f64::EPSILON * scale).sqrt();
    let mut poles: Vec<Pole> = eig
        .iter()
        .filter(|l| l.im >= -floor)
        .map(|&l| {
            let l = Complex64::new(
                if l.re.abs() <= floor { 0.0 } else { l.re },
                if l.im.abs() <= floor { 0.0 } else { l.im },
            );
            let wn = l.norm();
            Pole {
                eigenvalue: l,
                natural_hz: wn / (2.0 * PI),
                damped_hz: l.im.abs() / (2.0 * PI),
                damping_ratio: if wn > 0.0 { Some(-l.re / wn) } else { None },
            }
        })
        .collect();
    poles.sort_by(|a, b| a.natural_hz.total_cmp(&b.natural_hz).then(a.eigenvalue.re.total_cmp(&b.eigenvalue.re)));
    Ok(poles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn only_a_line_without_gears_or_ground_turns_freely_as_one() {
        // two shafts of 1e4 and 3e4 N·m/rad in a chain: K·1 = 0 exactly
        let (a, b) = (1e4, 3e4);
        let chain = DMatrix::from_row_slice(3, 3, &[a, -a, 0.0, -a, a + b, -b, 0.0, -b, b]);
        assert!(turns_freely_as_one(&chain));
        // the same shaft behind a 1:2 gear (φ₂ = 2φ₁ twists nothing): the stiffness on
        // (φ₁, φ₂) of the twist 2φ₁ − φ₂ is a·[4, −2; −2, 1], and 1 twists it
        let geared = DMatrix::from_row_slice(2, 2, &[4.0 * a, -2.0 * a, -2.0 * a, a]);
        assert!(!turns_freely_as_one(&geared));
        assert!(geared * DVector::from_row_slice(&[1.0, 2.0]) == DVector::zeros(2));
        // a spring to ground of a ten-thousandth of the shaft's: no free motion at all
        let mut grounded = chain.clone();
        grounded[(0, 0)] += 1e-4 * a;
        assert!(!turns_freely_as_one(&grounded));
    }

    #[test]
    fn single_oscillator_pole_is_analytic() {
        // J φ̈ + d φ̇ + c φ = 0: λ = −ζω ± iω√(1−ζ²)
        let (j, c, d) = (2.0, 800.0, 4.0);
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -c / j, -d / j]);
        let p = damp(&a).unwrap();
        assert_eq!(p.len(), 1);
        let wn = (c / j).sqrt();
        let zeta = d / (2.0 * (c * j).sqrt());
        assert_relative_eq!(p[0].natural_hz, wn / (2.0 * PI), max_relative = 1e-12);
        assert_relative_eq!(p[0].damping_ratio.unwrap(), zeta, max_relative = 1e-10);
        assert_relative_eq!(p[0].damped_hz, wn * (1.0 - zeta * zeta).sqrt() / (2.0 * PI), max_relative = 1e-10);
    }

    #[test]
    fn non_diagonal_inertia_is_handled() {
        // Same two-mass system in rotated coordinates q = T p must have the same frequencies.
        let j = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 4.0]));
        let c = DMatrix::from_row_slice(2, 2, &[100.0, -100.0, -100.0, 100.0]);
        let t = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 1.0]);
        let m1 = modes(&j, &c).unwrap();
        let m2 = modes(&(t.transpose() * &j * &t), &(t.transpose() * &c * &t)).unwrap();
        assert_relative_eq!(m1.frequencies_hz[1], m2.frequencies_hz[1], max_relative = 1e-12);
        assert_relative_eq!(m1.frequencies_hz[1], (100.0_f64 * 1.25).sqrt() / (2.0 * PI), max_relative = 1e-12);
    }

    #[test]
    fn indefinite_inertia_is_an_error() {
        let j = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
        assert!(modes(&j, &DMatrix::identity(2, 2)).is_err());
    }
}
