//! A bearing, seal or squeeze-film damper as a lateral K/C/M block on a soft support (San Andrés
//! 2011, slides 6–19).
//!
//! The element's reaction force is f = −(K z + C ż + M z̈) with full 2×2 matrices over the
//! lateral displacements z = [x, y] (slide 6). On its support (diagonal Kh, Ch, Mh from dry shake
//! tests) the equations of motion are (M + Mh) z̈ + (C + Ch) ż + (K + Kh) z = F (slide 12), the
//! impedance is H(ω) = (K + Kh) − ω²(M + Mh) + iω(C + Ch) (slide 17) and the flexibility
//! G = H⁻¹ (slide 23). Seals and gas bearings have coefficients that depend on the excitation
//! frequency or the rotor speed: a table of coefficients against one such variable, linearly
//! interpolated.

use nalgebra::{DMatrix, Matrix2};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::error::{non_negative, positive, PlantError, Result};
use crate::statespace::StateSpace;

/// 2×2 matrix, row-major: `[[xx, xy], [yx, yy]]`.
pub type Mat2 = [[f64; 2]; 2];

fn m2(a: &Mat2) -> Matrix2<f64> {
    Matrix2::new(a[0][0], a[0][1], a[1][0], a[1][1])
}

/// Stiffness, damping and inertia force coefficients of a test element (slide 6).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coefficients {
    /// K, N/m.
    #[serde(rename = "K_N_per_m")]
    pub k_n_per_m: Mat2,
    /// C, N s/m.
    #[serde(rename = "C_Ns_per_m")]
    pub c_ns_per_m: Mat2,
    /// M, kg.
    #[serde(rename = "M_kg")]
    pub m_kg: Mat2,
}

impl Coefficients {
    /// The element's own impedance K − ω²M + iωC at ω rad/s.
    pub fn impedance(&self, omega: f64) -> Matrix2<Complex64> {
        let (k, c, m) = (m2(&self.k_n_per_m), m2(&self.c_ns_per_m), m2(&self.m_kg));
        Matrix2::from_fn(|i, j| Complex64::new(k[(i, j)] - omega * omega * m[(i, j)], omega * c[(i, j)]))
    }

    /// Element-wise sum.
    pub fn plus(&self, o: &Coefficients) -> Coefficients {
        let add = |a: &Mat2, b: &Mat2| [[a[0][0] + b[0][0], a[0][1] + b[0][1]], [a[1][0] + b[1][0], a[1][1] + b[1][1]]];
        Coefficients {
            k_n_per_m: add(&self.k_n_per_m, &o.k_n_per_m),
            c_ns_per_m: add(&self.c_ns_per_m, &o.c_ns_per_m),
            m_kg: add(&self.m_kg, &o.m_kg),
        }
    }

    /// Linear interpolation between `self` (t = 0) and `o` (t = 1).
    pub fn lerp(&self, o: &Coefficients, t: f64) -> Coefficients {
        let mix = |a: &Mat2, b: &Mat2| {
            let mut r = [[0.0; 2]; 2];
            for i in 0..2 {
                for j in 0..2 {
                    r[i][j] = a[i][j] + t * (b[i][j] - a[i][j]);
                }
            }
            r
        };
        Coefficients {
            k_n_per_m: mix(&self.k_n_per_m, &o.k_n_per_m),
            c_ns_per_m: mix(&self.c_ns_per_m, &o.c_ns_per_m),
            m_kg: mix(&self.m_kg, &o.m_kg),
        }
    }

    fn check_finite(&self, field: &str) -> Result<()> {
        for (name, a) in [("K_N_per_m", &self.k_n_per_m), ("C_Ns_per_m", &self.c_ns_per_m), ("M_kg", &self.m_kg)] {
            if a.iter().flatten().any(|v| !v.is_finite()) {
                return Err(PlantError::Invalid(format!("`{field}.{name}` has a non-finite entry")));
            }
        }
        Ok(())
    }
}

/// The soft support (diagonal), from dry shake tests; keys as in a `bearing_shake` bundle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Support {
    /// Stiffness along x, N/m.
    pub k_x: f64,
    /// Stiffness along y, N/m.
    pub k_y: f64,
    /// Damping along x, N s/m.
    pub c_x: f64,
    /// Damping along y, N s/m.
    pub c_y: f64,
    /// Effective mass along x, kg.
    pub m_x: f64,
    /// Effective mass along y, kg.
    pub m_y: f64,
}

