//! One FMU instance, independent of the FMI version: its mode (checked at every entry, as the
//! Reference FMUs do), parameters, states, inputs, the model, and what the standard asks of
//! each call. The version glue (`fmi2`, `fmi3`) only converts arguments and statuses.

use nalgebra::DVector;

use crate::model::{Model, DRIVE_INPUT, NU};
use crate::params::FmuParams;
use crate::variables::{
    parameter_set, parameter_values, variant_number, Causality, Kind, Slot, Table, NPARAMS, PARAMETERS,
};
use plant::effects::DelayLine;

/// Whether the instance simulates itself (co-simulation) or lends its derivatives to the
/// importer's solver (model exchange).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interface {
    /// Model exchange.
    ModelExchange,
    /// Co-simulation.
    CoSimulation,
}

/// The instance's state in the FMI state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// After instantiation.
    Instantiated,
    /// Between Enter- and ExitInitializationMode.
    InitializationMode,
    /// Model exchange: event mode.
    EventMode,
    /// Model exchange: continuous-time mode.
    ContinuousTimeMode,
    /// Co-simulation: step mode.
    StepMode,
    /// After Terminate.
    Terminated,
    /// After a step or an evaluation whose state came out non-finite (or could not be taken):
    /// every call but Reset, SetFMUState and FreeInstance is refused.
    Failed,
}

/// Status escalation OK < Warning < Discard < Error < Fatal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// Success.
    Ok,
    /// Success with something to say.
    Warning,
    /// The step was not done.
    Discard,
    /// The call failed; the instance can be reset, restored or freed.
    Error,
    /// The instance is unusable.
    Fatal,
}

/// A failed call: its status and the message logged for it.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// Status returned.
    pub status: Status,
    /// Message logged.
    pub message: String,
}

/// Result of an instance call.
pub type Res<T> = Result<T, Failure>;

fn error<T>(message: impl Into<String>) -> Res<T> {
    Err(Failure { status: Status::Error, message: message.into() })
}

/// Where log messages go (the importer's callback, wrapped by the version glue).
pub trait Logger {
    /// Passes one message on.
    fn log(&self, status: Status, category: &str, message: &str);
}

/// A saved instance state (Get/SetFMUState): with a dead time, the drive torque's history too.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    mode: Mode,
    time: f64,
    x: Vec<f64>,
    u: Vec<f64>,
    params: [f64; NPARAMS],
    variant: i32,
    history: Vec<(f64, f64)>,
}

/// Version 3: the states are the bounded ones (twists in place of the drive's and the motor's
/// angles), so a state saved by an older FMU is refused rather than misread.
const SNAPSHOT_MAGIC: &[u8; 8] = b"RIGTWIN3";
/// Magic, mode, variant, number of states, number of history records.
const SNAPSHOT_HEADER: usize = 8 + 1 + 4 + 4 + 4;

