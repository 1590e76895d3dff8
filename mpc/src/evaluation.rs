//! How a controller is judged (`rigtwin mpc`): its closed loop on a plant as the model's FMU
//! steps it — on the paper rig beside the PI baseline through a [`Scenario`], on a drive model
//! through a step of its tracked speeds' references — the controller's timing and allocations,
//! its first input against the exact optimum of the same QP, and the figures of the report
//! ([`MpcReport`]), the same for every model.

use nalgebra::DVector;
use plant::DriveModel;
use serde::Serialize;

use crate::closed_loop::{
    compare, median_p99, run_mpc, share_at_bounds, step_figures, Comparison, HarnessSettings, Plant, Probes,
    RigSignals, Scenario, ScenarioKind, StepFigures, Trace,
};
use crate::error::{setting, MpcError, Result};
use crate::prediction::{Design, Prediction};
use crate::qp::QpSnapshot;
use crate::settings::{MpcSettings, OutputSettings};
use crate::{Controller, DrivePlant, StepInfo};

/// Median, 99th percentile and maximum, µs.
#[derive(Debug, Clone, Serialize)]
pub struct Timing {
    /// Median.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub max: f64,
}

impl Timing {
    /// The timing of `times_us`.
    fn of(times_us: &[f64]) -> Timing {
        let (median, p99) = median_p99(times_us);
        Timing { median, p99, max: times_us.iter().copied().fold(0.0, f64::max) }
    }
}

/// A figure of the MPC's run beside the PI baseline's (`None`: the model has no baseline; only
/// the paper rig's speed loops have one).
#[derive(Debug, Clone, Serialize)]
pub struct Compared<T> {
    /// With the MPC.
    pub mpc: T,
    /// With the PI speed loops.
    pub baseline: Option<T>,
}

impl<T> Compared<T> {
    /// The MPC's figure alone.
    fn alone(mpc: T) -> Self {
        Compared { mpc, baseline: None }
    }
}

/// The controller's signals, read from its settings by one rule for every model.
#[derive(Debug, Clone, Serialize)]
pub struct Signals {
    /// The controller's inputs.
    pub inputs: Vec<String>,
    /// Outputs and inputs with a reference.
    pub tracked: Vec<String>,
    /// Forces weighted without a reference (whose oscillation is penalised).
    pub penalised: Vec<String>,
    /// Measured outputs.
    pub measured: Vec<String>,
    /// Each input's hard bound |u| ≤ (see `units.force`).
    pub input_max: Vec<f64>,
}

impl Signals {
    /// The signals of `settings`, `forces` being the model's force outputs.
    pub fn of(settings: &MpcSettings, forces: &[String]) -> Signals {
        let outputs = |keep: &dyn Fn(&OutputSettings) -> bool| {
            settings.outputs.iter().filter(|o| keep(o)).map(|o| o.name.clone()).collect::<Vec<_>>()
        };
        let mut tracked = outputs(&|o| o.tracked);
        tracked.extend(settings.inputs.iter().filter(|u| u.tracked).map(|u| u.name.clone()));
        Signals {
            inputs: settings.inputs.iter().map(|u| u.name.clone()).collect(),
            tracked,
            penalised: outputs(&|o| !o.tracked && o.weight > 0.0 && forces.contains(&o.name)),
            measured: outputs(&|o| o.noise_std.is_some()),
            input_max: settings.inputs.iter().map(|u| u.max_nm.abs().max(u.min_nm.abs())).collect(),
        }
    }
}

/// The step run: what steps, the signal the figures are taken from, and the figures.
#[derive(Debug, Clone, Serialize)]
pub struct StepResponse {
    /// What steps: an input (the paper rig's drive torque) or `reference` (every tracked
    /// speed's reference of a drive model).
    pub stepped: String,
    /// Height of the step (in `units.force` for an input, `units.speed` for a reference).
    pub step: f64,
    /// When it steps, s.
    pub at_s: f64,
    /// The signal the figures are taken from.
    pub signal: String,
    /// Settling band, relative to the step height.
    pub settling_band: f64,
    /// Overshoot and settling time.
    pub figures: Compared<StepFigures>,
    /// The signal at the end: the mean of the run's last 10 % (NaN when the run stopped).
    pub final_value: Compared<f64>,
}

/// The units of the figures whose unit depends on the model's domain.
#[derive(Debug, Clone, Serialize)]
pub struct Units {
    /// Of speeds and the tracking error: rad/s or m/s.
    pub speed: &'static str,
    /// Of forces, inputs and their bounds: N.m or N.
    pub force: &'static str,
}

