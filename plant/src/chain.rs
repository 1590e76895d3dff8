//! The torsional chain: inertias coupled by springs (section 2.1, Figure 3a).

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{non_negative, positive, PlantError, Result};
use crate::mechanical::{MechanicalModel, Spring};

/// One body of a chain as Tables A1 and A2 list it: its inertia J_i and its own (partial)
/// stiffness c_i.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Body {
    /// Name shown in reports, e.g. "J7 side shaft (short)".
    pub name: String,
    /// Polar moment of inertia J_i, kg m².
    pub inertia_kgm2: f64,
    /// Partial torsional stiffness c_i of the body itself, Nm/rad.
    pub stiffness_nm_per_rad: f64,
}

/// A lumped torsional chain: `n` inertias and `n − 1` coupling springs (with optional dampers)
/// between neighbours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chain {
    /// Name of each mass.
    pub names: Vec<String>,
    /// Inertias J_i, kg m².
    pub inertias_kgm2: Vec<f64>,
    /// Coupling stiffnesses c_Ti between mass i and i + 1, Nm/rad.
    pub stiffnesses_nm_per_rad: Vec<f64>,
    /// Coupling dampings between mass i and i + 1, Nm s/rad.
    pub dampings_nms_per_rad: Vec<f64>,
    /// For each mass, the 0-based position in the chain it was reduced from of the body it
    /// stands for (its heaviest member); the identity for an unreduced chain.
    pub origins: Vec<usize>,
}

impl Chain {
    /// A chain from its inertias and coupling stiffnesses, undamped.
    pub fn new(names: Vec<String>, inertias_kgm2: Vec<f64>, stiffnesses_nm_per_rad: Vec<f64>) -> Result<Self> {
        let dampings = vec![0.0; stiffnesses_nm_per_rad.len()];
        Self::with_damping(names, inertias_kgm2, stiffnesses_nm_per_rad, dampings)
    }

    /// A chain from inertias, coupling stiffnesses and coupling dampings.
    pub fn with_damping(
        names: Vec<String>,
        inertias_kgm2: Vec<f64>,
        stiffnesses_nm_per_rad: Vec<f64>,
        dampings_nms_per_rad: Vec<f64>,
    ) -> Result<Self> {
        let n = inertias_kgm2.len();
        if n == 0 {
            return Err(PlantError::Invalid("a chain needs at least one mass".into()));
        }
        if stiffnesses_nm_per_rad.len() + 1 != n || dampings_nms_per_rad.len() + 1 != n || names.len() != n {
            return Err(PlantError::Invalid(format!(
                "a chain of {n} masses needs {n} names, {} coupling stiffnesses and dampings; got {}, {} and {}",
                n - 1,
                names.len(),
                stiffnesses_nm_per_rad.len(),
                dampings_nms_per_rad.len()
            )));
        }
        for (i, &j) in inertias_kgm2.iter().enumerate() {
            positive(|| format!("inertias_kgm2[{}]", i + 1), j, "kg m^2")?;
        }
        for (i, &c) in stiffnesses_nm_per_rad.iter().enumerate() {
            positive(|| format!("stiffnesses_Nm_per_rad[{}]", i + 1), c, "Nm/rad")?;
        }
        for (i, &d) in dampings_nms_per_rad.iter().enumerate() {
            non_negative(|| format!("dampings_Nms_per_rad[{}]", i + 1), d, "Nm s/rad")?;
        }
        Ok(Chain { names, inertias_kgm2, stiffnesses_nm_per_rad, dampings_nms_per_rad, origins: (0..n).collect() })
    }

