//! The controller FMU: `rigtwin mpc`'s controller of any model (`mpc::Design::controller`, run
//! by the real-time core `mpc::RealTime` that the C library runs too) as a co-simulation FMU.
//! Inputs: what the plant measures (the rig's three speeds; a drive model's measured outputs)
//! and the references; outputs: the commands (the plant's inputs); tunable parameters: the
//! MPC's weights, bounds and time limit. The communication step is the control
//! period. The outputs depend directly on the inputs: the step that makes them runs when they
//! are read after the inputs of a communication point were set (or at DoStep if they are not
//! read), so a master that reads the plant, sets the controller's inputs, reads its outputs and
//! sets the plant's inputs (Gauss-Seidel) closes the loop without a delay — as `rigtwin mpc`
//! does in process; a master that reads every output right after the step and sets every
//! input before the next (Jacobi, as OSP libcosim) gets the commands of the step before: one
//! sample of computational delay.

use crate::params::{ControllerSpec, FmuParams, Plant};
use crate::variables::{Constraint, Port, Ports};
use mpc::{Design, MpcSection, MpcSettings, Prediction, RealTime, Status};
use plant::drive::{Dimension, MAX_INPUTS};
use plant::{Domain, DriveModel};

/// The paper rig's inputs: (name, unit, description), in input order.
pub const INPUTS: [(&str, &str, &str); 6] = [
    ("w_m2", "rad/s", "measured speed of load machine M2"),
    ("w_drive", "rad/s", "measured speed of the drive"),
    ("w_m3", "rad/s", "measured speed of load machine M3"),
    ("w_m2_ref", "rad/s", "speed reference of load machine M2"),
    ("w_m3_ref", "rad/s", "speed reference of load machine M3"),
    ("M_drive_ref", "N.m", "drive torque reference"),
];

/// The paper rig's outputs: (name, description), torques in N.m, in the prediction model's
/// input order.
pub const OUTPUTS: [(&str, &str); 3] = [
    ("M_m2", "torque command of load machine M2"),
    ("M_drive", "torque command of the drive"),
    ("M_m3", "torque command of load machine M3"),
];

/// The paper rig's tunable parameters: (name, unit, description, constraint), in the order of
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

/// The rig's tunable settings of `s`, in [`PARAMETERS`] order.
fn rig_values(s: &MpcSettings) -> Vec<f64> {
    let w = s.outputs.iter().find(|o| o.name == "w_m2").map_or(100.0, |o| o.weight);
    let shaft = s.outputs.iter().find(|o| o.name == "T_short_side_shaft");
    let (load, drive) = (&s.inputs[0], &s.inputs[1]);
    vec![
        w,
        shaft.map_or(1.0, |o| o.weight),
        shaft.and_then(|o| o.soft_max).unwrap_or(60.0),
        drive.weight_per_nm2,
        load.max_nm,
        drive.max_nm,
        load.max_rate_nm_per_s,
        drive.max_rate_nm_per_s,
        s.solver.time_limit_s,
    ]
}

impl ControllerSpec {
    /// `rigtwin mpc`'s controller of the paper rig with horizon `horizon` and `move_blocks` blocks.
    pub fn new(horizon: usize, move_blocks: usize) -> ControllerSpec {
        let s = MpcSettings::powertrain(horizon.max(1));
        ControllerSpec { horizon, move_blocks, values: rig_values(&s), section: None }
    }

    /// The controller of the model of `p` with its `[mpc]` section `section`: the rig's
    /// weights and bounds from the section, or a drive model's section kept whole.
    pub fn of_model(
        p: &FmuParams,
        section: &MpcSection,
        horizon: usize,
        move_blocks: usize,
    ) -> Result<ControllerSpec, String> {
        let spec = match &p.plant {
            Plant::PaperRig(_) => {
                let s = section.rig_settings(horizon).map_err(|e| e.to_string())?;
                ControllerSpec { horizon, move_blocks, values: rig_values(&s), section: None }
            }
            Plant::Drive(m) => {
                let (_, s) = Design::Drive(m).controller(section, horizon).map_err(|e| e.to_string())?;
                let largest = s.inputs.iter().map(|u| u.max_nm).fold(0.0, f64::max);
                let (speed_weight, force_weight) = section.drive_weights(largest);
                let mut values = vec![speed_weight, force_weight];
                if let Some(b) = section.force_soft_max {
                    values.push(b);
                }
                values.extend(s.inputs.iter().map(|u| u.max_nm));
                values.extend(s.inputs.iter().map(|u| u.max_rate_nm_per_s));
                values.push(s.solver.time_limit_s);
                ControllerSpec { horizon, move_blocks, values, section: Some(section.clone()) }
            }
        };
        spec.design(p)?;
        Ok(spec)
    }