impl Support {
    /// Checks the values; keys under `section`.
    pub fn validate(&self, section: &str) -> Result<()> {
        non_negative(|| format!("{section}.k_x"), self.k_x, "N/m")?;
        non_negative(|| format!("{section}.k_y"), self.k_y, "N/m")?;
        non_negative(|| format!("{section}.c_x"), self.c_x, "N s/m")?;
        non_negative(|| format!("{section}.c_y"), self.c_y, "N s/m")?;
        positive(|| format!("{section}.m_x"), self.m_x, "kg")?;
        positive(|| format!("{section}.m_y"), self.m_y, "kg")?;
        Ok(())
    }

    /// The support as coefficients (diagonal).
    pub fn coefficients(&self) -> Coefficients {
        Coefficients {
            k_n_per_m: [[self.k_x, 0.0], [0.0, self.k_y]],
            c_ns_per_m: [[self.c_x, 0.0], [0.0, self.c_y]],
            m_kg: [[self.m_x, 0.0], [0.0, self.m_y]],
        }
    }
}

/// Coefficients tabulated against excitation frequency or rotor speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoefficientTable {
    /// What the table is keyed by: "frequency_hz" or "speed_rpm".
    pub variable: String,
    /// Key values, strictly increasing.
    pub points: Vec<f64>,
    /// Coefficients at each key value.
    pub coefficients: Vec<Coefficients>,
}

impl CoefficientTable {
    /// Checks ordering and sizes.
    pub fn validate(&self, section: &str) -> Result<()> {
        if self.variable != "frequency_hz" && self.variable != "speed_rpm" {
            return Err(PlantError::Invalid(format!(
                "`{section}.variable` = \"{}\": expected \"frequency_hz\" or \"speed_rpm\"",
                self.variable
            )));
        }
        if self.points.is_empty() || self.points.len() != self.coefficients.len() {
            return Err(PlantError::Invalid(format!(
                "`{section}` needs one coefficient set per point: {} points, {} sets",
                self.points.len(),
                self.coefficients.len()
            )));
        }
        if self.points.windows(2).any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater)) {
            return Err(PlantError::Invalid(format!("`{section}.points` must increase strictly")));
        }
        for (i, c) in self.coefficients.iter().enumerate() {
            c.check_finite(&format!("{section}.coefficients[{}]", i + 1))?;
        }
        Ok(())
    }

    /// Coefficients at `x`, interpolated linearly, held constant beyond the table's ends.
    pub fn at(&self, x: f64) -> Coefficients {
        let p = &self.points;
        if x <= p[0] {
            return self.coefficients[0];
        }
        if x >= p[p.len() - 1] {
            return self.coefficients[p.len() - 1];
        }
        let i = p.partition_point(|&v| v <= x);
        let t = (x - p[i - 1]) / (p[i] - p[i - 1]);
        self.coefficients[i - 1].lerp(&self.coefficients[i], t)
    }
}

/// The test element on its support.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BearingModel {
    /// The element's coefficients (used when there is no table, and for the state space).
    pub element: Coefficients,
    /// The support.
    pub support: Support,
    /// Coefficients against frequency or speed, where known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<CoefficientTable>,
}

impl BearingModel {
    /// Checks the model.
    pub fn validate(&self) -> Result<()> {
        self.element.check_finite("bearing.element")?;
        self.support.validate("bearing.support")?;
        if let Some(t) = &self.table {
            t.validate("bearing.table")?;
        }
        let m = m2(&self.system(&self.element).m_kg);
        if ((m + m.transpose()) * 0.5).symmetric_eigenvalues().min() <= 0.0 {
            return Err(PlantError::Invalid(
                "the element's and support's masses together are not positive definite".into(),
            ));
        }
        Ok(())
    }

    fn system(&self, element: &Coefficients) -> Coefficients {
        element.plus(&self.support.coefficients())
    }

    /// The element's coefficients at an excitation frequency (a frequency-keyed table), else
    /// the constant ones.
    pub fn element_at_frequency(&self, f_hz: f64) -> Coefficients {
        match &self.table {
            Some(t) if t.variable == "frequency_hz" => t.at(f_hz),
            _ => self.element,
        }
    }

    /// Slide 17: H(ω) = (K + Kh) − ω²(M + Mh) + iω(C + Ch), N/m.
    pub fn impedance(&self, omega: f64) -> Matrix2<Complex64> {
        self.system(&self.element_at_frequency(omega / (2.0 * std::f64::consts::PI))).impedance(omega)
    }

