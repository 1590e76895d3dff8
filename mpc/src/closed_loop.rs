//! Closed-loop simulation: a controller against a plant (the ZOH-exact linear plant here, the
//! FMU in the tests), the rig's conventional PI speed control as the baseline, and the
//! shuffle figures (overshoot, settling time) of a drive-torque step.

use nalgebra::{DMatrix, DVector};
use plant::statespace::StateSpace;
use serde::Serialize;

use crate::controller::Controller;
use crate::error::Result;

/// How `rigtwin mpc` judges a closed loop: the baseline it compares the MPC with, the band its
/// figures settle in, the longest run it takes and how often it checks the real-time solve.
/// The defaults are documented per field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HarnessSettings {
    /// The PI baseline's speed-loop crossover, Hz. Default 5 Hz: a typical rig's load-machine
    /// speed loop, well below the shuffle (≈ 20 Hz on the paper's rig).
    pub pi_bandwidth_hz: f64,
    /// Settling band of the step figures, relative to the step height. Default 0.02 (the 2 %
    /// settling time of control texts).
    pub settling_band: f64,
    /// Longest closed-loop run taken, s. Default 120 s: both runs keep their traces
    /// (≈ 0.4 kB per sample), so a run stays under ≈ 100 MB.
    pub max_duration_s: f64,
    /// Every this many steps the real-time first input is compared with the exact optimum.
    /// Default 25: the exact solve costs tens of real-time steps, so checking one step in 25
    /// keeps a 60 s run within seconds while still sampling every phase of the scenario.
    pub check_every: usize,
    /// A drive model's run: the step of every tracked speed's reference in a rotational line,
    /// rad/s. Default 10 rad/s (≈ 100 rpm: a speed step a test bench makes, small against its
    /// machines' rated speeds).
    pub reference_step_radps: f64,
    /// The same in a translational line, m/s. Default 0.1 m/s (a positioning axis's jog).
    pub reference_step_mps: f64,
    /// When a drive model's reference steps, s. Default 0.05 s (the paper rig's step time).
    pub reference_step_at_s: f64,
    /// Length of a drive model's run, s. Default 1 s (the paper rig's step run).
    pub drive_run_s: f64,
}

impl HarnessSettings {
    /// The documented defaults.
    pub const DEFAULT: HarnessSettings = HarnessSettings {
        pi_bandwidth_hz: 5.0,
        settling_band: 0.02,
        max_duration_s: 120.0,
        check_every: 25,
        reference_step_radps: 10.0,
        reference_step_mps: 0.1,
        reference_step_at_s: 0.05,
        drive_run_s: 1.0,
    };

    /// `duration_s` as the length of a run whose `start` (its name and time, s) it must pass:
    /// finite, longer than that and at most [`HarnessSettings::max_duration_s`] — the one rule
    /// of the paper rig's scenarios and a drive model's run.
    pub fn run_length(&self, duration_s: f64, start: (&str, f64)) -> std::result::Result<f64, String> {
        let ((what, start_s), longest) = (start, self.max_duration_s);
        if !(duration_s.is_finite() && duration_s > start_s && duration_s <= longest) {
            return Err(format!("expected more than {what} {start_s} s and at most {longest} s"));
        }
        Ok(duration_s)
    }

    /// These settings with a drive model's run `duration_s` long: after its reference step
    /// ([`HarnessSettings::run_length`]).
    pub fn with_drive_run(self, duration_s: f64) -> std::result::Result<Self, String> {
        let drive_run_s = self.run_length(duration_s, ("the reference step's time", self.reference_step_at_s))?;
        Ok(HarnessSettings { drive_run_s, ..self })
    }

    /// The reference step of a drive model's run in `domain` (rad/s or m/s).
    pub fn reference_step(&self, domain: plant::Domain) -> f64 {
        match domain {
            plant::Domain::Rotational => self.reference_step_radps,
            plant::Domain::Translational => self.reference_step_mps,
        }
    }
}

impl Default for HarnessSettings {
    fn default() -> Self {
        HarnessSettings::DEFAULT
    }
}

/// Largest share of a run's controller steps that may fall back to the shifted previous plan
/// (the QP missed its time limit or failed) for the run to describe the MPC: past it the loop
/// was mostly driven by stale plans, and its figures are the fallback's, not the controller's.
pub const MAX_FALLBACK_SHARE: f64 = 0.1;