impl Units {
    /// The units of `domain` (as the FMUs write them).
    pub fn of(domain: plant::Domain) -> Units {
        Units { speed: plant::Dimension::Speed.unit(domain), force: plant::Dimension::Force.unit(domain) }
    }
}

/// What `rigtwin mpc` reports, the same for every model (the paper rig against its PI
/// baseline, a drive model alone).
#[derive(Debug, Clone, Serialize)]
pub struct MpcReport {
    /// `paper_rig` or `drive_model`.
    pub model_kind: &'static str,
    /// Prediction horizon, steps of `dt_s`.
    pub horizon: usize,
    /// Sample time, s.
    pub dt_s: f64,
    /// QP formulation.
    pub formulation: crate::Formulation,
    /// Move blocks.
    pub move_blocks: Vec<usize>,
    /// QP size: variables and constraint rows.
    pub qp_variables: usize,
    /// Constraint rows.
    pub qp_constraints: usize,
    /// The run the timing comes from.
    pub scenario: ScenarioKind,
    /// One controller step (estimate + target + QP + bookkeeping), µs.
    pub step_time_us: Timing,
    /// Interior-point iterations per step: mean.
    pub qp_iterations_mean: f64,
    /// Largest number of heap allocations in one step, the controller's first step and the
    /// first that ran the interior-point method left out (Clarabel's first call sets up its
    /// timers; each later call allocates once, `mpc/tests/allocations.rs`) (`None`: not counted).
    pub allocations_per_step: Option<u64>,
    /// Heap allocations in the first step (`None`: not counted).
    pub allocations_first_step: Option<u64>,
    /// Steps that fell back to the shifted plan.
    pub fallbacks: usize,
    /// Controller steps of the timed run.
    pub steps: usize,
    /// Largest |u₀ − u₀*| over the checked steps, in `units.force` (u₀* from the same QP
    /// solved to 1e-12); none when no step could be checked (each fell back).
    pub u0_error: Option<f64>,
    /// Steps checked for `u0_error`.
    pub u0_checked_steps: usize,
    /// The controller's signals.
    pub signals: Signals,
    /// The step run's figures.
    pub step_response: StepResponse,
    /// RMS error of the tracked speeds from their references, in `units.speed`.
    pub tracking_error_rms: Compared<f64>,
    /// Largest |penalised force| of the step run, in `units.force`.
    pub peak_penalised_force: Compared<f64>,
    /// Share of the step run's samples with an input at a hard bound.
    pub input_at_bound_share: Compared<f64>,
    /// Where a step run stopped because the loop diverged (`None`: it ran to the end).
    pub stopped: Compared<Option<String>>,
    /// What the prediction includes and leaves out of the model's effects.
    pub prediction: Vec<String>,
    /// The effects of the plant the loop was closed on.
    pub plant_effects: String,
    /// The effects of the model the controller was designed on.
    pub model_effects: String,
    /// The domain's units.
    pub units: Units,
    /// The paper rig's sweep only: largest deviation of the short side-shaft torque from its
    /// quasi-static share of the drive torque (half of it) during the sweep, N·m.
    #[serde(rename = "sweep_peak_torque_deviation_Nm", skip_serializing_if = "Option::is_none")]
    pub sweep_peak_torque_deviation_nm: Option<Compared<f64>>,
    /// How the loops were judged (the baseline's bandwidth, the settling band).
    #[serde(skip)]
    pub harness: HarnessSettings,
    /// Whether the figures describe the MPC.
    #[serde(flatten)]
    pub validity: Validity,
}

/// Whether a run's figures describe the MPC ([`crate::closed_loop::fallback_verdict`]).
#[derive(Debug, Clone, Serialize)]
pub struct Validity {
    /// `valid`, or `not_valid` when the figures do not describe the MPC.
    pub verdict: &'static str,
    /// Why they do not, if they do not.
    pub not_valid_because: Option<String>,
}

impl Validity {
    /// The validity of a run of `steps` controller steps, `fallbacks` of them on the fallback plan.
    fn of(fallbacks: usize, steps: usize) -> Validity {
        let why = crate::closed_loop::fallback_verdict(fallbacks, steps);
        Validity { verdict: if why.is_some() { "not_valid" } else { "valid" }, not_valid_because: why }
    }
}

impl MpcReport {
    /// Why the figures do not describe the MPC, if they do not.
    pub fn invalid(&self) -> Option<String> {
        self.validity.not_valid_because.clone()
    }
}