    /// The prediction and the settings of the tunable values, checked; an error names the
    /// parameter.
    pub fn design(&self, p: &FmuParams) -> Result<(Prediction, MpcSettings), String> {
        let parameters = self.parameters(p)?;
        if self.values.len() != parameters.len() {
            return Err(format!("{} controller settings for {}", self.values.len(), parameters.len()));
        }
        for (v, q) in self.values.iter().zip(&parameters) {
            q.constraint.check(*v).map_err(|want| format!("`{}` = {v}: expected {want}", q.name))?;
        }
        let (prediction, mut s) = match (&p.plant, &self.section) {
            (Plant::PaperRig(_), _) => {
                let s = self.rig_settings();
                (p.plant.design().prediction(s.dt_s).map_err(|e| e.to_string())?, s)
            }
            (Plant::Drive(m), Some(section)) => {
                Design::Drive(m).controller(&self.drive_section(section), self.horizon).map_err(|e| e.to_string())?
            }
            (Plant::Drive(_), None) => return Err("a drive model's controller needs its [mpc] section".into()),
        };
        s.move_blocks =
            if self.move_blocks == 0 { Vec::new() } else { mpc::exponential_blocks(self.horizon, self.move_blocks) };
        s.solver.time_limit_s = *self.values.last().expect("checked above: every controller has a time limit");
        s.validate().map_err(|e| e.to_string())?;
        Ok((prediction, s))
    }

    /// The paper rig's settings of the [`PARAMETERS`] values.
    fn rig_settings(&self) -> MpcSettings {
        let v = &self.values;
        let mut s = MpcSettings::powertrain(self.horizon);
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
        s
    }

    /// A drive model's section with the tunable values in place of its weights and bounds.
    fn drive_section(&self, section: &MpcSection) -> MpcSection {
        let v = &self.values;
        let soft = usize::from(section.force_soft_max.is_some());
        let m = (v.len() - 3 - soft) / 2;
        MpcSection {
            speed_weight: Some(v[0]),
            force_weight: Some(v[1]),
            force_soft_max: section.force_soft_max.map(|_| v[2]),
            input_max: Some(v[2 + soft..2 + soft + m].to_vec()),
            input_rate_max: Some(v[2 + soft + m..2 + soft + 2 * m].to_vec()),
            ..section.clone()
        }
    }

    /// The FMU's tunable parameters for the model of `p` (the rig's [`PARAMETERS`]), in
    /// [`ControllerSpec::values`] order.
    fn parameters(&self, p: &FmuParams) -> Result<Vec<Port>, String> {
        match (&p.plant, &self.section) {
            (Plant::PaperRig(_), _) => Ok(PARAMETERS
                .iter()
                .map(|&(name, unit, description, constraint)| Port {
                    name: name.into(),
                    unit,
                    description: description.into(),
                    constraint,
                })
                .collect()),
            (Plant::Drive(m), Some(section)) => Ok(drive_parameters(m, section)),
            (Plant::Drive(_), None) => Err("a drive model's controller needs its [mpc] section".into()),
        }
    }

    /// The FMU's variables for the model of `p`.
    pub fn ports(&self, p: &FmuParams) -> Result<Ports, String> {
        let Plant::Drive(m) = &p.plant else {
            return Ok(Ports {
                parameters: self.parameters(p)?,
                inputs: INPUTS.iter().map(|&(n, u, d)| Port::of(n, u, d)).collect(),
                measured: 3,
                outputs: OUTPUTS.iter().map(|&(n, d)| Port::of(n, "N.m", d)).collect(),
            });
        };
        let section = self.section.as_ref().ok_or("a drive model's controller needs its [mpc] section")?;
        let (prediction, s) = Design::Drive(m).controller(section, self.horizon).map_err(|e| e.to_string())?;
        Ok(drive_ports(m, section, &prediction, &s))
    }
}