/// Why a closed-loop run's figures do not describe the MPC, if they do not: the QP missed its
/// time limit in more than [`MAX_FALLBACK_SHARE`] of the `steps` (or there were none), so the
/// loop ran on the fallback plan.
pub fn fallback_verdict(fallbacks: usize, steps: usize) -> Option<String> {
    let share = fallbacks as f64 / steps.max(1) as f64;
    (steps == 0 || share > MAX_FALLBACK_SHARE).then(|| {
        format!(
            "the QP missed its time limit in {fallbacks} of {steps} steps ({:.0} %): the loop ran on the fallback plan, so these figures do not describe the MPC; shorten --horizon, use more --blocks or raise --time-limit-us",
            share * 100.0
        )
    })
}

/// Anything that takes the inputs for one sample period and gives its outputs.
pub trait Plant {
    /// Current outputs (all of them, in the plant's output order).
    fn outputs(&self) -> &[f64];
    /// Applies `u` (held for one sample period) and advances.
    fn advance(&mut self, u: &[f64]) -> std::result::Result<(), String>;
}

/// Anything that maps outputs and references to inputs.
pub trait Control {
    /// Input for this sample (plant order, Nm).
    fn control(&mut self, y: &[f64], reference: &[f64], u: &mut [f64]) -> std::result::Result<(), String>;
}

/// The continuous plant, exact under ZOH.
pub struct LinearPlant {
    ad: DMatrix<f64>,
    bd: DMatrix<f64>,
    c: DMatrix<f64>,
    x: DVector<f64>,
    next: DVector<f64>,
    y: DVector<f64>,
    u: DVector<f64>,
}

impl LinearPlant {
    /// `plant` sampled every `dt_s`, starting at `x0`.
    pub fn new(plant: &StateSpace, dt_s: f64, x0: &DVector<f64>) -> Result<Self> {
        let d = plant.c2d(dt_s)?;
        let y = &d.c * x0;
        Ok(LinearPlant {
            u: DVector::zeros(d.bd.ncols()),
            next: x0.clone(),
            x: x0.clone(),
            ad: d.ad,
            bd: d.bd,
            c: d.c,
            y,
        })
    }

    /// The state.
    pub fn state(&self) -> &DVector<f64> {
        &self.x
    }
}

impl Plant for LinearPlant {
    fn outputs(&self) -> &[f64] {
        self.y.as_slice()
    }
    fn advance(&mut self, u: &[f64]) -> std::result::Result<(), String> {
        self.u.copy_from_slice(u);
        self.next.gemv(1.0, &self.ad, &self.x, 0.0);
        self.next.gemv(1.0, &self.bd, &self.u, 1.0);
        std::mem::swap(&mut self.x, &mut self.next);
        self.y.gemv(1.0, &self.c, &self.x, 0.0);
        Ok(())
    }
}

impl Control for Controller {
    fn control(&mut self, y: &[f64], reference: &[f64], u: &mut [f64]) -> std::result::Result<(), String> {
        let (v, _) = self.step(y, reference);
        u.copy_from_slice(v);
        Ok(())
    }
}

/// The rig's conventional control (section 1.2): each load machine a PI speed controller,
/// the drive torque set to its reference directly (open loop).
#[derive(Debug, Clone)]
pub struct PiBaseline {
    /// Per load machine: (input index, output index of its speed, reference index).
    pub loops: Vec<(usize, usize, usize)>,
    /// Drive: (input index, reference index).
    pub feedthrough: Vec<(usize, usize)>,
    /// Proportional gain, Nm s/rad.
    pub kp: f64,
    /// Integral gain, Nm/rad.
    pub ki: f64,
    /// Sample time, s.
    pub dt_s: f64,
    integral: Vec<f64>,
}

impl PiBaseline {
    /// PI speed loops whose crossover is `bandwidth_hz` on a load inertia `j_load`
    /// (kp = J ω_c) with the integral corner a quarter of it (ki = kp ω_c / 4); `integral0`
    /// pre-loads the integrators (the torque already needed at the start, Nm).
    pub fn new(
        loops: Vec<(usize, usize, usize)>,
        feedthrough: Vec<(usize, usize)>,
        j_load: f64,
        bandwidth_hz: f64,
        dt_s: f64,
        integral0: Vec<f64>,
    ) -> Self {
        let wc = 2.0 * std::f64::consts::PI * bandwidth_hz;
        let kp = j_load * wc;
        PiBaseline { loops, feedthrough, kp, ki: kp * wc / 4.0, dt_s, integral: integral0 }
    }
}