/// A QP of one step with what rigtwin's Clarabel made of it.
#[derive(Debug, Clone, Serialize)]
pub struct ExportedQp {
    /// The QP.
    #[serde(flatten)]
    pub qp: QpSnapshot,
    /// The real-time solve's first input, Nm.
    #[serde(rename = "clarabel_u0_Nm")]
    pub clarabel_u0_nm: Vec<f64>,
    /// The real-time step's wall-clock time, µs (estimate + QP).
    pub clarabel_solve_time_us: f64,
}

/// A drive model's closed-loop run: what `rigtwin mpc --plot` draws.
#[derive(Debug, Clone)]
pub struct DriveRun {
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// The model's outputs.
    pub output_names: Vec<String>,
    /// The model's inputs.
    pub input_names: Vec<String>,
    /// Indices of the tracked outputs.
    pub tracked: Vec<usize>,
    /// Indices of the penalised forces.
    pub penalised: Vec<usize>,
    /// The tracked outputs' reference after the step.
    pub reference: f64,
    /// When the reference steps, s.
    pub step_at_s: f64,
    /// Outputs per sample.
    pub outputs: Vec<Vec<f64>>,
    /// Inputs per sample.
    pub inputs: Vec<Vec<f64>>,
}

/// The controller's real-time first input and its largest deviation from the exact optimum of
/// the same QP (solved to 1e-12): (max |u₀ − u₀*|, u₀).
fn first_input_error(c: &Controller) -> Result<(f64, Vec<f64>)> {
    let exact = c.exact_first_input()?;
    let rt = c.planned_first_input();
    let e = rt.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    Ok((e, rt))
}

/// The real-time first input against the exact optimum, at every `every`-th step that did not
/// fall back.
struct FirstInputCheck {
    every: usize,
    largest: f64,
    checked: usize,
}

impl FirstInputCheck {
    fn new(every: usize) -> Self {
        FirstInputCheck { every, largest: 0.0, checked: 0 }
    }

    /// Checks step `k` of controller `c` when it is due: the step's real-time first input then.
    fn at(&mut self, k: usize, c: &Controller, info: &StepInfo) -> Result<Option<Vec<f64>>> {
        if k % self.every != 0 || info.fallback {
            return Ok(None);
        }
        let (e, rt) = first_input_error(c)?;
        self.largest = self.largest.max(e);
        self.checked += 1;
        Ok(Some(rt))
    }

    /// The largest |u₀ − u₀*| over the checked steps (none when no step was checked).
    fn error(&self) -> Option<f64> {
        (self.checked > 0).then_some(self.largest)
    }
}

fn exact_solve_failed(e: impl std::fmt::Display) -> MpcError {
    MpcError::Numerical(format!("reference solve of the exact optimum failed: {e}"))
}

/// Largest |value| of the columns `which` over the samples `rows`.
fn peak_abs(rows: &[Vec<f64>], which: &[usize]) -> f64 {
    rows.iter().flat_map(|y| which.iter().map(move |&j| y[j].abs())).fold(0.0, f64::max)
}

/// The mean of the last 10 % of `values` (NaN when the run `stopped`).
fn final_mean(values: impl ExactSizeIterator<Item = f64>, stopped: bool) -> f64 {
    let n = values.len();
    let tail = (n / 10).max(1);
    if stopped || n == 0 {
        return f64::NAN;
    }
    values.skip(n - tail).sum::<f64>() / tail as f64
}

/// Largest of the steps' `allocations`, leaving out the first step and the first whose QP ran
/// interior-point `iterations` (each path's set-up).
fn steady_allocations(allocations: &[u64], iterations: &[u32]) -> u64 {
    let first_solve = iterations.iter().position(|&i| i > 0);
    let steady = allocations.iter().enumerate().filter(|&(k, _)| k > 0 && Some(k) != first_solve);
    steady.map(|(_, &a)| a).max().unwrap_or(0)
}

/// Mean of `counts` (0 for none).
fn mean(counts: &[u32]) -> f64 {
    counts.iter().map(|&c| f64::from(c)).sum::<f64>() / counts.len().max(1) as f64
}

/// Indices of `names` among `all`.
fn positions(names: &[String], all: &[String]) -> Vec<usize> {
    names.iter().filter_map(|n| all.iter().position(|o| o == n)).collect()
}

