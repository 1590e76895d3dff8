//! The controller a real-time target runs — the one core behind the C library
//! (`rigtwin_mpc.h`) and the controller FMU: a [`Controller`] on a [`Prediction`] with the
//! signals named for the outside (what is measured, what has a reference, what is commanded),
//! started at an operating point and stepped with plain arrays. It guards what crosses a
//! boundary: non-finite measurements or references are refused (the last commands held), a
//! non-finite command is never returned (the controller is then failed for good), and a step
//! allocates nothing.

use crate::closed_loop::steady_spin;
use crate::error::{MpcError, Result};
use crate::prediction::Prediction;
use crate::{Controller, MpcSettings};

/// What a step did (`rigtwin_mpc_status` in C).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The QP was solved.
    Ok = 0,
    /// The shifted previous plan was applied.
    Fallback = 1,
    /// A measurement or reference was not finite: the last commands were held.
    BadInput = -1,
    /// The controller failed (a non-finite command, or an earlier failure): the last finite
    /// commands were held.
    Invalid = -2,
}

/// The indices of the outputs (of `output_names`) that `settings` measure, in output order: what
/// a real-time controller's `measured[]` holds.
pub fn measured_outputs(output_names: &[String], settings: &MpcSettings) -> Vec<usize> {
    (0..output_names.len())
        .filter(|&j| settings.outputs.iter().any(|o| o.name == output_names[j] && o.noise_std.is_some()))
        .collect()
}

/// The real-time controller of one model.
pub struct RealTime {
    controller: Controller,
    model: plant::statespace::StateSpace,
    /// Model output index of each measured signal, in model output order.
    measured: Vec<usize>,
    measured_names: Vec<String>,
    reference_names: Vec<String>,
    /// Every plant output: the measured ones set per step, the others unused.
    y: Vec<f64>,
    /// The commands of the last step (model input order).
    last: Vec<f64>,
    failed: bool,
    dt_s: f64,
}

impl RealTime {
    /// The controller of `prediction` with `settings`, at rest.
    pub fn new(prediction: &Prediction, settings: &MpcSettings) -> Result<RealTime> {
        let model = &prediction.model;
        let controller = Controller::with_input_delays(model, &prediction.input_delays_s, settings)?;
        if controller.reference_names() != settings.reference_names() {
            return Err(MpcError::Numerical(format!(
                "the settings list the inputs out of the plant's order ({:?})",
                model.input_names
            )));
        }
        let measured = measured_outputs(&model.output_names, settings);
        if measured.is_empty() {
            return Err(MpcError::Numerical("the controller measures no output".into()));
        }
        let mut c = RealTime {
            measured_names: measured.iter().map(|&j| model.output_names[j].clone()).collect(),
            reference_names: settings.reference_names(),
            y: vec![0.0; model.output_names.len()],
            last: vec![0.0; model.input_names.len()],
            measured,
            controller,
            model: model.clone(),
            failed: false,
            dt_s: settings.dt_s,
        };
        c.reset(0.0)?;
        Ok(c)
    }

    /// What `measured[]` holds, in order (plant outputs).
    pub fn measured_names(&self) -> &[String] {
        &self.measured_names
    }

    /// What `reference[]` holds, in order (tracked outputs, then tracked inputs).
    pub fn reference_names(&self) -> &[String] {
        &self.reference_names
    }

    /// What `commands[]` holds, in order (the plant's inputs).
    pub fn command_names(&self) -> &[String] {
        &self.model.input_names
    }

    /// The control period, s.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Starts from steady motion at `speed` (every body at that speed; rad/s or m/s), the inputs
    /// holding it against the drag; refused when the speed is not finite or no input can hold it.
    pub fn reset(&mut self, speed: f64) -> Result<()> {
        if !speed.is_finite() {
            return Err(MpcError::Numerical(format!("speed {speed}: expected a finite value")));
        }
        let (x0, u0) = steady_spin(&self.model, speed)?;
        if u0.iter().any(|v| !v.is_finite()) {
            return Err(MpcError::Numerical(format!("no finite inputs hold the model at {speed}")));
        }
        self.controller.reset(&x0, &u0);
        self.last.copy_from_slice(&u0);
        self.failed = false;
        Ok(())
    }

    /// One step: `measured` and `reference` in the orders of [`RealTime::measured_names`] and
    /// [`RealTime::reference_names`]; `commands` (as many as [`RealTime::command_names`])
    /// receives the inputs to apply now. Wrong lengths are [`Status::Invalid`] with nothing
    /// written. Allocation-free.
    pub fn step(&mut self, measured: &[f64], reference: &[f64], commands: &mut [f64]) -> Status {
        if measured.len() != self.measured.len()
            || reference.len() != self.reference_names.len()
            || commands.len() != self.last.len()
        {
            return Status::Invalid;
        }
        if self.failed {
            commands.copy_from_slice(&self.last);
            return Status::Invalid;
        }
        if measured.iter().chain(reference).any(|v| !v.is_finite()) {
            commands.copy_from_slice(&self.last);
            return Status::BadInput;
        }
        for (k, &j) in self.measured.iter().enumerate() {
            self.y[j] = measured[k];
        }
        let (u, info) = self.controller.step(&self.y, reference);
        if u.iter().any(|v| !v.is_finite()) {
            self.failed = true;
            commands.copy_from_slice(&self.last);
            return Status::Invalid;
        }
        self.last.copy_from_slice(u);
        commands.copy_from_slice(u);
        if info.fallback {
            Status::Fallback
        } else {
            Status::Ok
        }
    }

    /// The commands of the last step (after a reset: the steady state's).
    pub fn commands(&self) -> &[f64] {
        &self.last
    }

    /// Marks the controller failed (after a panic caught at a boundary): every later step is
    /// [`Status::Invalid`] until a reset.
    pub fn fail(&mut self) {
        self.failed = true;
    }

    /// Length of the record [`RealTime::save_state`] writes.
    pub fn state_len(&self) -> usize {
        self.controller.state_len() + self.last.len()
    }

    /// The controller's state and its last commands, into `out` (of [`RealTime::state_len`]).
    pub fn save_state(&self, out: &mut [f64]) {
        let n = self.controller.state_len();
        self.controller.save_state(&mut out[..n]);
        out[n..].copy_from_slice(&self.last);
    }

    /// Restores a record of [`RealTime::save_state`]; false (nothing changed) if it cannot be
    /// one.
    pub fn restore_state(&mut self, s: &[f64]) -> bool {
        let n = self.controller.state_len();
        if s.len() != self.state_len() || s[n..].iter().any(|v| !v.is_finite()) {
            return false;
        }
        if !self.controller.restore_state(&s[..n]) {
            return false;
        }
        self.last.copy_from_slice(&s[n..]);
        self.failed = false;
        true
    }

    /// The controller (for its QP, timing and first-input checks).
    pub fn controller(&self) -> &Controller {
        &self.controller
    }
}

impl std::fmt::Debug for RealTime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RealTime")
            .field("measured", &self.measured_names)
            .field("references", &self.reference_names)
            .field("commands", &self.model.input_names)
            .field("failed", &self.failed)
            .finish()
    }
}