impl Control for PiBaseline {
    fn control(&mut self, y: &[f64], reference: &[f64], u: &mut [f64]) -> std::result::Result<(), String> {
        for (k, &(iu, iy, ir)) in self.loops.iter().enumerate() {
            let e = reference[ir] - y[iy];
            self.integral[k] += self.ki * e * self.dt_s;
            u[iu] = self.kp * e + self.integral[k];
        }
        for &(iu, ir) in &self.feedthrough {
            u[iu] = reference[ir];
        }
        Ok(())
    }
}

/// Advances `plant` and checks that its outputs stay finite and within ±[`DIVERGED`].
pub fn advance(plant: &mut dyn Plant, u: &[f64]) -> std::result::Result<(), String> {
    plant.advance(u)?;
    match plant.outputs().iter().position(|y| y.is_nan() || y.abs() >= DIVERGED) {
        Some(i) => Err(format!("output {i} is {} (the loop diverged)", plant.outputs()[i])),
        None => Ok(()),
    }
}

/// A recorded closed-loop run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Trace {
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// Outputs per sample (plant order).
    pub outputs: Vec<Vec<f64>>,
    /// Inputs per sample (plant order), Nm.
    pub inputs: Vec<Vec<f64>>,
    /// References per sample.
    pub references: Vec<Vec<f64>>,
    /// Why the run stopped early (the plant's state diverged or could not be integrated);
    /// `None`: it ran to the end.
    pub stopped: Option<String>,
}

/// A run is stopped when an output leaves ±this (rad/s, Nm): the loop has gone unstable.
pub const DIVERGED: f64 = 1e6;

impl Trace {
    /// The output column `j`.
    pub fn output(&self, j: usize) -> Vec<f64> {
        self.outputs.iter().map(|y| y[j]).collect()
    }
}

/// Runs `control` against `plant` for the references `reference(k)` (sample k), recording
/// everything. `on_step` is told each sample (for timing).
pub fn simulate(
    plant: &mut dyn Plant,
    control: &mut dyn Control,
    samples: usize,
    dt_s: f64,
    u0: &[f64],
    reference: &dyn Fn(usize) -> Vec<f64>,
) -> std::result::Result<Trace, String> {
    let mut trace = Trace::default();
    let mut u = u0.to_vec();
    for k in 0..samples {
        let r = reference(k);
        let y = plant.outputs().to_vec();
        control.control(&y, &r, &mut u)?;
        trace.time_s.push(k as f64 * dt_s);
        trace.outputs.push(y);
        trace.inputs.push(u.clone());
        trace.references.push(r);
        if let Err(e) = advance(plant, &u) {
            trace.stopped = Some(format!("at {:.4} s: {e}", k as f64 * dt_s));
            break;
        }
    }
    Ok(trace)
}

/// Overshoot and settling of a step response.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepFigures {
    /// (peak − final) / (final − initial), in the step's direction; 0 when it never
    /// passes the final value.
    pub overshoot: f64,
    /// Time after the step until the signal stays within ±`band` of the step height around
    /// its final value, s.
    pub settling_time_s: f64,
}

/// Figures of `signal` (sampled every `dt_s`) for a step at sample `k_step`; the initial value
/// is the sample before it, the final value the mean of the last 10 % of the record.
pub fn step_figures(signal: &[f64], k_step: usize, dt_s: f64, band: f64) -> StepFigures {
    let initial = signal[k_step.saturating_sub(1)];
    let tail = &signal[signal.len() - signal.len() / 10..];
    let fin = tail.iter().sum::<f64>() / tail.len() as f64;
    let height = fin - initial;
    let after = &signal[k_step..];
    let peak = after.iter().map(|v| (v - initial) / height).fold(f64::NEG_INFINITY, f64::max);
    let overshoot = (peak - 1.0).max(0.0);
    let last_out = after.iter().rposition(|v| ((v - fin) / height).abs() > band).map_or(0, |i| i + 1);
    StepFigures { overshoot, settling_time_s: last_out as f64 * dt_s }
}