impl Scenario {
    /// This scenario run for `duration_s` instead of its own length: longer than its start and
    /// at most `harness.max_duration_s` ([`HarnessSettings::run_length`]).
    pub fn with_duration(mut self, duration_s: f64, harness: &HarnessSettings) -> std::result::Result<Self, String> {
        self.duration_s = harness.run_length(duration_s, ("the scenario's start", self.start_s))?;
        Ok(self)
    }
}

/// The paper rig's MPC (designed on `model`, predicting with `prediction`, with `settings`)
/// and its PI baseline through `scenario`, each closed on `truth` as the rig's FMU steps it
/// from the steady spin at the scenario's speed; the step figures come from the step scenario
/// (the same run when `scenario` is it). `allocations` reads the process's allocation counter;
/// `export` receives the QPs of the checked steps. Both models must be the paper rig's.
#[allow(clippy::too_many_arguments)]
pub fn rig(
    model: &Design,
    prediction: &Prediction,
    truth: &Design,
    settings: &MpcSettings,
    scenario: &Scenario,
    harness: &HarnessSettings,
    allocations: Option<fn() -> u64>,
    mut export: Option<&mut Vec<ExportedQp>>,
) -> Result<(MpcReport, Comparison)> {
    let (Design::Rig { rig, variant, effects }, Design::Rig { rig: t_rig, variant: t_variant, effects: t_effects }) =
        (*model, *truth)
    else {
        return Err(setting("plant", "the paper rig's loop is closed on the paper rig (a drive model was given)"));
    };
    let ss = &prediction.model;
    let sig = RigSignals::of(ss)?;
    let j_load = rig.effective(variant)?.j_m2;
    let run_on = |scenario: &Scenario, probes: Probes<'_>| -> Result<Comparison> {
        let (_, u0) = crate::closed_loop::steady_spin(ss, scenario.speed_radps)?;
        let speed = scenario.speed_radps;
        let mut make = |_: &DVector<f64>| -> std::result::Result<Box<dyn Plant>, String> {
            let p = DrivePlant::paper_rig(t_rig, t_variant, t_effects, settings.dt_s, speed, &u0, &ss.output_names)
                .map_err(|e| format!("the plant: {e}"))?;
            Ok(Box::new(p))
        };
        let pi_hz = harness.pi_bandwidth_hz;
        compare(ss, &prediction.input_delays_s, &mut make, settings, scenario, j_load, pi_hz, probes)
            .map_err(MpcError::Numerical)
    };
    let (mut check, mut failure) = (FirstInputCheck::new(harness.check_every), None);
    let mut hook = |k: usize, c: &Controller, info: &StepInfo| match check.at(k, c, info) {
        Ok(Some(rt)) => {
            if let Some(list) = export.as_deref_mut() {
                list.push(ExportedQp {
                    qp: c.snapshot(),
                    clarabel_u0_nm: rt,
                    clarabel_solve_time_us: info.elapsed_s * 1e6,
                });
            }
        }
        Ok(None) => {}
        Err(e) => failure = Some(e),
    };
    let run = run_on(scenario, Probes { allocations, after_step: Some(&mut hook) })?;
    if let Some(e) = failure {
        return Err(exact_solve_failed(e));
    }
    let step_scenario = Scenario::new(ScenarioKind::Step);
    let step = if *scenario == step_scenario { run.clone() } else { run_on(&step_scenario, Probes::default())? };
    let k_step = (step_scenario.start_s / settings.dt_s).round() as usize;
    let fig = |t: &Trace| {
        if t.stopped.is_some() {
            StepFigures { overshoot: f64::NAN, settling_time_s: f64::NAN }
        } else {
            step_figures(&t.output(sig.short_shaft), k_step, settings.dt_s, harness.settling_band)
        }
    };
    let speed_rms = |t: &Trace| {
        if t.stopped.is_some() {
            return f64::NAN;
        }
        let n = t.outputs.len() as f64;
        let squares = |y: &Vec<f64>| {
            (y[sig.speeds[0]] - scenario.speed_radps).powi(2) + (y[sig.speeds[2]] - scenario.speed_radps).powi(2)
        };
        (t.outputs.iter().map(squares).sum::<f64>() / (2.0 * n)).sqrt()
    };
    let sweep_dev = |t: &Trace| {
        t.outputs
            .iter()
            .zip(&t.time_s)
            .filter(|(_, &time)| time >= scenario.start_s)
            .map(|(y, &time)| (y[sig.short_shaft] - 0.5 * scenario.drive_torque(time)).abs())
            .fold(0.0, f64::max)
    };
    // the rig's forces are its side-shaft torques, T_…
    let forces: Vec<String> = ss.output_names.iter().filter(|n| n.starts_with("T_")).cloned().collect();
    let signals = Signals::of(settings, &forces);
    let penalised = positions(&signals.penalised, &ss.output_names);
    let both = |f: &dyn Fn(&Trace) -> f64| Compared { mpc: f(&step.mpc), baseline: Some(f(&step.baseline)) };
    let times_us: Vec<f64> = run.step_times_s.iter().map(|t| t * 1e6).collect();
    let report = MpcReport {
        model_kind: "paper_rig",
        horizon: settings.horizon,
        dt_s: settings.dt_s,
        formulation: settings.formulation,
        move_blocks: settings.blocks(),
        qp_variables: run.qp_size.0,
        qp_constraints: run.qp_size.1,
        scenario: scenario.kind,
        step_time_us: Timing::of(&times_us),
        qp_iterations_mean: mean(&run.iterations),
        allocations_per_step: allocations.map(|_| steady_allocations(&run.step_allocations, &run.iterations)),
        allocations_first_step: allocations.map(|_| run.step_allocations.first().copied().unwrap_or(0)),
        fallbacks: run.fallbacks,
        steps: run.step_times_s.len(),
        validity: Validity::of(run.fallbacks, run.step_times_s.len()),
        u0_error: check.error(),
        u0_checked_steps: check.checked,
        step_response: StepResponse {
            stepped: ss.input_names[sig.inputs[1]].clone(),
            step: step_scenario.torque_nm,
            at_s: step_scenario.start_s,
            signal: ss.output_names[sig.short_shaft].clone(),
            settling_band: harness.settling_band,
            figures: Compared { mpc: fig(&step.mpc), baseline: Some(fig(&step.baseline)) },
            final_value: both(&|t| final_mean(t.outputs.iter().map(|y| y[sig.short_shaft]), t.stopped.is_some())),
        },
        tracking_error_rms: Compared { mpc: speed_rms(&run.mpc), baseline: Some(speed_rms(&run.baseline)) },
        peak_penalised_force: both(&|t| peak_abs(&t.outputs, &penalised)),
        input_at_bound_share: both(&|t| share_at_bounds(&t.inputs, settings, &ss.input_names)),
        stopped: Compared { mpc: step.mpc.stopped.clone(), baseline: Some(step.baseline.stopped.clone()) },
        signals,
        prediction: prediction.notes.clone(),
        plant_effects: t_effects.in_words(),
        model_effects: effects.in_words(),
        units: Units::of(plant::Domain::Rotational),
        sweep_peak_torque_deviation_nm: (scenario.kind == ScenarioKind::Sweep)
            .then(|| Compared { mpc: sweep_dev(&run.mpc), baseline: Some(sweep_dev(&run.baseline)) }),
        harness: *harness,
    };
    Ok((report, run))
}