/// A drive model's controller FMU variables: the section's weights and bounds as tunables, its
/// measured outputs and references as inputs, its inputs as outputs.
fn drive_ports(m: &DriveModel, section: &MpcSection, prediction: &Prediction, s: &MpcSettings) -> Ports {
    let domain = m.line.domain;
    let (speed, force) = (Dimension::Speed.unit(domain), Dimension::Force.unit(domain));
    let unit_of_signal = |n: &str| if n.starts_with("w_") || n.starts_with("v_") { speed } else { force };
    let measured = mpc::realtime::measured_outputs(&prediction.model.output_names, s);
    let mut ports: Vec<Port> = measured
        .iter()
        .map(|&j| {
            let n = &prediction.model.output_names[j];
            Port::of(n.clone(), unit_of_signal(n), format!("measured {n}"))
        })
        .collect();
    for n in s.reference_names() {
        ports.push(Port::of(format!("{n}_ref"), unit_of_signal(&n), format!("reference of {n}")));
    }
    Ports {
        parameters: drive_parameters(m, section),
        measured: measured.len(),
        inputs: ports,
        outputs: prediction
            .model
            .input_names
            .iter()
            .map(|n| Port::of(n.clone(), force, format!("command of {n}")))
            .collect(),
    }
}

/// A drive model's tunable parameters: its `[mpc]` section's weights and bounds (the soft force
/// bound only where the section gives one), per input its bounds, the time limit — in the order
/// of [`ControllerSpec::values`].
fn drive_parameters(m: &DriveModel, section: &MpcSection) -> Vec<Port> {
    let domain = m.line.domain;
    let force = Dimension::Force.unit(domain);
    let (force_word, rate) = match domain {
        Domain::Rotational => ("torque", "N.m/s"),
        Domain::Translational => ("force", "N/s"),
    };
    let (speed_weight, force_weight) = match domain {
        Domain::Rotational => ("s2/rad2", "1/(N.m)2"),
        Domain::Translational => ("s2/m2", "1/N2"),
    };
    let tunable = |name: String, unit, description: String, constraint| Port {
        name: name.into(),
        unit,
        description: description.into(),
        constraint,
    };
    let mut parameters = vec![
        tunable(
            "mpc.speed_weight".into(),
            speed_weight,
            "weight on the tracked speeds' error: cost per unit squared".into(),
            Constraint::Positive,
        ),
        tunable(
            "mpc.force_weight".into(),
            force_weight,
            format!("weight on the penalised coupling {force_word}s: cost per unit squared"),
            Constraint::NonNegative,
        ),
    ];
    if section.force_soft_max.is_some() {
        parameters.push(tunable(
            "mpc.force_soft_max".into(),
            force,
            format!("soft bound on |penalised coupling {force_word}|"),
            Constraint::Positive,
        ));
    }
    let inputs = m.input_names();
    for name in &inputs {
        parameters.push(tunable(
            format!("mpc.input_max.{name}"),
            force,
            format!("hard bound on |{name}|"),
            Constraint::Positive,
        ));
    }
    for name in &inputs {
        parameters.push(tunable(
            format!("mpc.input_rate_max.{name}"),
            rate,
            format!("hard bound on the rate of {name}"),
            Constraint::Positive,
        ));
    }
    parameters.push(tunable(
        "mpc.time_limit".into(),
        "s",
        "wall-clock limit of one QP solve (then the shifted plan is applied)".into(),
        Constraint::Positive,
    ));
    parameters
}

/// The controller of an instance (`mpc::RealTime`) and its lazy step.
pub struct ControllerMachine {
    core: RealTime,
    /// How many inputs are measurements (the rest are references).
    measured: usize,
    /// The commands of the last step.
    out: [f64; MAX_INPUTS],
    /// The communication point and the inputs the last step was made at, while it is not yet
    /// committed by DoStep.
    computed: Option<f64>,
    given: Vec<f64>,
    /// The controller's state before that step (to redo it if the inputs change).
    before: Vec<f64>,
    /// Control period, s.
    pub dt_s: f64,
}