/// What the rig is asked to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScenarioKind {
    /// Drive-torque step at constant load-machine speeds.
    Step,
    /// Drive-torque sine sweep (1 → 30 Hz) about a set point at constant speeds.
    Sweep,
}

/// The road-load scenario on the open-differential rig.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scenario {
    /// Step or sweep.
    pub kind: ScenarioKind,
    /// Load-machine speed reference, rad/s.
    pub speed_radps: f64,
    /// Drive-torque step height (step) or set point (sweep), Nm.
    pub torque_nm: f64,
    /// Sweep amplitude, Nm.
    pub sweep_amplitude_nm: f64,
    /// Time of the step / start of the sweep, s.
    pub start_s: f64,
    /// Length of the run, s.
    pub duration_s: f64,
}

impl Scenario {
    /// 40 Nm drive-torque step (the paper's sweep set point at the output) at 0.05 s, loads
    /// held at 10 rad/s, 1 s long; or the set point from 0 s and, from 0.5 s on, a 1-30 Hz
    /// sweep of ±8 Nm about it over 3 s (the paper's 16 Nm peak to peak).
    pub fn new(kind: ScenarioKind) -> Self {
        match kind {
            ScenarioKind::Step => Scenario {
                kind,
                speed_radps: 10.0,
                torque_nm: 40.0,
                sweep_amplitude_nm: 0.0,
                start_s: 0.05,
                duration_s: 1.0,
            },
            ScenarioKind::Sweep => Scenario {
                kind,
                speed_radps: 10.0,
                torque_nm: 40.0,
                sweep_amplitude_nm: 8.0,
                start_s: 0.5,
                duration_s: 3.5,
            },
        }
    }

    /// Drive-torque reference at time `t`, Nm.
    pub fn drive_torque(&self, t: f64) -> f64 {
        match self.kind {
            ScenarioKind::Step => {
                if t >= self.start_s {
                    self.torque_nm
                } else {
                    0.0
                }
            }
            ScenarioKind::Sweep => {
                if t < self.start_s {
                    return self.torque_nm;
                }
                // Linear chirp 1 → 30 Hz over the run after the start.
                let (f0, f1, len) = (1.0, 30.0, self.duration_s - self.start_s);
                let tau = t - self.start_s;
                let phase = 2.0 * std::f64::consts::PI * (f0 * tau + 0.5 * (f1 - f0) / len * tau * tau);
                self.torque_nm + self.sweep_amplitude_nm * phase.sin()
            }
        }
    }
}

/// The rig's signals, found by name in the plant's state space.
#[derive(Debug, Clone, Copy)]
pub struct RigSignals {
    /// Inputs M_m2, M_drive, M_m3.
    pub inputs: [usize; 3],
    /// Outputs w_m2, w_drive, w_m3.
    pub speeds: [usize; 3],
    /// Output T_short_side_shaft.
    pub short_shaft: usize,
}

impl RigSignals {
    /// Finds the rig's signals in `plant`.
    pub fn of(plant: &StateSpace) -> Result<Self> {
        let find = |names: &[String], n: &str, kind: &'static str| {
            names.iter().position(|s| s == n).ok_or_else(|| crate::error::MpcError::UnknownSignal {
                key: "plant".into(),
                kind,
                name: n.into(),
                available: names.join(", "),
            })
        };
        let i = |n| find(&plant.input_names, n, "input");
        let o = |n| find(&plant.output_names, n, "output");
        Ok(RigSignals {
            inputs: [i("M_m2")?, i("M_drive")?, i("M_m3")?],
            speeds: [o("w_m2")?, o("w_drive")?, o("w_m3")?],
            short_shaft: o("T_short_side_shaft")?,
        })
    }
}

/// The open-differential rig of `params` in `variant` with the outputs the controller and the
/// figures use: the three speeds and the two side-shaft torques.
pub fn rig_plant(params: &plant::rig::RigParams, variant: plant::rig::Variant) -> Result<StateSpace> {
    use plant::mechanical::Output;
    Ok(params.open_differential(variant)?.state_space(&[Output::Speeds, Output::SpringTorques])?)
}

