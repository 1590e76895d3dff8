//! The controller a real-time target runs — the one core behind the C library
//! (`rigtwin_mpc.h`) and the controller FMU: a [`Controller`] on a [`Prediction`] with the
//! signals named for the outside (what is measured, what has a reference, what is commanded),
//! started at an operating point and stepped with plain arrays. It guards what crosses a
//! boundary: non-finite measurements or references are refused (the last commands held), a
//! non-finite command is never returned (the controller is then failed for good), and a step
//! allocates nothing.

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
    /// Free motion at unit speed (`Prediction::motion`).
    motion: Option<crate::prediction::Motion>,
    /// Each measured output in that motion (the first body at 1).
    pattern: Vec<f64>,
    /// The commands of the last step (model input order).
    last: Vec<f64>,
    failed: bool,
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
        let pattern = match &prediction.motion {
            Some(m) => measured.iter().map(|&j| (model.c.row(j) * &m.state)[0]).collect(),
            None => vec![0.0; measured.len()],
        };
        let mut c = RealTime {
            motion: prediction.motion.clone(),
            pattern,
            measured_names: measured.iter().map(|&j| model.output_names[j].clone()).collect(),
            reference_names: settings.reference_names(),
            y: vec![0.0; model.output_names.len()],
            last: vec![0.0; model.input_names.len()],
            measured,
            controller,
            model: model.clone(),
            failed: false,
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

    /// Starts from steady motion at `speed` — every body moving together as its gears allow, the
    /// first body at `speed` (rad/s or m/s), the inputs holding it against the drag and the
    /// couplings twisted as that needs ([`RealTime::steady_state`]) — or at rest for 0. Refused
    /// when the speed is not finite, or not 0 for a model that cannot move freely.
    pub fn reset(&mut self, speed: f64) -> Result<()> {
        if !speed.is_finite() {
            return Err(MpcError::Numerical(format!("speed {speed}: expected a finite value")));
        }
        let n = self.model.nstates();
        let (x0, rate) = match (&self.motion, speed == 0.0) {
            (_, true) => (nalgebra::DVector::zeros(n), nalgebra::DVector::zeros(n)),
            (Some(m), false) => (&m.state * speed, &m.rate * speed),
            (None, false) => {
                return Err(MpcError::Numerical(format!(
                    "speed {speed}: the model cannot move freely (a spring to ground holds it): only 0 is an operating speed"
                )))
            }
        };
        let (x0, u0) = self.steady_state(x0, &rate)?;
        if u0.iter().any(|v| !v.is_finite()) {
            return Err(MpcError::Numerical(format!("no finite inputs hold the model at {speed}")));
        }
        self.controller.reset(&x0, u0.as_slice());
        self.last.copy_from_slice(u0.as_slice());
        self.failed = false;
        Ok(())
    }

    /// The steady motion through the speeds `x` whose positions advance at `rate` (ẋ = rate):
    /// the inputs u = B⁺(rate − A x) that hold it; where they cannot without the couplings
    /// twisting (drag behind a gear stage), the twists too — the least-norm (x, u) with
    /// A x + B u = rate and the measured outputs at their values in `x`.
    fn steady_state(
        &self,
        x: nalgebra::DVector<f64>,
        rate: &nalgebra::DVector<f64>,
    ) -> Result<(nalgebra::DVector<f64>, nalgebra::DVector<f64>)> {
        let (a, b) = (&self.model.a, &self.model.b);
        let fail = |e: &str| MpcError::Numerical(e.to_string());
        let u = b.clone().pseudo_inverse(1e-12).map_err(fail)? * (rate - a * &x);
        let residual = (a * &x + b * &u - rate).norm();
        if residual <= 1e-9 * (a * &x).norm().max(rate.norm()).max(1e-300) {
            return Ok((x, u));
        }
        let (n, m, k) = (a.nrows(), b.ncols(), self.measured.len());
        let mut lhs = nalgebra::DMatrix::zeros(n + k, n + m);
        lhs.view_mut((0, 0), (n, n)).copy_from(a);
        lhs.view_mut((0, n), (n, m)).copy_from(b);
        let mut rhs = nalgebra::DVector::zeros(n + k);
        rhs.rows_mut(0, n).copy_from(rate);
        for (r, &j) in self.measured.iter().enumerate() {
            let row = self.model.c.row(j);
            lhs.view_mut((n + r, 0), (1, n)).copy_from(&row);
            rhs[n + r] = (row * &x)[0];
        }
        let z = lhs.pseudo_inverse(1e-12).map_err(fail)? * rhs;
        Ok((z.rows(0, n).into_owned(), z.rows(n, m).into_owned()))
    }

    /// The speed of free motion that fits the measurements `measured` best (least squares of
    /// the motion's pattern over the measured speeds; the rig's: their mean), 0 for a model
    /// that cannot move freely: where a controller starts from.
    pub fn speed_of(&self, measured: &[f64]) -> f64 {
        let norm: f64 = self.pattern.iter().map(|p| p * p).sum();
        if norm == 0.0 {
            return 0.0;
        }
        self.pattern.iter().zip(measured).map(|(p, y)| p * y).sum::<f64>() / norm
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