    /// Slide 23: G(ω) = H(ω)⁻¹, m/N (None where H is singular).
    pub fn flexibility(&self, omega: f64) -> Option<Matrix2<Complex64>> {
        self.impedance(omega).try_inverse()
    }

    /// The model at a rotor speed (a speed-keyed table), else itself.
    pub fn at_speed(&self, speed_rpm: f64) -> BearingModel {
        match &self.table {
            Some(t) if t.variable == "speed_rpm" => {
                BearingModel { element: t.at(speed_rpm), table: None, ..self.clone() }
            }
            _ => self.clone(),
        }
    }

    /// State space of slide 12 with the constant element coefficients: x = [x, y, ẋ, ẏ],
    /// u = [F_x, F_y] (N), outputs the displacements (m) and velocities (m/s).
    pub fn state_space(&self) -> Result<StateSpace> {
        self.validate()?;
        let s = self.system(&self.element);
        let minv = m2(&s.m_kg).try_inverse().ok_or_else(|| PlantError::Numerical("singular mass matrix".into()))?;
        let (k, c) = (m2(&s.k_n_per_m), m2(&s.c_ns_per_m));
        let mut a = DMatrix::zeros(4, 4);
        a.view_mut((0, 2), (2, 2)).fill_with_identity();
        a.view_mut((2, 0), (2, 2)).copy_from(&(-minv * k));
        a.view_mut((2, 2), (2, 2)).copy_from(&(-minv * c));
        let mut b = DMatrix::zeros(4, 2);
        b.view_mut((2, 0), (2, 2)).copy_from(&minv);
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        Ok(StateSpace {
            a,
            b,
            c: DMatrix::identity(4, 4),
            d: DMatrix::zeros(4, 2),
            state_names: names(&["x", "y", "vx", "vy"]),
            input_names: names(&["F_x", "F_y"]),
            output_names: names(&["x", "y", "vx", "vy"]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn model() -> BearingModel {
        BearingModel {
            element: Coefficients {
                k_n_per_m: [[4e5, 2e4], [-2e4, 5e5]],
                c_ns_per_m: [[2600.0, 0.0], [0.0, 2800.0]],
                m_kg: [[5.4, 0.0], [0.0, 5.9]],
            },
            support: Support { k_x: 3.68e6, k_y: 3.85e6, c_x: 1226.0, c_y: 1313.0, m_x: 18.14, m_y: 18.14 },
            table: None,
        }
    }

    #[test]
    fn flexibility_matches_the_state_space_transfer_function() {
        // Two routes to the displacement response: G = H⁻¹ (slide 23) and C (iωI − A)⁻¹ B.
        let m = model();
        let ss = m.state_space().unwrap();
        for f in [5.0, 42.0, 85.0] {
            let w = 2.0 * std::f64::consts::PI * f;
            let g = m.flexibility(w).unwrap();
            let a = ss.a.map(|v| Complex64::new(v, 0.0));
            let resolvent = (DMatrix::<Complex64>::identity(4, 4) * Complex64::new(0.0, w) - a).try_inverse().unwrap();
            let tf = resolvent * ss.b.map(|v| Complex64::new(v, 0.0));
            for i in 0..2 {
                for j in 0..2 {
                    assert_relative_eq!(tf[(i, j)].re, g[(i, j)].re, max_relative = 1e-9, epsilon = 1e-15);
                    assert_relative_eq!(tf[(i, j)].im, g[(i, j)].im, max_relative = 1e-9, epsilon = 1e-15);
                }
            }
        }
    }

    #[test]
    fn table_interpolates_and_holds_at_the_ends() {
        let c0 = Coefficients::default();
        let c1 = Coefficients { c_ns_per_m: [[1000.0, 0.0], [0.0, 2000.0]], ..Default::default() };
        let t =
            CoefficientTable { variable: "speed_rpm".into(), points: vec![0.0, 10_000.0], coefficients: vec![c0, c1] };
        t.validate("t").unwrap();
        assert_relative_eq!(t.at(2500.0).c_ns_per_m[1][1], 500.0);
        assert_eq!(t.at(-1.0), c0);
        assert_eq!(t.at(1e9), c1);
        let bad = CoefficientTable { points: vec![1.0, 1.0], ..t.clone() };
        assert!(bad.validate("bearing.table").unwrap_err().to_string().contains("bearing.table.points"));
    }

    #[test]
    fn support_needs_mass() {
        let mut m = model();
        m.support.m_x = 0.0;
        assert!(m.validate().unwrap_err().to_string().contains("bearing.support.m_x"));
    }
}
