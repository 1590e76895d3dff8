//! The controller FMU: `rigtwin mpc`'s controller (`mpc::rig::prediction` of the parameter
//! set's rig and effects, `mpc::Controller`) as a co-simulation FMU. Inputs: what the rig
//! measures (the three speeds) and the references; outputs: the torque commands; tunable
//! parameters: the MPC's weights, bounds and time limit. The communication step is the control
//! period. The outputs depend directly on the inputs: the step that makes them runs when they
//! are read after the inputs of a communication point were set (or at DoStep if they are not
//! read), so a master that reads the plant, sets the controller's inputs, reads its outputs and
//! sets the plant's inputs (Gauss-Seidel) closes the loop without a delay — as `rigtwin mpc`
//! does in process; a master that reads every output right after the step and sets every
//! input before the next (Jacobi, as OSP libcosim) gets the commands of the step before: one
//! sample of computational delay.

use serde::{Deserialize, Serialize};

use crate::params::FmuParams;
use crate::variables::Constraint;
use mpc::{Controller, MpcSettings};

/// Inputs: (name, unit, description), in input order.
pub const INPUTS: [(&str, &str, &str); 6] = [
    ("w_m2", "rad/s", "measured speed of load machine M2"),
    ("w_drive", "rad/s", "measured speed of the drive"),
    ("w_m3", "rad/s", "measured speed of load machine M3"),
    ("w_m2_ref", "rad/s", "speed reference of load machine M2"),
    ("w_m3_ref", "rad/s", "speed reference of load machine M3"),
    ("M_drive_ref", "N.m", "drive torque reference"),
];

/// Outputs: (name, description), torques in N.m, in the prediction model's input order.
pub const OUTPUTS: [(&str, &str); 3] = [
    ("M_m2", "torque command of load machine M2"),
    ("M_drive", "torque command of the drive"),
    ("M_m3", "torque command of load machine M3"),
];

/// Tunable parameters: (name, unit, description, constraint), in the order of
/// [`ControllerSpec::values`].
pub const PARAMETERS: [(&str, &str, &str, Constraint); 9] = [
    (
        "mpc.speed_weight",
        "s2/rad2",
        "weight on the load speeds' tracking error: cost per (rad/s)^2",
        Constraint::Positive,
    ),
    (
        "mpc.shaft_weight",
        "1/(N.m)2",
        "weight on the side-shaft torques' oscillation: cost per (N.m)^2",
        Constraint::NonNegative,
    ),
    ("mpc.shaft_soft_max", "N.m", "soft bound on |side-shaft torque|", Constraint::Positive),
    (
        "mpc.drive_weight",
        "1/(N.m)2",
        "weight on the drive torque's tracking error: cost per (N.m)^2",
        Constraint::Positive,
    ),
    ("mpc.load_torque_max", "N.m", "hard bound on |load-machine torque|", Constraint::Positive),
    ("mpc.drive_torque_max", "N.m", "hard bound on |drive torque|", Constraint::Positive),
    ("mpc.load_rate_max", "N.m/s", "hard bound on the load-machine torque's rate", Constraint::Positive),
    ("mpc.drive_rate_max", "N.m/s", "hard bound on the drive torque's rate", Constraint::Positive),
    (
        "mpc.time_limit",
        "s",
        "wall-clock limit of one QP solve (then the shifted plan is applied)",
        Constraint::Positive,
    ),
];

/// The controller an FMU carries: horizon and move blocks (fixed at export) and the tunable
/// settings (start values of [`PARAMETERS`]); defaults are `mpc::MpcSettings::powertrain`'s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// Prediction horizon, steps of 1 ms.
    pub horizon: usize,
    /// Number of move blocks (0: every step free).
    pub move_blocks: usize,
    /// The tunable settings, in [`PARAMETERS`] order.
    pub values: Vec<f64>,
}

