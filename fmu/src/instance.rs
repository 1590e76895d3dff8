//! One FMU instance, independent of the FMI version: its mode (checked at every entry, as the
//! Reference FMUs do), parameters, states, inputs, the model, and what the standard asks of
//! each call. The version glue (`fmi2`, `fmi3`) only converts arguments and statuses.

use nalgebra::DVector;

use crate::controller::ControllerMachine;
use crate::model::{Model, DRIVE_INPUT};
use crate::params::{FmuParams, Plant};
use crate::variables::{parameter_set, parameter_values, rig_parameter, variant_number, Causality, Kind, Slot, Table};
use plant::DelayLine;

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

/// A saved instance state (Get/SetFMUState): with dead times, the inputs' histories too.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// The instantiation token of the FMU the state was taken from: a state of another model,
    /// even one of the same dimensions, is refused.
    token: String,
    mode: Mode,
    time: f64,
    x: Vec<f64>,
    u: Vec<f64>,
    params: Vec<f64>,
    variant: i32,
    history: Vec<Vec<(f64, f64)>>,
    /// The controller FMU's state (`ControllerMachine::save`); empty for the other models.
    internal: Vec<f64>,
}

/// Version 6: the FMU's instantiation token, then parameters, inputs and one history per input
/// of any model and the controller's state, so a state saved by an older FMU or by another
/// model is refused rather than misread.
const SNAPSHOT_MAGIC: &[u8; 8] = b"RIGTWIN6";
/// Bytes of the instantiation token ("{8-4-4-4-12}" hexadecimal digits).
const SNAPSHOT_TOKEN: usize = 38;
/// Magic, token, mode, variant, number of states, inputs, parameters and controller values.
const SNAPSHOT_HEADER: usize = 8 + SNAPSHOT_TOKEN + 1 + 4 + 4 + 4 + 4 + 4;
/// Where the mode byte is; the variant and the four counts follow it.
const SNAPSHOT_MODE_AT: usize = 8 + SNAPSHOT_TOKEN;
/// Most states, inputs or parameters a serialized state may claim (a bound against a
/// corrupt length, far above any model here).
const SNAPSHOT_MAX_LEN: usize = 1 << 16;