/// The MPC of the drive model `model` (predicting with `prediction`, with `settings`) in closed
/// loop on `truth` as its FMU steps it, from rest: every tracked speed's reference steps by
/// `harness`' reference step at its time (tracked inputs' references stay 0), for its run's
/// length. The first input is checked against the exact optimum every `harness.check_every`
/// steps and the allocations counted (`allocations`), as on the paper rig.
pub fn drive(
    model: &DriveModel,
    prediction: &Prediction,
    truth: &DriveModel,
    settings: &MpcSettings,
    harness: &HarnessSettings,
    allocations: Option<fn() -> u64>,
) -> Result<(MpcReport, DriveRun)> {
    let step = harness.reference_step(model.line.domain);
    if truth.input_names() != model.input_names() || truth.coupling_force_names() != model.coupling_force_names() {
        return Err(setting("plant", "its bodies and inputs differ from the model's"));
    }
    let ss = &prediction.model;
    let mut controller = Controller::with_input_delays(ss, &prediction.input_delays_s, settings)?;
    let names = controller.reference_names();
    controller.reset(&DVector::zeros(ss.nstates()), &vec![0.0; ss.input_names.len()]);
    let mut plant = DrivePlant::new(truth, settings.dt_s, &ss.output_names)?;
    let dt = settings.dt_s;
    let samples = (harness.drive_run_s / dt).round() as usize;
    let k_step = (harness.reference_step_at_s / dt).round() as usize;
    let tracked = positions(&names, &ss.output_names);
    let signals = Signals::of(settings, &model.coupling_force_names());
    let penalised = positions(&signals.penalised, &ss.output_names);
    let reference = |k: usize| -> Vec<f64> {
        names.iter().map(|n| if k >= k_step && ss.output_names.contains(n) { step } else { 0.0 }).collect()
    };
    let (mut check, mut failure) = (FirstInputCheck::new(harness.check_every), None);
    let run = {
        let mut hook = |k: usize, c: &Controller, info: &StepInfo| {
            if let Err(e) = check.at(k, c, info) {
                failure.get_or_insert(e);
            }
        };
        let mut probes = Probes { allocations, after_step: Some(&mut hook) };
        run_mpc(&mut controller, &mut plant, samples, dt, &reference, &mut probes)
    };
    if let Some(e) = failure {
        return Err(exact_solve_failed(e));
    }
    let times_us: Vec<f64> = run.step_times_s.iter().map(|t| t * 1e6).collect();
    let Trace { time_s, outputs: trace, inputs, stopped, .. } = run.trace;
    let response = match (tracked.first(), &stopped) {
        (Some(&j), None) => {
            step_figures(&trace.iter().map(|y| y[j]).collect::<Vec<_>>(), k_step, dt, harness.settling_band)
        }
        _ => StepFigures { overshoot: f64::NAN, settling_time_s: f64::NAN },
    };
    let after = &trace[k_step.min(trace.len())..];
    let tracking_error_rms = if tracked.is_empty() || after.is_empty() || stopped.is_some() {
        f64::NAN
    } else {
        (after.iter().map(|y| tracked.iter().map(|&j| (y[j] - step).powi(2)).sum::<f64>()).sum::<f64>()
            / (after.len() * tracked.len()) as f64)
            .sqrt()
    };
    let in_words = |m: &DriveModel| {
        let named = m.effects_at();
        if named.is_empty() {
            "none".to_string()
        } else {
            named.join(", ")
        }
    };
    let report = MpcReport {
        model_kind: "drive_model",
        horizon: settings.horizon,
        dt_s: dt,
        formulation: settings.formulation,
        move_blocks: settings.blocks(),
        qp_variables: controller.qp().nvars(),
        qp_constraints: controller.qp().nrows(),
        scenario: ScenarioKind::Step,
        step_time_us: Timing::of(&times_us),
        qp_iterations_mean: mean(&run.iterations),
        allocations_per_step: allocations.map(|_| steady_allocations(&run.step_allocations, &run.iterations)),
        allocations_first_step: allocations.map(|_| run.step_allocations.first().copied().unwrap_or(0)),
        fallbacks: controller.fallbacks(),
        steps: times_us.len(),
        validity: Validity::of(controller.fallbacks(), times_us.len()),
        u0_error: check.error(),
        u0_checked_steps: check.checked,
        step_response: StepResponse {
            stepped: "reference".into(),
            step,
            at_s: k_step as f64 * dt,
            signal: tracked.first().map_or("nothing tracked".into(), |&j| ss.output_names[j].clone()),
            settling_band: harness.settling_band,
            figures: Compared::alone(response),
            final_value: Compared::alone(
                tracked.first().map_or(f64::NAN, |&j| final_mean(trace.iter().map(|y| y[j]), stopped.is_some())),
            ),
        },
        tracking_error_rms: Compared::alone(tracking_error_rms),
        peak_penalised_force: Compared::alone(peak_abs(&trace, &penalised)),
        input_at_bound_share: Compared::alone(share_at_bounds(&inputs, settings, &ss.input_names)),
        stopped: Compared::alone(stopped),
        signals,
        prediction: prediction.notes.clone(),
        plant_effects: in_words(truth),
        model_effects: in_words(model),
        units: Units::of(model.line.domain),
        sweep_peak_torque_deviation_nm: None,
        harness: *harness,
    };
    let run = DriveRun {
        time_s,
        output_names: ss.output_names.clone(),
        input_names: ss.input_names.clone(),
        tracked,
        penalised,
        reference: step,
        step_at_s: k_step as f64 * dt,
        outputs: trace,
        inputs,
    };
    Ok((report, run))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first step and the first interior-point solve (each path's set-up) are left out of
    /// the per-step allocations; without any solve only the first step is.
    #[test]
    fn set_up_steps_are_left_out_of_the_allocations_per_step() {
        assert_eq!(steady_allocations(&[5, 0, 0, 2, 1, 1], &[0, 0, 0, 9, 10, 8]), 1);
        assert_eq!(steady_allocations(&[5, 0, 3], &[0, 0, 0]), 3);
        assert_eq!(steady_allocations(&[5], &[7]), 0);
    }
}
