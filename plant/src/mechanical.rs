//! Second-order torsional systems J q̈ + D q̇ + C q = M and their state space (eqs. (21)–(26), (35)–(38)).
//!
//! Every torsional model of the crate (chain, three-mass rig, open differential) is one of these:
//! an inertia matrix, a list of springs and diagonal drag. A spring is a Kelvin–Voigt element
//! whose elongation is a linear function eᵀq of the coordinates, so its potential energy is
//! ½ c (eᵀq)² and it contributes c e eᵀ to the stiffness matrix (eq. (26)) and d e eᵀ to the
//! damping matrix — the damping matrix is built the same way as the stiffness matrix.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{PlantError, Result};
use crate::modal::{self, Modes};
use crate::statespace::StateSpace;

/// A spring-damper whose elongation is eᵀq.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    /// Name, e.g. "short side shaft".
    pub name: String,
    /// e: elongation = eᵀq, rad per rad of each coordinate.
    pub elongation: DVector<f64>,
    /// Stiffness c, Nm/rad.
    pub stiffness: f64,
    /// Damping d, Nm s/rad.
    pub damping: f64,
}

impl Spring {
    /// Torque the spring transmits, c eᵀq + d eᵀq̇, Nm.
    pub fn torque_nm(&self, q: &DVector<f64>, qdot: &DVector<f64>) -> f64 {
        self.stiffness * self.elongation.dot(q) + self.damping * self.elongation.dot(qdot)
    }
}

/// Where the rig's parts sit among the coordinates, for the shuffle classifier (0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Layout {
    /// Coordinate of load machine M2 (left output).
    pub m2: usize,
    /// Coordinate of the drive (differential cage), when the model still has it.
    pub drive: Option<usize>,
    /// Coordinate of load machine M3 (right output).
    pub m3: usize,
    /// The two coordinates that bracket the short side shaft (M2 side).
    pub short_shaft: (usize, usize),
    /// The two coordinates that bracket the long side shaft (M3 side).
    pub long_shaft: (usize, usize),
}

/// A linear second-order mechanical system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MechanicalModel {
    /// One name per coordinate.
    pub dof_names: Vec<String>,
    /// Inertia matrix J (symmetric positive definite), kg m².
    pub inertia: DMatrix<f64>,
    /// Springs; C = Σ c e eᵀ and D = Σ d e eᵀ + diag(drag).
    pub springs: Vec<Spring>,
    /// Speed-proportional drag of each coordinate to ground, Nm s/rad.
    pub drag: DVector<f64>,
    /// Roles of the coordinates, where the model is a rig.
    pub layout: Option<Layout>,
}

/// Which signals the state space outputs (eq. (36) uses the angles and speeds).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Output {
    /// The angles q, rad.
    Angles,
    /// The speeds q̇, rad/s.
    Speeds,
    /// The torque of every spring, c eᵀq + d eᵀq̇, Nm.
    SpringTorques,
}

impl MechanicalModel {
    /// Number of coordinates.
    pub fn dofs(&self) -> usize {
        self.dof_names.len()
    }

    /// Stiffness matrix C = Σ c e eᵀ, Nm/rad (eq. (26)).
    pub fn stiffness_matrix(&self) -> DMatrix<f64> {
        let n = self.dofs();
        self.springs
            .iter()
            .fold(DMatrix::zeros(n, n), |k, s| k + &s.elongation * s.elongation.transpose() * s.stiffness)
    }

    /// Damping matrix D = Σ d e eᵀ + diag(drag), Nm s/rad.
    pub fn damping_matrix(&self) -> DMatrix<f64> {
        let n = self.dofs();
        let springs = self
            .springs
            .iter()
            .fold(DMatrix::zeros(n, n), |k, s| k + &s.elongation * s.elongation.transpose() * s.damping);
        springs + DMatrix::from_diagonal(&self.drag)
    }

    /// True when any spring damping or drag is non-zero.
    pub fn is_damped(&self) -> bool {
        self.springs.iter().any(|s| s.damping != 0.0) || self.drag.iter().any(|&d| d != 0.0)
    }

    /// Undamped natural frequencies and normalised mode shapes of (J, C).
    pub fn modes(&self) -> Result<Modes> {
        modal::modes(&self.inertia, &self.stiffness_matrix())
    }

    /// Eqs. (35)–(38): x = [qᵀ q̇ᵀ]ᵀ, u = torques on every coordinate,
    /// A = [0 E; −J⁻¹C −J⁻¹D], B = [0; J⁻¹], outputs as selected, D = 0.
    pub fn state_space(&self, outputs: &[Output]) -> Result<StateSpace> {
        let n = self.dofs();
        let jinv = self
            .inertia
            .clone()
            .cholesky()
            .ok_or_else(|| PlantError::Numerical("inertia matrix is not positive definite".into()))?
            .inverse();
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        a.view_mut((0, n), (n, n)).fill_with_identity();
        a.view_mut((n, 0), (n, n)).copy_from(&(-&jinv * self.stiffness_matrix()));
        a.view_mut((n, n), (n, n)).copy_from(&(-&jinv * self.damping_matrix()));
        let mut b = DMatrix::zeros(2 * n, n);
        b.view_mut((n, 0), (n, n)).copy_from(&jinv);

        let mut rows: Vec<DVector<f64>> = Vec::new();
        let mut output_names = Vec::new();
        for o in outputs {
            match o {
                Output::Angles | Output::Speeds => {
                    let offset = if *o == Output::Angles { 0 } else { n };
                    for (i, name) in self.dof_names.iter().enumerate() {
                        let mut r = DVector::zeros(2 * n);
                        r[offset + i] = 1.0;
                        rows.push(r);
                        output_names.push(if *o == Output::Angles {
                            format!("phi_{name}")
                        } else {
                            format!("w_{name}")
                        });
                    }
                }
                Output::SpringTorques => {
                    for s in &self.springs {
                        let mut r = DVector::zeros(2 * n);
                        r.rows_mut(0, n).copy_from(&(&s.elongation * s.stiffness));
                        r.rows_mut(n, n).copy_from(&(&s.elongation * s.damping));
                        rows.push(r);
                        output_names.push(format!("T_{}", s.name.replace(' ', "_")));
                    }
                }
            }
        }
        let c = DMatrix::from_fn(rows.len(), 2 * n, |i, j| rows[i][j]);
        let d = DMatrix::zeros(rows.len(), n);
        Ok(StateSpace {
            a,
            b,
            c,
            d,
            state_names: self
                .dof_names
                .iter()
                .map(|s| format!("phi_{s}"))
                .chain(self.dof_names.iter().map(|s| format!("w_{s}")))
                .collect(),
            input_names: self.dof_names.iter().map(|s| format!("M_{s}")).collect(),
            output_names,
        })
    }
}