impl Snapshot {
    /// Bytes of the state (SerializeFMUState).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(self.byte_len());
        b.extend_from_slice(SNAPSHOT_MAGIC);
        let mut token = [b' '; SNAPSHOT_TOKEN];
        let n = self.token.len().min(SNAPSHOT_TOKEN);
        token[..n].copy_from_slice(&self.token.as_bytes()[..n]);
        b.extend_from_slice(&token);
        b.push(self.mode as u8);
        b.extend(self.variant.to_le_bytes());
        for n in [self.x.len(), self.u.len(), self.params.len(), self.internal.len()] {
            b.extend((n as u32).to_le_bytes());
        }
        for h in &self.history {
            b.extend((h.len() as u32).to_le_bytes());
        }
        let history = self.history.iter().flatten().flat_map(|r| [r.0, r.1]);
        let values = std::iter::once(self.time).chain(self.x.iter().copied()).chain(self.u.iter().copied());
        for v in values.chain(self.params.iter().copied()).chain(self.internal.iter().copied()).chain(history) {
            b.extend(v.to_le_bytes());
        }
        b
    }

    /// Length of [`Snapshot::to_bytes`].
    pub fn byte_len(&self) -> usize {
        let records: usize = self.history.iter().map(Vec::len).sum();
        SNAPSHOT_HEADER
            + 4 * self.u.len()
            + 8 * (1 + self.x.len() + self.u.len() + self.params.len() + self.internal.len() + 2 * records)
    }

    /// Where the continuous states stand in [`Snapshot::to_bytes`] (the time is the 8 bytes
    /// before them): for tools and tests that inspect a serialized state.
    pub fn state_bytes(&self) -> std::ops::Range<usize> {
        let start = SNAPSHOT_HEADER + 4 * self.u.len() + 8;
        start..start + 8 * self.x.len()
    }

    /// Every value a number (a state with a NaN or an infinity is no state of an FMU); an input
    /// history's first record may stand at −∞ (the initialisation's value, held before the start).
    fn is_finite(&self) -> bool {
        let history_ok =
            self.history.iter().flatten().all(|&(t, v)| !t.is_nan() && t != f64::INFINITY && v.is_finite());
        std::iter::once(self.time)
            .chain(self.x.iter().copied())
            .chain(self.u.iter().copied())
            .chain(self.params.iter().copied())
            .chain(self.internal.iter().copied())
            .all(f64::is_finite)
            && history_ok
    }

    /// The state of serialized bytes, if they are one: of this format, consistent in its
    /// lengths, and every value finite (else why not).
    pub fn from_bytes(b: &[u8]) -> Result<Snapshot, &'static str> {
        let s = Self::parse(b).ok_or("the bytes are not a serialized state of a rigtwin FMU of this version")?;
        if !s.is_finite() {
            return Err("the serialized state holds a value that is not a finite number");
        }
        Ok(s)
    }

    fn parse(b: &[u8]) -> Option<Snapshot> {
        if b.len() < SNAPSHOT_HEADER || &b[..8] != SNAPSHOT_MAGIC {
            return None;
        }
        let token = std::str::from_utf8(&b[8..SNAPSHOT_MODE_AT]).ok()?.trim_end().to_string();
        let word =
            |at: usize| -> Option<usize> { Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?) as usize) };
        let counts = SNAPSHOT_MODE_AT + 1 + 4;
        let (nx, nu, np, ni) = (word(counts)?, word(counts + 4)?, word(counts + 8)?, word(counts + 12)?);
        if [nx, nu, np, ni].iter().any(|&n| n > SNAPSHOT_MAX_LEN) {
            return None;
        }
        let lengths: Vec<usize> = (0..nu).map(|j| word(SNAPSHOT_HEADER + 4 * j)).collect::<Option<_>>()?;
        let records = lengths.iter().try_fold(0usize, |a, &n| a.checked_add(n))?;
        let start = SNAPSHOT_HEADER + 4 * nu;
        let floats = (1 + nx + nu + np + ni).checked_add(records.checked_mul(2)?)?;
        if b.len() != start.checked_add(floats.checked_mul(8)?)? {
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
        .get(b[SNAPSHOT_MODE_AT] as usize)
        .copied()?;
        let variant = i32::from_le_bytes(b[SNAPSHOT_MODE_AT + 1..SNAPSHOT_MODE_AT + 5].try_into().ok()?);
        let f: Vec<f64> =
            b[start..].chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
        let p0 = 1 + nx + nu;
        let mut at = p0 + np + ni;
        let mut history = Vec::with_capacity(nu);
        for &n in &lengths {
            let h: Vec<(f64, f64)> = f[at..at + 2 * n].chunks_exact(2).map(|c| (c[0], c[1])).collect();
            DelayLine::from_records(h.clone())?;
            history.push(h);
            at += 2 * n;
        }
        Some(Snapshot {
            token,
            mode,
            time: f[0],
            x: f[1..1 + nx].to_vec(),
            u: f[1 + nx..p0].to_vec(),
            params: f[p0..p0 + np].to_vec(),
            internal: f[p0 + np..p0 + np + ni].to_vec(),
            variant,
            history,
        })
    }
}

