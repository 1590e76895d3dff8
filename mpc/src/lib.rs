//! # mpc — model-predictive control of the rig on the plant's state space
//!
//! Section 1.2 of Hübner & Prokop (Vehicles 2026): the rig's PID control and dead times falsify
//! driveability measurements; a model-predictive controller built on the plant model is the way
//! out. This crate is what a rig engineer embeds in that controller:
//!
//! - [`model`]: any continuous `plant` state space, reduced to what its outputs observe and
//!   held by a zero-order hold.
//! - [`qp`]: the MPC problem (tracking, side-shaft torque oscillation penalty, hard input and
//!   rate bounds, soft output bounds, Riccati terminal cost, move blocking) as a parametric
//!   QP, condensed or sparse; only q and b change per step.
//! - [`solver`]: Clarabel set up once, updated in place.
//! - [`estimator`]: steady-state Kalman filter with input disturbances (offset-free).
//! - [`controller`]: one allocation-free step; the shifted previous plan when a solve fails.
//! - [`closed_loop`]: simulation against a plant, the PI baseline, step figures.
//! - [`evaluation`]: how `rigtwin mpc` judges a controller on any model: its closed loop, its
//!   timing and allocations, its first input against the exact optimum; the report.
//! - [`prediction`]: any model (the paper rig with its effects, a drive model) as a
//!   prediction model with its `[mpc]` section's settings.
//! - [`realtime`]: the core a real-time target runs (the C library, the controller FMU).
#![warn(missing_docs)]

pub mod alloc_counter;
pub mod closed_loop;
pub mod controller;
pub mod drive_plant;
pub mod error;
pub mod estimator;
pub mod evaluation;
pub mod model;
pub mod prediction;
pub mod qp;
pub mod realtime;
pub mod settings;
pub mod solver;

pub use controller::{Controller, StepInfo};
pub use drive_plant::DrivePlant;
pub use error::{MpcError, Result};
pub use prediction::{Design, Prediction};
pub use realtime::{RealTime, Status};
pub use settings::{
    exponential_blocks, Formulation, InputSettings, MpcSection, MpcSettings, OutputSettings, SolverSettings,
    MAX_HORIZON,
};
