//! The FMU's dynamics: the open-differential powertrain (6 states) beside the bearing block (4
//! states), x' = A x + B u, from `plant`'s state spaces. The co-simulation step is exact for a
//! linear model with inputs held over the step: x⁺ = Ad x + Bd u with (Ad, Bd) from the matrix
//! exponential, cached per step size.

use nalgebra::{DMatrix, DVector};

use crate::params::FmuParams;
use plant::Output;

/// Number of continuous states.
pub const NX: usize = 10;
/// Number of inputs.
pub const NU: usize = 5;

/// The linear system and its discretisations.
#[derive(Debug, Clone)]
pub struct LinearModel {
    /// System matrix (10×10).
    pub a: DMatrix<f64>,
    /// Input matrix (10×5).
    pub b: DMatrix<f64>,
    /// Side-shaft torques from the states (2×10).
    pub torque: DMatrix<f64>,
    cache: Vec<(f64, DMatrix<f64>, DMatrix<f64>)>,
    scratch: DVector<f64>,
}

/// Discretisations kept: a co-simulation master uses one or a few step sizes.
const CACHE: usize = 8;

impl LinearModel {
    /// Builds the model; the error names the offending parameter.
    pub fn new(p: &FmuParams) -> Result<Self, String> {
        let pt = p.powertrain.open_differential(p.variant).map_err(|e| e.to_string())?;
        let pt = pt.state_space(&[Output::SpringTorques]).map_err(|e| e.to_string())?;
        let br = p.bearing.state_space().map_err(|e| e.to_string())?;
        let mut a = DMatrix::zeros(NX, NX);
        let mut b = DMatrix::zeros(NX, NU);
        a.view_mut((0, 0), (6, 6)).copy_from(&pt.a);
        a.view_mut((6, 6), (4, 4)).copy_from(&br.a);
        b.view_mut((0, 0), (6, 3)).copy_from(&pt.b);
        b.view_mut((6, 3), (4, 2)).copy_from(&br.b);
        let mut torque = DMatrix::zeros(2, NX);
        torque.view_mut((0, 0), (2, 6)).copy_from(&pt.c);
        if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
            return Err("the parameters give a system matrix with non-finite entries".into());
        }
        Ok(LinearModel { a, b, torque, cache: Vec::new(), scratch: DVector::zeros(NX) })
    }

    /// ẋ = A x + B u.
    pub fn derivatives(&self, x: &DVector<f64>, u: &DVector<f64>) -> DVector<f64> {
        &self.a * x + &self.b * u
    }

    /// One exact step of length `h` with `u` held; allocates only when a new step size is
    /// discretised.
    pub fn step(&mut self, x: &mut DVector<f64>, u: &DVector<f64>, h: f64) {
        let i = self.discretise(h);
        let (_, ad, bd) = &self.cache[i];
        self.scratch.gemv(1.0, ad, x, 0.0);
        self.scratch.gemv(1.0, bd, u, 1.0);
        x.copy_from(&self.scratch);
    }

    /// (Ad, Bd) of step size `h`.
    pub fn discretisation(&mut self, h: f64) -> (&DMatrix<f64>, &DMatrix<f64>) {
        let i = self.discretise(h);
        (&self.cache[i].1, &self.cache[i].2)
    }

    fn discretise(&mut self, h: f64) -> usize {
        match self.cache.iter().position(|c| c.0 == h) {
            Some(i) => i,
            None => {
                let mut aug = DMatrix::zeros(NX + NU, NX + NU);
                aug.view_mut((0, 0), (NX, NX)).copy_from(&(&self.a * h));
                aug.view_mut((0, NX), (NX, NU)).copy_from(&(&self.b * h));
                let e = aug.exp();
                if self.cache.len() == CACHE {
                    self.cache.remove(0);
                }
                self.cache.push((h, e.view((0, 0), (NX, NX)).into_owned(), e.view((0, NX), (NX, NU)).into_owned()));
                self.cache.len() - 1
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn shuffle_and_bearing_poles_survive_the_assembly() {
        let p = FmuParams::default();
        let m = LinearModel::new(&p).unwrap();
        let poles = plant::damp(&m.a).unwrap();
        let f_shuffle = p.powertrain.open_differential(p.variant).unwrap().modes().unwrap().frequencies_hz[2];
        assert!(poles.iter().any(|q| (q.natural_hz - f_shuffle).abs() < 0.01 * f_shuffle), "{poles:?}");
        // bearing on its support: ω² ≈ (K + Kh)/(M + Mh) along x
        let k = p.bearing.element.k_n_per_m[0][0] + p.bearing.support.k_x;
        let mass = p.bearing.element.m_kg[0][0] + p.bearing.support.m_x;
        let f_b = (k / mass).sqrt() / (2.0 * std::f64::consts::PI);
        assert!(poles.iter().any(|q| (q.natural_hz - f_b).abs() < 0.05 * f_b), "{poles:?}");
    }

    #[test]
    fn two_half_steps_are_one_step() {
        let mut m = LinearModel::new(&FmuParams::default()).unwrap();
        let u = DVector::from_vec(vec![1.0, 10.0, -2.0, 50.0, -20.0]);
        let mut x1 = DVector::from_element(NX, 1e-3);
        let mut x2 = x1.clone();
        m.step(&mut x1, &u, 2e-3);
        m.step(&mut x2, &u, 1e-3);
        m.step(&mut x2, &u, 1e-3);
        for i in 0..NX {
            assert_relative_eq!(x1[i], x2[i], max_relative = 1e-9, epsilon = 1e-15);
        }
    }
}