impl ControllerSpec {
    /// `rigtwin mpc`'s controller with horizon `horizon` and `move_blocks` blocks.
    pub fn new(horizon: usize, move_blocks: usize) -> ControllerSpec {
        let s = MpcSettings::powertrain(horizon.max(1));
        let w = s.outputs.iter().find(|o| o.name == "w_m2").map_or(100.0, |o| o.weight);
        let shaft = s.outputs.iter().find(|o| o.name == "T_short_side_shaft");
        let (load, drive) = (&s.inputs[0], &s.inputs[1]);
        ControllerSpec {
            horizon,
            move_blocks,
            values: vec![
                w,
                shaft.map_or(1.0, |o| o.weight),
                shaft.and_then(|o| o.soft_max).unwrap_or(60.0),
                drive.weight_per_nm2,
                load.max_nm,
                drive.max_nm,
                load.max_rate_nm_per_s,
                drive.max_rate_nm_per_s,
                s.solver.time_limit_s,
            ],
        }
    }

    /// The settings, checked; the error names the parameter.
    pub fn settings(&self) -> Result<MpcSettings, String> {
        if self.values.len() != PARAMETERS.len() {
            return Err(format!("{} controller settings for {}", self.values.len(), PARAMETERS.len()));
        }
        for (v, p) in self.values.iter().zip(&PARAMETERS) {
            p.3.check(*v).map_err(|want| format!("`{}` = {v}: expected {want}", p.0))?;
        }
        let v = &self.values;
        let mut s = MpcSettings::powertrain(self.horizon);
        s.move_blocks =
            if self.move_blocks == 0 { Vec::new() } else { mpc::exponential_blocks(self.horizon, self.move_blocks) };
        for o in s.outputs.iter_mut() {
            match o.name.as_str() {
                "w_m2" | "w_m3" => o.weight = v[0],
                "T_short_side_shaft" | "T_long_side_shaft" => {
                    o.weight = v[1];
                    o.soft_min = Some(-v[2]);
                    o.soft_max = Some(v[2]);
                }
                _ => {}
            }
        }
        for u in s.inputs.iter_mut() {
            let (max, rate) = if u.name == "M_drive" { (v[5], v[7]) } else { (v[4], v[6]) };
            u.min_nm = -max;
            u.max_nm = max;
            u.max_rate_nm_per_s = rate;
            if u.name == "M_drive" {
                u.weight_per_nm2 = v[3];
            }
        }
        s.solver.time_limit_s = v[8];
        s.validate().map_err(|e| e.to_string())?;
        Ok(s)
    }
}

/// The controller of an instance and its lazy step.
pub struct ControllerMachine {
    controller: Controller,
    model: plant::statespace::StateSpace,
    /// Model output index of each measured input (w_m2, w_drive, w_m3).
    measured: [usize; 3],
    /// Model input index of each output.
    commands: [usize; 3],
    y: Vec<f64>,
    /// The commands of the last step.
    out: [f64; 3],
    /// The communication point and the inputs the last step was made at, while it is not yet
    /// committed by DoStep.
    computed: Option<(f64, [f64; 6])>,
    /// The controller's state before that step (to redo it if the inputs change).
    before: Vec<f64>,
    /// Control period, s.
    pub dt_s: f64,
}

impl ControllerMachine {
    /// The controller of parameter set `p` (its `controller` spec), at rest.
    pub fn new(p: &FmuParams) -> Result<ControllerMachine, String> {
        let spec = p.controller.as_ref().ok_or("the parameter set has no controller")?;
        let settings = spec.settings()?;
        let pred = mpc::prediction::prediction(&p.powertrain, p.variant, &p.effects, settings.dt_s)
            .map_err(|e| e.to_string())?;
        let controller =
            Controller::with_input_delays(&pred.model, &pred.input_delays_s, &settings).map_err(|e| e.to_string())?;
        let refs = controller.reference_names();
        if refs != ["w_m2", "w_m3", "M_drive"] {
            return Err(format!("the controller's references are {refs:?}"));
        }
        let find = |names: &[String], n: &str| names.iter().position(|x| x == n).ok_or(format!("no signal `{n}`"));
        let (mut measured, mut commands) = ([0; 3], [0; 3]);
        for i in 0..3 {
            measured[i] = find(&pred.model.output_names, INPUTS[i].0)?;
            commands[i] = find(&pred.model.input_names, OUTPUTS[i].0)?;
        }
        let n = controller.state_len();
        Ok(ControllerMachine {
            controller,
            y: vec![0.0; pred.model.output_names.len()],
            model: pred.model,
            measured,
            commands,
            out: [0.0; 3],
            computed: None,
            before: vec![0.0; n],
            dt_s: settings.dt_s,
        })
    }