/// What an instance runs: a plant (the paper rig or any drive model) or the controller.
#[derive(Debug)]
enum Machine {
    Plant(Box<Model>),
    Controller(Box<ControllerMachine>),
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
    /// The parameter set instantiated: its structure (rig, or which drive model) is fixed.
    spec: FmuParams,
    /// The instantiation token of the parameter set (a saved state carries it).
    token: String,
    params: Vec<f64>,
    variant: i32,
    start: (Vec<f64>, i32),
    x: DVector<f64>,
    u: DVector<f64>,
    /// Per input: the parameter holding its dead time, if it has one.
    delay_param: Vec<Option<usize>>,
    /// Per input: its history, for its dead time.
    delays: Vec<DelayLine>,
    /// The inputs acting now (after their dead times), scratch.
    acting: Vec<f64>,
    /// Scratch of the computed outputs: ẋ, the coupling forces, the angles that are not states.
    computed: (Vec<f64>, Vec<f64>, Vec<f64>),
    time: f64,
    /// Model exchange: the last accepted time (initialisation, event, completed integrator
    /// step); SetTime may not go back before it.
    accepted_time: f64,
    model: Option<Machine>,
    /// The controller FMU: its state carried over a change of its tunable parameters (the
    /// controller is rebuilt, its estimates and plan kept).
    carry: Option<Vec<f64>>,
    /// The controller FMU: inputs were set since the last DoStep.
    fresh_inputs: bool,
}