impl Snapshot {
    /// Bytes of the state (SerializeFMUState).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = SNAPSHOT_MAGIC.to_vec();
        b.push(self.mode as u8);
        b.extend(self.variant.to_le_bytes());
        b.extend((self.x.len() as u32).to_le_bytes());
        b.extend((self.history.len() as u32).to_le_bytes());
        let history = self.history.iter().flat_map(|r| [r.0, r.1]);
        for v in std::iter::once(self.time).chain(self.x.iter().copied()).chain(self.u.iter().copied()) {
            b.extend(v.to_le_bytes());
        }
        for v in self.params.iter().copied().chain(history) {
            b.extend(v.to_le_bytes());
        }
        b
    }

    /// Length of [`Snapshot::to_bytes`].
    pub fn byte_len(&self) -> usize {
        SNAPSHOT_HEADER + 8 * (1 + self.x.len() + NU + NPARAMS + 2 * self.history.len())
    }

    /// The state of serialized bytes, if they are one.
    pub fn from_bytes(b: &[u8]) -> Option<Snapshot> {
        if b.len() < SNAPSHOT_HEADER || &b[..8] != SNAPSHOT_MAGIC {
            return None;
        }
        let nx = u32::from_le_bytes(b[13..17].try_into().ok()?) as usize;
        let nh = u32::from_le_bytes(b[17..21].try_into().ok()?) as usize;
        if nx > 64 || b.len() != SNAPSHOT_HEADER + 8 * (1 + nx + NU + NPARAMS + 2 * nh) {
            return None;
        }
        let mode = [
            Mode::Instantiated,
            Mode::InitializationMode,
            Mode::EventMode,
            Mode::ContinuousTimeMode,
            Mode::StepMode,
            Mode::Terminated,
            Mode::Failed,
        ]
        .get(b[8] as usize)
        .copied()?;
        let variant = i32::from_le_bytes(b[9..13].try_into().ok()?);
        let f: Vec<f64> =
            b[SNAPSHOT_HEADER..].chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
        let mut params = [0.0; NPARAMS];
        let p0 = 1 + nx + NU;
        params.copy_from_slice(&f[p0..p0 + NPARAMS]);
        let history = f[p0 + NPARAMS..].chunks_exact(2).map(|c| (c[0], c[1])).collect::<Vec<_>>();
        DelayLine::from_records(history.clone())?;
        Some(Snapshot {
            mode,
            time: f[0],
            x: f[1..1 + nx].to_vec(),
            u: f[1 + nx..1 + nx + NU].to_vec(),
            params,
            variant,
            history,
        })
    }
}

/// One instance.
pub struct Instance {
    /// Instance name given by the importer.
    pub name: String,
    /// ME or CS.
    pub interface: Interface,
    /// Current mode.
    pub mode: Mode,
    /// Whether informational messages are logged (errors and warnings always are).
    pub logging_on: bool,
    logger: Box<dyn Logger>,
    table: Table,
    params: [f64; NPARAMS],
    variant: i32,
    start: ([f64; NPARAMS], i32),
    x: DVector<f64>,
    u: DVector<f64>,
    /// History of the drive torque for its dead time.
    delay: DelayLine,
    time: f64,
    /// Model exchange: the last accepted time (initialisation, event, completed integrator
    /// step); SetTime may not go back before it.
    accepted_time: f64,
    model: Option<Model>,
}

impl Instance {
    /// A new instance with the start values of `p`.
    pub fn new(name: &str, interface: Interface, logger: Box<dyn Logger>, logging_on: bool, p: &FmuParams) -> Instance {
        let params = parameter_values(p);
        let variant = variant_number(p.variant);
        let table = Table::new(p);
        Instance {
            name: name.to_string(),
            interface,
            mode: Mode::Instantiated,
            logging_on,
            logger,
            params,
            variant,
            start: (params, variant),
            x: DVector::zeros(table.nx()),
            table,
            u: DVector::zeros(NU),
            delay: DelayLine::default(),
            time: 0.0,
            accepted_time: 0.0,
            model: None,
        }
    }

    /// The instance cannot go on: it refuses every call until it is reset or a saved state is
    /// set. Returns the failure to report.
    fn fail(&mut self, message: String) -> Failure {
        self.mode = Mode::Failed;
        Failure {
            status: Status::Error,
            message: format!("{message}; the instance stops (reset it, set a saved FMU state, or free it)"),
        }
    }

    /// Logs a failure (always) and returns its status.
    pub fn report(&self, f: &Failure) -> Status {
        let category = if f.status >= Status::Error { "logStatusError" } else { "logStatusWarning" };
        self.logger.log(f.status, category, &f.message);
        f.status
    }

    /// Logs an informational message when logging is on.
    pub fn info(&self, message: &str) {
        if self.logging_on {
            self.logger.log(Status::Ok, "logEvents", message);
        }
    }

    /// Fails unless the instance is in one of `allowed`.
    pub fn expect(&self, function: &str, allowed: &[Mode]) -> Res<()> {
        if allowed.contains(&self.mode) {
            Ok(())
        } else {
            error(format!("{function} is not allowed in {:?} (allowed: {allowed:?})", self.mode))
        }
    }

    /// The variable table of this instance.
    pub fn table(&self) -> &Table {
        &self.table
    }