    /// Starts from steady spinning at `speed_radps` (the load machines holding it against their
    /// drag, no drive torque).
    pub fn reset(&mut self, speed_radps: f64) -> Result<(), String> {
        let (x0, u0) = mpc::closed_loop::steady_spin(&self.model, speed_radps).map_err(|e| e.to_string())?;
        self.controller.reset(&x0, &u0);
        self.out = self.commands.map(|j| u0[j]);
        self.computed = None;
        Ok(())
    }

    /// The commands at communication point `t` for the inputs `u` (measured speeds, then the
    /// references): the step is made once per point, and made again from the state before it
    /// if the inputs have changed since. `fresh`: the importer has set the inputs since the
    /// last DoStep; if it has not (a Jacobi master reads every output right after the step),
    /// the commands of the last step are returned — a sample of computational delay, as a
    /// controller on a real-time target has — and the step is made at DoStep. Allocation-free.
    pub fn outputs(&mut self, t: f64, u: &[f64], fresh: bool) -> Result<[f64; 3], String> {
        let inputs: [f64; 6] = u.try_into().map_err(|_| format!("{} inputs for 6", u.len()))?;
        if !fresh && self.computed.is_none() {
            return Ok(self.out);
        }
        match self.computed {
            Some((at, given)) if at == t && given == inputs => return Ok(self.out),
            Some((at, _)) if at == t => {
                self.controller.restore_state(&self.before);
            }
            _ => self.controller.save_state(&mut self.before),
        }
        for (k, &j) in self.measured.iter().enumerate() {
            self.y[j] = inputs[k];
        }
        let (cmd, _) = self.controller.step(&self.y, &inputs[3..]);
        let next = self.commands.map(|j| cmd[j]);
        if let Some(v) = next.iter().find(|v| !v.is_finite()) {
            self.controller.restore_state(&self.before);
            self.computed = None;
            return Err(format!("the controller commanded {v} N.m at {t} s"));
        }
        self.out = next;
        self.computed = Some((t, inputs));
        Ok(self.out)
    }

    /// The commands of the last step (after a reset: the steady state's).
    pub fn commands(&self) -> [f64; 3] {
        self.out
    }

    /// DoStep from `t` over `h` (the control period) with inputs `u`: the step of `t` is made if
    /// it was not, and committed.
    pub fn advance(&mut self, t: f64, h: f64, u: &[f64]) -> Result<(), String> {
        if (h - self.dt_s).abs() > 1e-9 * self.dt_s {
            return Err(format!("the communication step must be the control period {} s, got {h} s", self.dt_s));
        }
        self.outputs(t, u, true)?;
        self.computed = None;
        Ok(())
    }

    /// Length of [`ControllerMachine::save`]'s record.
    pub fn state_len(&self) -> usize {
        self.controller.state_len() + 3
    }

    /// The controller's state at the present communication point (before a step made there
    /// and not yet committed) and its last commands.
    pub fn save(&self, out: &mut [f64]) {
        let n = self.controller.state_len();
        if self.computed.is_some() {
            out[..n].copy_from_slice(&self.before);
        } else {
            self.controller.save_state(&mut out[..n]);
        }
        out[n..].copy_from_slice(&self.out);
    }

    /// Restores a record of [`ControllerMachine::save`]; false if it cannot be one.
    pub fn restore(&mut self, s: &[f64]) -> bool {
        let n = self.controller.state_len();
        if s.len() != n + 3 || !self.controller.restore_state(&s[..n]) {
            return false;
        }
        self.out.copy_from_slice(&s[n..]);
        self.computed = None;
        true
    }
}

impl std::fmt::Debug for ControllerMachine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ControllerMachine").field("dt_s", &self.dt_s).field("out", &self.out).finish()
    }
}