impl Instance {
    /// A new instance with the start values of `p`.
    pub fn new(name: &str, interface: Interface, logger: Box<dyn Logger>, logging_on: bool, p: &FmuParams) -> Instance {
        let params = parameter_values(p);
        let variant = p.plant.rig().map_or(0, |r| variant_number(r.variant));
        let table = crate::table(p);
        let nu = table.nu();
        let delay_param = match &p.plant {
            // the controller's inputs act at once (the dead time is in its prediction)
            _ if p.controller.is_some() => vec![None; nu],
            Plant::PaperRig(r) => (0..nu)
                .map(|j| {
                    (j == DRIVE_INPUT && r.effects.time_delay_s > 0.0)
                        .then(|| rig_parameter("drive.time_delay"))
                        .flatten()
                })
                .collect(),
            Plant::Drive(m) => (0..nu).map(|j| m.delay_parameter(j)).collect(),
        };
        Instance {
            name: name.to_string(),
            interface,
            mode: Mode::Instantiated,
            logging_on,
            logger,
            start: (params.clone(), variant),
            params,
            variant,
            spec: p.clone(),
            token: crate::token(p),
            x: DVector::zeros(table.nx()),
            table,
            u: DVector::zeros(nu),
            delay_param,
            delays: vec![DelayLine::default(); nu],
            acting: vec![0.0; nu],
            computed: Default::default(),
            time: 0.0,
            accepted_time: 0.0,
            model: None,
            carry: None,
            fresh_inputs: false,
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

    fn lookup(&self, vr: u32) -> Option<&crate::variables::Variable> {
        self.table.lookup(vr)
    }

    /// Dead time of input `j`, s (0: none).
    fn delay_s(&self, j: usize) -> f64 {
        self.delay_param.get(j).copied().flatten().map_or(0.0, |i| self.params[i])
    }

    /// The inputs acting now into `self.acting`: each input, or with a dead time its past
    /// value.
    fn update_acting(&mut self) {
        for j in 0..self.acting.len() {
            let tau = self.delay_s(j);
            self.acting[j] = if tau > 0.0 { self.delays[j].value_at(self.time - tau, self.u[j]) } else { self.u[j] };
        }
    }

    /// Drops each input's history before what its dead time still needs at the present time.
    fn forget_history(&mut self) {
        for j in 0..self.delays.len() {
            let tau = self.delay_s(j);
            if tau > 0.0 {
                self.delays[j].forget_before(self.time, tau);
            }
        }
    }

    fn params(&self) -> Res<FmuParams> {
        parameter_set(&self.spec, &self.params, self.variant).or_else(error)
    }

    /// Builds the model from the parameters if a parameter changed since it was built. Callers
    /// then borrow `self.model` beside `self.x` and `self.u`, so nothing is copied.
    #[inline]
    fn ensure_model(&mut self) -> Res<()> {
        if self.model.is_some() {
            return Ok(());
        }
        self.build_model()
    }

    #[cold]
    fn build_model(&mut self) -> Res<()> {
        let p = self.params()?;
        let built = match &p.controller {
            Some(_) => ControllerMachine::new(&p).map(|mut m| {
                if let Some(s) = self.carry.take() {
                    m.restore(&s);
                }
                Machine::Controller(Box::new(m))
            }),
            None => Model::new(&p.plant).map(|m| Machine::Plant(Box::new(m))),
        };
        self.model = Some(built.or_else(|e| error(format!("the parameters do not describe a model: {e}")))?);
        Ok(())
    }

    /// ẋ at the present state and inputs into `out` (the model built).
    fn evaluate_derivatives(&mut self, out: &mut [f64]) {
        self.update_acting();
        match self.model.as_mut().expect("built by the caller") {
            Machine::Plant(m) => m.derivatives(self.x.as_slice(), &self.acting, out),
            Machine::Controller(_) => {}
        }
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
        // the controller starts from steady spinning at the measured speeds' mean
        if let Some(Machine::Controller(m)) = self.model.as_mut() {
            let speed = m.start_speed(self.u.as_slice());
            m.reset(speed).or_else(|e| error(format!("the controller cannot start at speed {speed}: {e}")))?;
        }
        // the inputs of the initialisation are what the dead times deliver at first
        for (line, &u) in self.delays.iter_mut().zip(self.u.iter()) {
            *line = DelayLine::default();
            line.record(f64::NEG_INFINITY, u);
        }
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
        (self.params, self.variant) = self.start.clone();
        self.x.fill(0.0);
        self.u.fill(0.0);
        self.delays.iter_mut().for_each(|d| *d = DelayLine::default());
        self.time = 0.0;
        self.accepted_time = 0.0;
        self.model = None;
        self.carry = None;
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
        self.forget_history();
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
        self.evaluate_derivatives(out);
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
        let stepped = match self.model.as_mut().expect("built above") {
            Machine::Plant(m) => m.step(&mut self.x, self.u.as_slice(), self.time, h, &self.delays),
            Machine::Controller(m) => m.advance(self.time, h, self.u.as_slice()),
        };
        if let Err(e) = stepped {
            return Err(self.fail(format!("DoStep from {t} s over {h} s: {e}")));
        }
        self.time = t + h;
        self.forget_history();
        self.fresh_inputs = false;
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
        let commands = if vrs.iter().any(|&v| matches!(self.lookup(v).map(|x| x.slot), Some(Slot::Command(_)))) {
            self.ensure_model()?;
            let (t, u) = (self.time, self.u.as_slice());
            let stepping = self.mode == Mode::StepMode;
            let mut commands = [0.0; plant::drive::MAX_INPUTS];
            let got = match self.model.as_mut().expect("built above") {
                // before the first step: the steady state's commands at the measured speeds
                Machine::Controller(m) if !stepping => {
                    let speed = m.start_speed(u);
                    m.reset(speed).or_else(|e| error(format!("the controller cannot start at speed {speed}: {e}")))?;
                    Ok(m.commands())
                }
                Machine::Controller(m) => m.outputs(t, u, self.fresh_inputs),
                _ => return error("commands belong to the controller FMU"),
            };
            match got {
                Ok(c) => commands[..c.len()].copy_from_slice(c),
                Err(e) => return Err(self.fail(format!("the controller's step at {t} s: {e}"))),
            }
            commands
        } else {
            [0.0; plant::drive::MAX_INPUTS]
        };
        let needs_model = vrs.iter().any(|&v| {
            matches!(self.lookup(v).map(|x| x.slot), Some(Slot::Derivative(_) | Slot::Torque(_) | Slot::Angle(_)))
        });
        // the computed outputs into the instance's scratch (allocation-free once sized)
        let mut computed = std::mem::take(&mut self.computed);
        if needs_model {
            self.ensure_model()?;
            computed.0.resize(self.x.len(), 0.0);
            self.evaluate_derivatives(&mut computed.0);
            if let Some(Machine::Plant(m)) = self.model.as_mut() {
                m.forces_into(self.x.as_slice(), &mut computed.1);
                m.angles_into(self.x.as_slice(), &mut computed.2);
            }
        }
        let mut result = Ok(());
        for (&vr, o) in vrs.iter().zip(out.iter_mut()) {
            let var = self.lookup(vr).filter(|v| v.kind == Kind::Float64);
            let value = match var.map(|v| v.slot) {
                Some(Slot::Time) => Some(self.time),
                Some(Slot::Param(i)) => Some(self.params[i]),
                Some(Slot::State(i)) => Some(self.x[i]),
                Some(Slot::Input(i)) => Some(self.u[i]),
                Some(Slot::Derivative(i)) => computed.0.get(i).copied(),
                Some(Slot::Torque(i)) => computed.1.get(i).copied(),
                Some(Slot::Angle(i)) => computed.2.get(i).copied(),
                Some(Slot::Command(i)) => Some(commands[i]),
                _ => None,
            };
            match value {
                Some(v) => *o = v,
                None => {
                    result = error(format!("value reference {vr} is not a Float64 variable of this FMU"));
                    break;
                }
            }
        }
        self.computed = computed;
        result
    }

    /// Sets Float64 values; nothing is changed if any value is refused. Allocation-free unless
    /// a value is refused (the message) or a parameter changes (the model is rebuilt).
    pub fn set_f64(&mut self, vrs: &[u32], values: &[f64]) -> Res<()> {
        if vrs.len() != values.len() {
            return error("the number of value references and values differ");
        }
        const BEFORE_INIT: &[Mode] = &[Mode::Instantiated, Mode::InitializationMode];
        const TUNABLE: &[Mode] = &[Mode::Instantiated, Mode::InitializationMode, Mode::StepMode];
        const INPUT: &[Mode] =
            &[Mode::Instantiated, Mode::InitializationMode, Mode::EventMode, Mode::ContinuousTimeMode, Mode::StepMode];
        // every value is checked before any is set
        for (&vr, &v) in vrs.iter().zip(values) {
            let Some(var) = self.lookup(vr).filter(|x| x.kind == Kind::Float64) else {
                return error(format!("value reference {vr} is not a Float64 variable of this FMU"));
            };
            if !v.is_finite() {
                return error(format!("`{}` = {v}: expected a finite number", var.name));
            }
            let (what, allowed) = match (var.causality, var.slot) {
                // the controller's settings are tunable
                (Causality::Parameter, Slot::Param(_)) if self.spec.controller.is_some() => {
                    ("the tunable parameter", TUNABLE)
                }
                (Causality::Parameter, Slot::Param(_)) => ("the fixed parameter", BEFORE_INIT),
                (Causality::Input, _) => ("the input", INPUT),
                (_, Slot::State(_)) => ("the start value of", BEFORE_INIT),
                _ => return error(format!("`{}` (value reference {vr}) cannot be set: it is calculated", var.name)),
            };
            if !allowed.contains(&self.mode) {
                return error(format!(
                    "setting {what} `{}` is not allowed in {:?} (allowed: {allowed:?})",
                    var.name, self.mode
                ));
            }
            if let Slot::Param(_) = var.slot {
                if let Err(want) = var.constraint.check(v) {
                    return error(format!("`{}` = {v} {}: expected {want}", var.name, var.unit));
                }
            }
        }
        for (&vr, &v) in vrs.iter().zip(values) {
            let slot = self.lookup(vr).map(|x| x.slot);
            match slot {
                Some(Slot::Param(i)) => {
                    if self.params[i] == v {
                        continue;
                    }
                    self.params[i] = v;
                    if let Some(Machine::Controller(m)) = self.model.take() {
                        let mut state = vec![0.0; m.state_len()];
                        m.save(&mut state);
                        self.carry = Some(state);
                    }
                }
                Some(Slot::Input(i)) => {
                    self.u[i] = v;
                    self.fresh_inputs = true;
                    if self.delay_s(i) > 0.0 {
                        self.delays[i].record(self.time, v);
                    }
                }
                Some(Slot::State(i)) => self.x[i] = v,
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
            token: self.token.clone(),
            mode: self.mode,
            time: self.time,
            x: self.x.as_slice().to_vec(),
            u: self.u.as_slice().to_vec(),
            params: self.params.clone(),
            variant: self.variant,
            history: self.delays.iter().map(|d| d.records().to_vec()).collect(),
            internal: match self.model.as_ref() {
                Some(Machine::Controller(m)) => {
                    let mut v = vec![0.0; m.state_len()];
                    m.save(&mut v);
                    v
                }
                _ => self.carry.clone().unwrap_or_default(),
            },
        }
    }

    /// Whether `s` is a state of this FMU: taken from the same model (its instantiation token),
    /// of its dimensions, every value finite.
    pub fn check_state(&self, s: &Snapshot) -> Res<()> {
        if s.token != self.token {
            return error(format!(
                "the state was taken from the FMU {}, this is {}: a state only fits the model it came from",
                s.token, self.token
            ));
        }
        if s.x.len() != self.nx() || s.u.len() != self.u.len() || s.params.len() != self.params.len() {
            return error(format!(
                "the state has {} continuous states, {} inputs and {} parameters; this FMU has {}, {} and {}",
                s.x.len(),
                s.u.len(),
                s.params.len(),
                self.nx(),
                self.u.len(),
                self.params.len()
            ));
        }
        if !s.is_finite() {
            return error("the state holds a value that is not a finite number");
        }
        Ok(())
    }

    /// Restores a state (SetFMUState); refuses a state of another FMU.
    pub fn restore(&mut self, s: &Snapshot) -> Res<()> {
        self.check_state(s)?;
        let history = s
            .history
            .iter()
            .map(|h| DelayLine::from_records(h.clone()))
            .collect::<Option<Vec<_>>>()
            .filter(|h| h.len() == self.delays.len())
            .ok_or_else(|| Failure {
                status: Status::Error,
                message: "the state's input history is not ordered".into(),
            })?;
        if s.params != self.params || s.variant != self.variant {
            self.model = None;
        }
        // the controller's state goes into the controller, or waits for it to be built
        match (self.model.as_mut(), s.internal.is_empty()) {
            (_, true) => self.carry = None,
            (Some(Machine::Controller(m)), false) => {
                if !m.restore(&s.internal) {
                    return error("the state's controller record does not fit this controller");
                }
                self.carry = None;
            }
            (_, false) => self.carry = Some(s.internal.clone()),
        }
        self.delays = history;
        self.fresh_inputs = false;
        self.mode = s.mode;
        self.time = s.time;
        self.accepted_time = s.time;
        self.x.copy_from_slice(&s.x);
        self.u.copy_from_slice(&s.u);
        self.params.clone_from(&s.params);
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
        self.update_acting();
        // the Jacobians at the present state and inputs
        let (a, b, torque) = match self.model.as_mut().expect("built above") {
            Machine::Plant(m) => m.jacobians(self.x.as_slice(), &self.acting),
            Machine::Controller(_) => return error("the controller FMU provides no directional derivatives"),
        };
        let angle_gradient = |i: usize, col: usize| match self.model.as_ref() {
            Some(Machine::Plant(m)) => m.angle_gradient(i, col),
            _ => 0.0,
        };
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
                        } else if self.delay_s(col - nx) > 0.0 {
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
                            angle_gradient(i, col)
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