    /// Number of continuous states.
    pub fn nx(&self) -> usize {
        self.x.len()
    }

    fn lookup(&self, vr: u32) -> Option<crate::variables::Variable> {
        self.table.lookup(vr)
    }

    /// Dead time of the drive torque, s.
    fn delay_s(&self) -> f64 {
        self.params[crate::variables::FIRST_EFFECT]
    }

    /// The drive torque acting now: the input, or with a dead time its past value.
    fn drive_now(&self) -> f64 {
        let tau = self.delay_s();
        if tau > 0.0 {
            self.delay.value_at(self.time - tau, self.u[DRIVE_INPUT])
        } else {
            self.u[DRIVE_INPUT]
        }
    }

    fn params(&self) -> Res<FmuParams> {
        parameter_set(&self.params, self.variant).or_else(error)
    }

    /// Builds the model from the parameters if a parameter changed since it was built. Callers
    /// then borrow `self.model` beside `self.x` and `self.u`, so nothing is copied.
    fn ensure_model(&mut self) -> Res<()> {
        if self.model.is_none() {
            let p = self.params()?;
            self.model =
                Some(Model::new(&p).or_else(|e| error(format!("the parameters do not describe a model: {e}")))?);
        }
        Ok(())
    }

    /// Enter initialization mode at `start_time` (with the experiment's stop time if defined).
    pub fn enter_initialization_mode(&mut self, start_time: f64, stop_time: Option<f64>) -> Res<()> {
        self.expect("EnterInitializationMode", &[Mode::Instantiated])?;
        if !start_time.is_finite() {
            return error(format!("start time {start_time} is not finite"));
        }
        if let Some(stop) = stop_time {
            if stop.is_nan() || stop < start_time {
                return error(format!("stop time {stop} s is before the start time {start_time} s"));
            }
        }
        self.time = start_time;
        self.mode = Mode::InitializationMode;
        Ok(())
    }

    /// Leave initialization mode: the parameters must now describe a model.
    pub fn exit_initialization_mode(&mut self) -> Res<()> {
        self.expect("ExitInitializationMode", &[Mode::InitializationMode])?;
        self.ensure_model()?;
        // the drive torque of the initialisation is what the dead time delivers at first
        self.delay = DelayLine::default();
        self.delay.record(f64::NEG_INFINITY, self.u[DRIVE_INPUT]);
        self.accepted_time = self.time;
        self.mode = match self.interface {
            Interface::CoSimulation => Mode::StepMode,
            Interface::ModelExchange => Mode::EventMode,
        };
        self.info("initialized");
        Ok(())
    }

    /// Terminate.
    pub fn terminate(&mut self) -> Res<()> {
        self.expect("Terminate", &[Mode::EventMode, Mode::ContinuousTimeMode, Mode::StepMode])?;
        self.mode = Mode::Terminated;
        Ok(())
    }

    /// Reset to the state right after instantiation.
    pub fn reset(&mut self) {
        (self.params, self.variant) = self.start;
        self.x.fill(0.0);
        self.u.fill(0.0);
        self.delay = DelayLine::default();
        self.time = 0.0;
        self.accepted_time = 0.0;
        self.model = None;
        self.mode = Mode::Instantiated;
    }

    /// Model exchange: enter event mode.
    pub fn enter_event_mode(&mut self) -> Res<()> {
        self.expect("EnterEventMode", &[Mode::EventMode, Mode::ContinuousTimeMode])?;
        self.accepted_time = self.time;
        self.mode = Mode::EventMode;
        Ok(())
    }

    /// Model exchange: enter continuous-time mode.
    pub fn enter_continuous_time_mode(&mut self) -> Res<()> {
        self.expect("EnterContinuousTimeMode", &[Mode::EventMode])?;
        self.mode = Mode::ContinuousTimeMode;
        Ok(())
    }

    /// Model exchange: set the time.
    pub fn set_time(&mut self, t: f64) -> Res<()> {
        self.expect("SetTime", &[Mode::EventMode, Mode::ContinuousTimeMode])?;
        if !t.is_finite() {
            return error(format!("time {t} is not finite"));
        }
        // an integrator may go back to retry a step, but never before the last accepted point
        if t < self.accepted_time - 1e-12 * self.accepted_time.abs().max(1.0) {
            return error(format!("time {t} s is before the last accepted time {} s", self.accepted_time));
        }
        self.time = t;
        Ok(())
    }