    /// Eq. (3): couples neighbouring bodies through their half lengths, i.e. the doubled partial
    /// stiffnesses in series, c_T = 2 c_i c_{i+1} / (c_i + c_{i+1}). The half stiffnesses at the
    /// two free ends are neglected (torque enters through the end faces).
    pub fn from_bodies(bodies: &[Body]) -> Result<Self> {
        for (i, b) in bodies.iter().enumerate() {
            positive(|| format!("bodies[{}].j_kgm2", i + 1), b.inertia_kgm2, "kg m^2")?;
            positive(|| format!("bodies[{}].c_Nm_per_rad", i + 1), b.stiffness_nm_per_rad, "Nm/rad")?;
        }
        let couplings = bodies
            .windows(2)
            .map(|w| {
                let (a, b) = (w[0].stiffness_nm_per_rad, w[1].stiffness_nm_per_rad);
                2.0 * a * b / (a + b)
            })
            .collect();
        Self::new(
            bodies.iter().map(|b| b.name.clone()).collect(),
            bodies.iter().map(|b| b.inertia_kgm2).collect(),
            couplings,
        )
    }

    /// Number of masses.
    pub fn len(&self) -> usize {
        self.inertias_kgm2.len()
    }

    /// True for a chain without masses (never built by the constructors).
    pub fn is_empty(&self) -> bool {
        self.inertias_kgm2.is_empty()
    }

    /// Sum of all inertias, kg m².
    pub fn total_inertia_kgm2(&self) -> f64 {
        self.inertias_kgm2.iter().sum()
    }

    /// Series stiffness of the couplings between mass `from` and mass `to` (0-based, from < to), Nm/rad.
    pub fn series_stiffness_nm_per_rad(&self, from: usize, to: usize) -> f64 {
        1.0 / self.stiffnesses_nm_per_rad[from..to].iter().map(|c| 1.0 / c).sum::<f64>()
    }

    /// The chain as a second-order system J q̈ + D q̇ + C q = M, one angle per mass.
    pub fn mechanical(&self) -> MechanicalModel {
        let n = self.len();
        let springs = (0..n - 1)
            .map(|i| {
                // elongation φ_i − φ_{i+1}: torque positive when the left end leads
                let mut e = DVector::zeros(n);
                e[i] = 1.0;
                e[i + 1] = -1.0;
                Spring {
                    name: format!("{}-{}", self.names[i], self.names[i + 1]),
                    elongation: e,
                    stiffness: self.stiffnesses_nm_per_rad[i],
                    damping: self.dampings_nms_per_rad[i],
                }
            })
            .collect();
        MechanicalModel {
            dof_names: self.names.clone(),
            inertia: DMatrix::from_diagonal(&DVector::from_vec(self.inertias_kgm2.clone())),
            springs,
            drag: DVector::zeros(n),
            layout: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn body(j: f64, c: f64) -> Body {
        Body { name: String::new(), inertia_kgm2: j, stiffness_nm_per_rad: c }
    }

    #[test]
    fn eq3_is_series_of_half_segments() {
        // Two equal segments: c_T = 2c·2c/(4c)·... = c (the two half lengths make one length).
        let ch = Chain::from_bodies(&[body(1.0, 100.0), body(1.0, 100.0)]).unwrap();
        assert_relative_eq!(ch.stiffnesses_nm_per_rad[0], 100.0);
        // 1/c_T = 1/(2 c1) + 1/(2 c2)
        let ch = Chain::from_bodies(&[body(1.0, 100.0), body(1.0, 300.0)]).unwrap();
        assert_relative_eq!(1.0 / ch.stiffnesses_nm_per_rad[0], 1.0 / 200.0 + 1.0 / 600.0, max_relative = 1e-12);
    }

    #[test]
    fn rejects_non_positive_inertia_with_position() {
        let e = Chain::from_bodies(&[body(1.0, 1.0), body(0.0, 1.0)]).unwrap_err();
        assert!(e.to_string().contains("bodies[2].j_kgm2"), "{e}");
    }

    #[test]
    fn two_mass_frequency_is_analytic() {
        // ω² = c (J1 + J2)/(J1 J2)
        let ch = Chain::new(vec!["a".into(), "b".into()], vec![2.0, 3.0], vec![600.0]).unwrap();
        let m = ch.mechanical().modes().unwrap();
        let w = (600.0_f64 * 5.0 / 6.0).sqrt();
        assert_eq!(m.frequencies_hz[0], 0.0);
        assert_relative_eq!(m.frequencies_hz[1], w / (2.0 * std::f64::consts::PI), max_relative = 1e-12);
    }
}
