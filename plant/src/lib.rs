//! # plant — the torsional model of a powertrain HIL rig
//!
//! After Hübner & Prokop, *Modelling and Parametrisation Approach for an Electric Powertrain in a
//! Hardware-in-the-Loop Environment*, Vehicles 2026, 8, 12.
//!
//! - **Geometry → chain** ([`segment`], [`chain`]): a hollow cylinder has J = ρ l π(d1⁴ − d2⁴)/32
//!   (eq. 1) and c = G π(d1⁴ − d2⁴)/(32 l) (eq. 2); neighbours couple through their half
//!   lengths, c_T = 2 c_i c_{i+1}/(c_i + c_{i+1}) (eq. 3); diameter steps lengthen the thin
//!   segment by Δl (eqs. 4–6).
//! - **Modal analysis** ([`modal`]): J q̈ + C q = 0 → natural frequencies and mode shapes; the
//!   poles, damped frequencies and damping ratios of a damped system (`damp`).
//! - **Reduction** ([`reduce`]) after Rivin/Di (eqs. 7–12): the paper's 15-mass chain becomes
//!   J1 = 0.9148, J9 = 3.5003, J17 = 0.9148 kg m², c_T1 = 13,093, c_T14 = 10,211 Nm/rad.
//! - **The rig** ([`rig`]): the three-mass smooth strand (eq. 14) and its variants V1–V4 with
//!   the additional spring c_TΔ in series (eqs. 16–18, 44, 45); the open differential
//!   (eqs. 27–34, A1) with C = c_l c_r/(c_l + c_r) a aᵀ, a = [−1, 2, −1].
//! - **State space** ([`statespace`]): x = [qᵀ q̇ᵀ]ᵀ, u = [M_m2, M_drive, M_m3] (eqs. 35–38).
//! - **Shuffle mode** ([`shuffle`]): drive against both outputs, outputs in phase, side shafts
//!   as nodes.
//! - **Bearing block** ([`bearing`]): K/C/M force coefficients on a soft support, impedance
//!   H = (K + Kh) − ω²(M + Mh) + iω(C + Ch), flexibility G = H⁻¹, state space (San Andrés 2011).
//!
//! - **Predictor** ([`predictor`]): a drive model's one-step-ahead predictor, the simulation
//!   held to the measured outputs by the steady-state Kalman gain of its linear part
//!   ([`riccati`]: the discrete Riccati equation).
//!
//! No I/O: file formats live in the `rigtwin` package.
#![warn(missing_docs)]

pub mod bearing;
pub mod bending;
pub mod chain;
pub mod delay_line;
pub mod drive;
pub mod error;
pub mod integrate;
pub mod line;
pub mod mechanical;
pub mod modal;
pub mod paper;
pub mod predictor;
pub mod preset;
pub mod reduce;
pub mod riccati;
pub mod rig;
pub mod segment;
pub mod shuffle;
pub mod statespace;
pub mod stepper;
pub mod zoh_step;

pub use bearing::{BearingModel, CoefficientTable, Coefficients, Support};
pub use bending::{Beam, BeamSegment, Deflection};
pub use chain::{Body, Chain};
pub use delay_line::DelayLine;
pub use drive::{
    ActuatorLag, Backlash, Compliance, CoulombFriction, Dimension, DriveModel, Dynamics, Effect, EffectModel, Element,
    Parameter, TimeDelay,
};
pub use error::{PlantError, Result};
pub use line::{Coupling, Domain, Line, LineBody, Quantity, MAX_BODIES, MAX_COUPLINGS};
pub use mechanical::{Layout, MechanicalModel, Output, Spring};
pub use modal::{damp, modes, Modes, Pole};
pub use preset::{record_speeds, record_start, simulate_record};
pub use reduce::{reduce, Reduction, ReductionStep};
pub use rig::{AdditionalSpring, Effective, Rig, RigChain, RigParams, Variant};
pub use segment::{bodies_from_segments, step_length_correction_m, Segment};
pub use shuffle::{classify, ModeKind};
pub use statespace::{lstsq, zoh, DiscreteStateSpace, StateSpace};
pub use stepper::{Coordinate, Stepper};