    /// Model exchange: an accepted integrator step; the dead time's history before it is dropped.
    pub fn completed_integrator_step(&mut self) -> Res<()> {
        self.expect("CompletedIntegratorStep", &[Mode::ContinuousTimeMode])?;
        self.accepted_time = self.time;
        self.delay.forget_before(self.time, self.delay_s());
        Ok(())
    }

    /// Model exchange: the continuous states.
    pub fn continuous_states(&self, out: &mut [f64]) -> Res<()> {
        if out.len() != self.nx() {
            return error(format!("{} continuous states asked for; the model has {}", out.len(), self.nx()));
        }
        out.copy_from_slice(self.x.as_slice());
        Ok(())
    }

    /// Model exchange: the nominals of the continuous states.
    pub fn nominals(&self, out: &mut [f64]) -> Res<()> {
        if out.len() != self.nx() {
            return error(format!("{} nominals asked for; the model has {} states", out.len(), self.nx()));
        }
        for (o, v) in out.iter_mut().zip(self.table.nominals()) {
            *o = v;
        }
        Ok(())
    }

    /// Model exchange: set the continuous states.
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Res<()> {
        self.expect("SetContinuousStates", &[Mode::ContinuousTimeMode])?;
        if x.len() != self.nx() {
            return error(format!("{} continuous states given; the model has {}", x.len(), self.nx()));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return error(format!("continuous state {i} is not finite ({})", x[i]));
        }
        self.x.copy_from_slice(x);
        Ok(())
    }