impl ControllerMachine {
    /// The controller of parameter set `p` (its `controller` spec), at rest.
    pub fn new(p: &FmuParams) -> Result<ControllerMachine, String> {
        let spec = p.controller.as_ref().ok_or("the parameter set has no controller")?;
        let (prediction, settings) = spec.design(p)?;
        let core = RealTime::new(&prediction, &settings).map_err(|e| e.to_string())?;
        if core.command_names().len() > MAX_INPUTS {
            return Err(format!("{} commands: at most {MAX_INPUTS}", core.command_names().len()));
        }
        let measured = core.measured_names().len();
        let n = core.state_len();
        let inputs = measured + core.reference_names().len();
        Ok(ControllerMachine {
            dt_s: settings.dt_s,
            core,
            measured,
            out: [0.0; MAX_INPUTS],
            computed: None,
            given: vec![0.0; inputs],
            before: vec![0.0; n],
        })
    }

    /// The operating speed the inputs `u` give at start (`mpc::RealTime::speed_of` the
    /// measurements: for the rig, the three speeds' mean).
    pub fn start_speed(&self, u: &[f64]) -> f64 {
        self.core.speed_of(&u[..self.measured])
    }

    /// Starts from steady motion at `speed` (the inputs holding it against the drag).
    pub fn reset(&mut self, speed: f64) -> Result<(), String> {
        self.core.reset(speed).map_err(|e| e.to_string())?;
        let c = self.core.commands();
        self.out[..c.len()].copy_from_slice(c);
        self.computed = None;
        Ok(())
    }

    /// The commands at communication point `t` for the inputs `u` (measurements, then the
    /// references): the step is made once per point, and made again from the state before it
    /// if the inputs have changed since. `fresh`: the importer has set the inputs since the
    /// last DoStep; if it has not (a Jacobi master reads every output right after the step),
    /// the commands of the last step are returned — a sample of computational delay, as a
    /// controller on a real-time target has — and the step is made at DoStep. Allocation-free.
    pub fn outputs(&mut self, t: f64, u: &[f64], fresh: bool) -> Result<&[f64], String> {
        let nc = self.core.command_names().len();
        if u.len() != self.given.len() {
            return Err(format!("{} inputs for {}", u.len(), self.given.len()));
        }
        if !fresh && self.computed.is_none() {
            return Ok(&self.out[..nc]);
        }
        match self.computed {
            Some(at) if at == t && self.given == u => return Ok(&self.out[..nc]),
            Some(at) if at == t => {
                self.core.restore_state(&self.before);
            }
            _ => self.core.save_state(&mut self.before),
        }
        let (measured, reference) = u.split_at(self.measured);
        let status = self.core.step(measured, reference, &mut self.out[..nc]);
        if matches!(status, Status::Invalid | Status::BadInput) {
            self.core.restore_state(&self.before);
            self.computed = None;
            return Err(format!("the controller could not step at {t} s ({status:?}): a non-finite command"));
        }
        self.given.copy_from_slice(u);
        self.computed = Some(t);
        Ok(&self.out[..nc])
    }

    /// The commands of the last step (after a reset: the steady state's).
    pub fn commands(&self) -> &[f64] {
        &self.out[..self.core.command_names().len()]
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
        self.core.state_len()
    }

    /// The controller's state at the present communication point (before a step made there
    /// and not yet committed) and its last commands.
    pub fn save(&self, out: &mut [f64]) {
        if self.computed.is_some() {
            out.copy_from_slice(&self.before);
        } else {
            self.core.save_state(out);
        }
    }

    /// Restores a record of [`ControllerMachine::save`]; false if it cannot be one.
    pub fn restore(&mut self, s: &[f64]) -> bool {
        if !self.core.restore_state(s) {
            return false;
        }
        let c = self.core.commands();
        self.out[..c.len()].copy_from_slice(c);
        self.computed = None;
        true
    }
}

impl std::fmt::Debug for ControllerMachine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ControllerMachine").field("dt_s", &self.dt_s).field("core", &self.core).finish()
    }
}