/// Steady spinning at `speed` (all angles zero, every speed equal) and the inputs that hold
/// it (drag compensation): u = −B⁺ A x.
pub fn steady_spin(plant: &StateSpace, speed: f64) -> Result<(DVector<f64>, Vec<f64>)> {
    let n = plant.nstates();
    let mut x = DVector::zeros(n);
    for (i, name) in plant.state_names.iter().enumerate() {
        if name.starts_with("w_") {
            x[i] = speed;
        }
    }
    let pinv = plant.b.clone().pseudo_inverse(1e-12).map_err(|e| crate::error::MpcError::Numerical(e.to_string()))?;
    let u = -(pinv * &plant.a * &x);
    Ok((x, u.iter().copied().collect()))
}

/// The MPC and the PI baseline, each run on the same plant and scenario.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// The MPC run.
    pub mpc: Trace,
    /// The PI baseline run.
    pub baseline: Trace,
    /// Wall-clock time of every controller step, s.
    pub step_times_s: Vec<f64>,
    /// Heap allocations of every controller step (zeros when no counter was given).
    pub step_allocations: Vec<u64>,
    /// QP iterations of every step.
    pub iterations: Vec<u32>,
    /// Steps that used the fallback plan.
    pub fallbacks: usize,
    /// The MPC's QP: variables and constraint rows.
    pub qp_size: (usize, usize),
}

/// Called after each MPC step with the sample index, the controller and what the step did.
pub type AfterStep<'a> = &'a mut dyn FnMut(usize, &Controller, &crate::controller::StepInfo);

/// Makes a fresh plant starting at a state.
pub type MakePlant<'a> = &'a mut dyn FnMut(&DVector<f64>) -> std::result::Result<Box<dyn Plant>, String>;

/// Probes called around the MPC's steps: an allocation counter, and a hook after each step
/// (sample index, controller) — e.g. to keep QPs for other solvers.
#[derive(Default)]
pub struct Probes<'a> {
    /// Reads a process-wide allocation count.
    pub allocations: Option<fn() -> u64>,
    /// Called after each MPC step.
    pub after_step: Option<AfterStep<'a>>,
}

/// Runs the MPC (with `settings`, predicting with `plant` whose inputs act `input_delays_s` late)
/// and the PI baseline (speed loops of `pi_bandwidth_hz` on load inertia `j_load`) through
/// `scenario`, each from the steady spin at the scenario's speed. `make_plant` gives a fresh
/// plant per run (the linear plant, an FMU, a plant with effects the prediction lacks, …),
/// whose outputs are in the order of `plant`'s. A run whose plant diverges stops there
/// ([`Trace::stopped`]).
#[allow(clippy::too_many_arguments)]
pub fn compare(
    plant: &StateSpace,
    input_delays_s: &[f64],
    make_plant: MakePlant<'_>,
    settings: &crate::settings::MpcSettings,
    scenario: &Scenario,
    j_load: f64,
    pi_bandwidth_hz: f64,
    mut probes: Probes<'_>,
) -> std::result::Result<Comparison, String> {
    let sig = RigSignals::of(plant).map_err(|e| e.to_string())?;
    let dt = settings.dt_s;
    let (x0, u0) = steady_spin(plant, scenario.speed_radps).map_err(|e| e.to_string())?;
    let mut controller = Controller::with_input_delays(plant, input_delays_s, settings).map_err(|e| e.to_string())?;
    controller.reset(&x0, &u0);
    let names = controller.reference_names();
    let want = ["w_m2", "w_m3", "M_drive"];
    let order: Vec<usize> = names
        .iter()
        .map(|n| want.iter().position(|w| w == n).ok_or_else(|| format!("unexpected reference `{n}`")))
        .collect::<std::result::Result<_, _>>()?;
    let samples = (scenario.duration_s / dt).round() as usize;
    let refs = |k: usize| {
        let all = [scenario.speed_radps, scenario.speed_radps, scenario.drive_torque(k as f64 * dt)];
        order.iter().map(|&i| all[i]).collect::<Vec<f64>>()
    };

    let mut p = make_plant(&x0)?;
    let run = run_mpc(&mut controller, p.as_mut(), samples, dt, &refs, &mut probes);

    let ref_speed = |name: &str| order.iter().position(|&i| want[i] == name);
    let (i2, i3, id) = (ref_speed("w_m2"), ref_speed("w_m3"), ref_speed("M_drive"));
    let (i2, i3, id) = match (i2, i3, id) {
        (Some(a), Some(b), Some(c)) => (a, b, c),
        _ => return Err("the baseline needs references w_m2, w_m3 and M_drive".into()),
    };
    let mut pi = PiBaseline::new(
        vec![(sig.inputs[0], sig.speeds[0], i2), (sig.inputs[2], sig.speeds[2], i3)],
        vec![(sig.inputs[1], id)],
        j_load,
        pi_bandwidth_hz,
        dt,
        vec![u0[sig.inputs[0]], u0[sig.inputs[2]]],
    );
    let mut p = make_plant(&x0)?;
    let baseline = simulate(p.as_mut(), &mut pi, samples, dt, &u0, &refs)?;
    Ok(Comparison {
        mpc: run.trace,
        baseline,
        step_times_s: run.step_times_s,
        step_allocations: run.step_allocations,
        iterations: run.iterations,
        fallbacks: controller.fallbacks(),
        qp_size: (controller.qp().nvars(), controller.qp().nrows()),
    })
}