    /// Model exchange: ẋ.
    pub fn derivatives(&mut self, out: &mut [f64]) -> Res<()> {
        self.expect(
            "GetContinuousStateDerivatives",
            &[Mode::InitializationMode, Mode::EventMode, Mode::ContinuousTimeMode, Mode::Terminated],
        )?;
        if out.len() != self.nx() {
            return error(format!("{} derivatives asked for; the model has {}", out.len(), self.nx()));
        }
        self.ensure_model()?;
        let drive = self.drive_now();
        let m = self.model.as_mut().expect("built above");
        m.derivatives(self.x.as_slice(), self.u.as_slice(), drive, out);
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(self.fail(format!("the derivative of state {i} is {} at {} s", out[i], self.time)));
        }
        Ok(())
    }

    /// Co-simulation: one communication step of length `h` from `t`.
    pub fn do_step(&mut self, t: f64, h: f64) -> Res<()> {
        self.expect("DoStep", &[Mode::StepMode])?;
        if !(h > 0.0 && h.is_finite()) {
            return error(format!("communication step size {h} s must be positive and finite"));
        }
        if !t.is_finite() {
            return error(format!("currentCommunicationPoint {t} s is not finite"));
        }
        if (t - self.time).abs() > 1e-9 * self.time.abs().max(h) {
            return error(format!("currentCommunicationPoint {t} s differs from the FMU's time {} s", self.time));
        }
        self.ensure_model()?;
        let model = self.model.as_mut().expect("built above");
        if let Err(e) = model.step(&mut self.x, &self.u, self.time, h, &self.delay) {
            return Err(self.fail(format!("DoStep from {t} s over {h} s: {e}")));
        }
        self.time = t + h;
        self.delay.forget_before(self.time, self.delay_s());
        Ok(())
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Float64 values by value reference.
    pub fn get_f64(&mut self, vrs: &[u32], out: &mut [f64]) -> Res<()> {
        if vrs.len() != out.len() {
            return error("the number of value references and values differ");
        }
        let needs_model = vrs.iter().any(|&v| {
            matches!(self.lookup(v).map(|x| x.slot), Some(Slot::Derivative(_) | Slot::Torque(_) | Slot::Angle(_)))
        });
        let computed = if needs_model {
            self.ensure_model()?;
            let drive = self.drive_now();
            let m = self.model.as_mut().expect("built above");
            let mut dx = vec![0.0; self.x.len()];
            m.derivatives(self.x.as_slice(), self.u.as_slice(), drive, &mut dx);
            Some((dx, m.torques(self.x.as_slice()), m.angles(self.x.as_slice())))
        } else {
            None
        };
        for (&vr, o) in vrs.iter().zip(out.iter_mut()) {
            let var = self.lookup(vr).filter(|v| v.kind == Kind::Float64);
            *o = match var.map(|v| v.slot) {
                Some(Slot::Time) => self.time,
                Some(Slot::Param(i)) => self.params[i],
                Some(Slot::State(i)) => self.x[i],
                Some(Slot::Input(i)) => self.u[i],
                Some(Slot::Derivative(i)) => computed.as_ref().expect("computed above").0[i],
                Some(Slot::Torque(i)) => computed.as_ref().expect("computed above").1[i],
                Some(Slot::Angle(i)) => computed.as_ref().expect("computed above").2[i],
                _ => return error(format!("value reference {vr} is not a Float64 variable of this FMU")),
            };
        }
        Ok(())
    }

    /// Sets Float64 values; nothing is changed if any value is refused.
    pub fn set_f64(&mut self, vrs: &[u32], values: &[f64]) -> Res<()> {
        if vrs.len() != values.len() {
            return error("the number of value references and values differ");
        }
        let before_init = [Mode::Instantiated, Mode::InitializationMode];
        let mut changes = Vec::with_capacity(vrs.len());
        for (&vr, &v) in vrs.iter().zip(values) {
            let Some(var) = self.lookup(vr).filter(|x| x.kind == Kind::Float64) else {
                return error(format!("value reference {vr} is not a Float64 variable of this FMU"));
            };
            if !v.is_finite() {
                return error(format!("`{}` = {v}: expected a finite number", var.name));
            }
            match (var.causality, var.slot) {
                (Causality::Parameter, Slot::Param(i)) => {
                    self.expect(&format!("setting the fixed parameter `{}`", var.name), &before_init)?;
                    if let Err(want) = PARAMETERS[i].3.check(v) {
                        return error(format!("`{}` = {v} {}: expected {want}", var.name, PARAMETERS[i].1));
                    }
                }
                (Causality::Input, _) => self.expect(
                    &format!("setting the input `{}`", var.name),
                    &[
                        Mode::Instantiated,
                        Mode::InitializationMode,
                        Mode::EventMode,
                        Mode::ContinuousTimeMode,
                        Mode::StepMode,
                    ],
                )?,
                (_, Slot::State(_)) => {
                    self.expect(&format!("setting the start value of `{}`", var.name), &before_init)?
                }
                _ => return error(format!("`{}` (value reference {vr}) cannot be set: it is calculated", var.name)),
            }
            changes.push((var.slot, v));
        }
        for (slot, v) in changes {
            match slot {
                Slot::Param(i) => {
                    self.params[i] = v;
                    self.model = None;
                }
                Slot::Input(i) => {
                    self.u[i] = v;
                    if i == DRIVE_INPUT && self.delay_s() > 0.0 {
                        self.delay.record(self.time, v);
                    }
                }
                Slot::State(i) => self.x[i] = v,
                _ => unreachable!("refused above"),
            }
        }
        Ok(())
    }

    /// Int32 values (the variant).
    pub fn get_i32(&self, vrs: &[u32], out: &mut [i32]) -> Res<()> {
        if vrs.len() != out.len() {
            return error("the number of value references and values differ");
        }
        for (&vr, o) in vrs.iter().zip(out.iter_mut()) {
            match self.lookup(vr).map(|v| v.slot) {
                Some(Slot::Variant) => *o = self.variant,
                _ => return error(format!("value reference {vr} is not an integer variable of this FMU")),
            }
        }
        Ok(())
    }

    /// Sets Int32 values (the variant).
    pub fn set_i32(&mut self, vrs: &[u32], values: &[i32]) -> Res<()> {
        if vrs.len() != values.len() {
            return error("the number of value references and values differ");
        }
        for (&vr, &v) in vrs.iter().zip(values) {
            match self.lookup(vr).map(|x| x.slot) {
                Some(Slot::Variant) => {
                    self.expect(
                        "setting the fixed parameter `variant`",
                        &[Mode::Instantiated, Mode::InitializationMode],
                    )?;
                    if !(1..=4).contains(&v) {
                        return error(format!("`variant` = {v}: expected 1, 2, 3 or 4"));
                    }
                }
                _ => return error(format!("value reference {vr} is not an integer variable of this FMU")),
            }
        }
        if let Some(&v) = values.last() {
            self.variant = v;
            self.model = None;
        }
        Ok(())
    }

    /// The instance's state (GetFMUState).
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            mode: self.mode,
            time: self.time,
            x: self.x.as_slice().to_vec(),
            u: self.u.as_slice().to_vec(),
            params: self.params,
            variant: self.variant,
            history: self.delay.records().to_vec(),
        }
    }

    /// Restores a state (SetFMUState); refuses a state of another FMU.
    pub fn restore(&mut self, s: &Snapshot) -> Res<()> {
        if s.x.len() != self.nx() {
            return error(format!("the state has {} continuous states; this FMU has {}", s.x.len(), self.nx()));
        }
        let history = DelayLine::from_records(s.history.clone())
            .ok_or_else(|| Failure { status: Status::Error, message: "the state's history is not ordered".into() })?;
        if s.params != self.params || s.variant != self.variant {
            self.model = None;
        }
        self.delay = history;
        self.mode = s.mode;
        self.time = s.time;
        self.accepted_time = s.time;
        self.x.copy_from_slice(&s.x);
        self.u.copy_from_slice(&s.u);
        self.params = s.params;
        self.variant = s.variant;
        Ok(())
    }

    /// Directional derivative Σ_j ∂unknown_i/∂known_j · seed_j at the present state (the linear
    /// model, or with backlash that of the contact state): the unknowns are derivatives or
    /// outputs, the knowns states or inputs. With a dead time the derivatives do not depend on
    /// the present drive torque.
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> Res<()> {
        if knowns.len() != seed.len() || unknowns.len() != out.len() {
            return error("the numbers of value references, seeds and results differ");
        }
        self.ensure_model()?;
        let nx = self.nx();
        let delayed = self.delay_s() > 0.0;
        let m = self.model.as_ref().expect("built above");
        let (a, b, torque) = m.jacobians(self.x.as_slice());
        // column of a known in [x u]
        let cols = knowns
            .iter()
            .map(|&vr| match self.lookup(vr).map(|v| v.slot) {
                Some(Slot::State(i)) => Ok(i),
                Some(Slot::Input(i)) => Ok(nx + i),
                _ => {
                    error(format!("value reference {vr} is not a state or an input: no derivative with respect to it"))
                }
            })
            .collect::<Res<Vec<usize>>>()?;
        for (&vr, o) in unknowns.iter().zip(out.iter_mut()) {
            let row = |col: usize| -> Res<f64> {
                Ok(match self.lookup(vr).map(|v| v.slot) {
                    Some(Slot::Derivative(i)) => {
                        if col < nx {
                            a[(i, col)]
                        } else if delayed && col - nx == DRIVE_INPUT {
                            0.0
                        } else {
                            b[(i, col - nx)]
                        }
                    }
                    // a state that is an output and the derivative of another state
                    Some(Slot::State(i)) => {
                        if col == i {
                            1.0
                        } else {
                            0.0
                        }
                    }
                    Some(Slot::Torque(i)) => {
                        if col < nx {
                            torque[(i, col)]
                        } else {
                            0.0
                        }
                    }
                    Some(Slot::Angle(i)) => {
                        if col < nx {
                            m.angle_gradient(i, col)
                        } else {
                            0.0
                        }
                    }
                    _ => return error(format!("value reference {vr} is not an output or a derivative")),
                })
            };
            let mut acc = 0.0;
            for (&c, &s) in cols.iter().zip(seed) {
                acc += row(c)? * s;
            }
            *o = acc;
        }
        Ok(())
    }
}