/// The MPC's run: its trace and what each of its steps took.
#[derive(Debug, Clone, Default)]
pub struct MpcRun {
    /// Outputs, inputs and references per sample; where it stopped.
    pub trace: Trace,
    /// Wall-clock time of every controller step, s.
    pub step_times_s: Vec<f64>,
    /// Heap allocations of every controller step (zeros when no counter was given).
    pub step_allocations: Vec<u64>,
    /// QP iterations of every step.
    pub iterations: Vec<u32>,
}

/// Runs `controller` against `plant` for `samples` steps of `dt_s` with the references
/// `reference(k)` (sample k), recording everything; `probes` are called around each step. A
/// run whose plant diverges stops there ([`Trace::stopped`]).
pub fn run_mpc(
    controller: &mut Controller,
    plant: &mut dyn Plant,
    samples: usize,
    dt_s: f64,
    reference: &dyn Fn(usize) -> Vec<f64>,
    probes: &mut Probes<'_>,
) -> MpcRun {
    let mut run = MpcRun::default();
    let mut y = vec![0.0; plant.outputs().len()];
    for k in 0..samples {
        y.copy_from_slice(plant.outputs());
        let r = reference(k);
        let before = probes.allocations.map_or(0, |f| f());
        let (v, info) = controller.step(&y, &r);
        let after = probes.allocations.map_or(0, |f| f());
        let u = v.to_vec();
        run.step_times_s.push(info.elapsed_s);
        run.step_allocations.push(after - before);
        run.iterations.push(info.solve.iterations);
        if let Some(hook) = probes.after_step.as_mut() {
            hook(k, controller, &info);
        }
        run.trace.time_s.push(k as f64 * dt_s);
        run.trace.outputs.push(y.clone());
        run.trace.inputs.push(u.clone());
        run.trace.references.push(r);
        if let Err(e) = advance(plant, &u) {
            run.trace.stopped = Some(format!("at {:.4} s: {e}", k as f64 * dt_s));
            break;
        }
    }
    run
}

/// Share of the samples `inputs` (plant input order, names `input_names`) with an input at a
/// hard bound of `settings` (within 1e-9 of it, relative).
pub fn share_at_bounds(inputs: &[Vec<f64>], settings: &crate::settings::MpcSettings, input_names: &[String]) -> f64 {
    let bounds: Vec<(usize, f64, f64)> = settings
        .inputs
        .iter()
        .filter_map(|u| input_names.iter().position(|n| n == &u.name).map(|j| (j, u.min_nm, u.max_nm)))
        .collect();
    let hit = inputs
        .iter()
        .filter(|u| bounds.iter().any(|&(j, lo, hi)| u[j] <= lo + 1e-9 * lo.abs() || u[j] >= hi - 1e-9 * hi.abs()))
        .count();
    hit as f64 / inputs.len().max(1) as f64
}

/// Median and 99th percentile of `values`.
pub fn median_p99(values: &[f64]) -> (f64, f64) {
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.99))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_mostly_on_the_fallback_plan_is_no_mpc_figure() {
        // the share is "more than" MAX_FALLBACK_SHARE (10 %): 10 of 100 steps still describe the
        // MPC, 11 do not, and a run without steps describes nothing
        assert_eq!(fallback_verdict(10, 100), None);
        let why = fallback_verdict(11, 100).expect("11 % of the steps on the fallback plan");
        assert!(why.contains("11 of 100 steps (11 %)"), "{why}");
        assert!(fallback_verdict(0, 0).is_some());
    }
}
