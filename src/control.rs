//! `rigtwin mpc`: the closed loop of the MPC and of the PI baseline on the default rig, the
//! controller's timing and allocations, its first input against the exact optimum, and the
//! QPs for other solvers.

use mpc::closed_loop::{
    compare, median_p99, step_figures, Comparison, HarnessSettings, Plant, Probes, RigSignals, Scenario, ScenarioKind,
    StepFigures,
};
use mpc::qp::QpSnapshot;
use mpc::{Controller, MpcSettings, StepInfo};
use serde::Serialize;

/// How the closed loops are judged (`mpc::closed_loop::HarnessSettings`' documented defaults).
const HARNESS: HarnessSettings = HarnessSettings::DEFAULT;

pub use mpc::Prediction;

/// The prediction model of `params` (see [`Prediction`]); a drive model is refused.
pub fn prediction(params: &rigtwin_fmu::FmuParams) -> anyhow::Result<Prediction> {
    if params.drive.is_some() {
        anyhow::bail!("a drive model: the MPC runs on the paper rig's powertrain only (give a rig file)");
    }
    Ok(mpc::prediction::prediction(&params.powertrain, params.variant, &params.effects, 1e-3)?)
}

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

/// A figure of the MPC's run beside the PI baseline's (`None`: the model has no baseline; only
/// the paper rig's speed loops have one).
#[derive(Debug, Clone, Serialize)]
pub struct Compared<T> {
    /// With the MPC.
    pub mpc: T,
    /// With the PI speed loops.
    pub baseline: Option<T>,
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
        let outputs = |keep: &dyn Fn(&mpc::settings::OutputSettings) -> bool| {
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

/// The mean of the last 10 % of `values` (NaN when the run `stopped`).
fn final_mean(values: impl ExactSizeIterator<Item = f64>, stopped: bool) -> f64 {
    let n = values.len();
    let tail = (n / 10).max(1);
    if stopped || n == 0 {
        return f64::NAN;
    }
    values.skip(n - tail).sum::<f64>() / tail as f64
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
    /// The FMUs' units of `domain` (`rigtwin_fmu::variables::unit_of`).
    pub fn of(domain: plant::Domain) -> Units {
        use rigtwin_fmu::variables::unit_of;
        Units { speed: unit_of(plant::Dimension::Speed, domain), force: unit_of(plant::Dimension::Force, domain) }
    }
}

/// What `rigtwin mpc` prints, the same for every model (the paper rig against its PI baseline,
/// a drive model alone).
#[derive(Debug, Clone, Serialize)]
pub struct MpcReport {
    /// `paper_rig` or `drive_model`.
    pub model_kind: &'static str,
    /// Prediction horizon, steps of `dt_s`.
    pub horizon: usize,
    /// Sample time, s.
    pub dt_s: f64,
    /// QP formulation.
    pub formulation: mpc::Formulation,
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
    /// Largest number of heap allocations in one step after the first (`None`: not counted).
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
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep_peak_torque_deviation_nm: Option<Compared<f64>>,
}

/// The controller's real-time first input and its largest deviation from the exact optimum of
/// the same QP (solved to 1e-12): (max |u₀ − u₀*|, u₀).
fn first_input_error(c: &Controller) -> mpc::Result<(f64, Vec<f64>)> {
    let exact = c.exact_first_input()?;
    let rt = c.planned_first_input();
    let e = rt.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    Ok((e, rt))
}

/// Largest |value| of the columns `which` over the samples `rows`.
fn peak_abs(rows: &[Vec<f64>], which: &[usize]) -> f64 {
    rows.iter().flat_map(|y| which.iter().map(move |&j| y[j].abs())).fold(0.0, f64::max)
}

/// Move blocks as a person reads them: `1, 2, 4, 43` or `200 × 1` (runs of one length folded).
fn blocks_in_words(blocks: &[usize]) -> String {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for &b in blocks {
        match runs.last_mut() {
            Some((len, count)) if *len == b => *count += 1,
            _ => runs.push((b, 1)),
        }
    }
    let parts: Vec<String> = runs
        .iter()
        .map(
            |&(len, count)| {
                if count > 2 {
                    format!("{count} × {len}")
                } else {
                    vec![len.to_string(); count].join(", ")
                }
            },
        )
        .collect();
    format!("[{}] steps", parts.join(", "))
}

impl MpcReport {
    /// JSON with the verdict keys every `rigtwin mpc` document carries.
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = serde_json::to_value(self).expect("report serialises");
        if let Some(o) = v.as_object_mut() {
            if let Some(e) = o.remove("sweep_peak_torque_deviation_nm") {
                o.insert("sweep_peak_torque_deviation_Nm".into(), e);
            }
            let why = self.invalid();
            o.insert("verdict".into(), (if why.is_some() { "not_valid" } else { "valid" }).into());
            o.insert("not_valid_because".into(), why.into());
        }
        v
    }

    /// Why the figures do not describe the MPC, if they do not
    /// ([`mpc::closed_loop::fallback_verdict`]).
    pub fn invalid(&self) -> Option<String> {
        mpc::closed_loop::fallback_verdict(self.fallbacks, self.steps)
    }

    /// Text for the terminal.
    pub fn human(&self) -> String {
        let mut s = String::new();
        if let Some(why) = self.invalid() {
            s += &format!("NOT VALID: {why}\n");
        }
        let (speed, force) = (self.units.speed, self.units.force);
        let what = if self.model_kind == "paper_rig" { "the open-differential rig" } else { "the drive model" };
        s += &format!(
            "MPC on {what}: N = {} at {} ms, {} QP, move blocks {} → QP {} variables × {} constraints\n",
            self.horizon,
            self.dt_s * 1e3,
            crate::report::words(&self.formulation),
            blocks_in_words(&self.move_blocks),
            self.qp_variables,
            self.qp_constraints
        );
        let g = &self.signals;
        let list = |v: &[String]| if v.is_empty() { "nothing".to_string() } else { v.join(", ") };
        s += &format!(
            "  tracked {}; penalised {}; measured {}; |u| <= [{}] {force}\n",
            list(&g.tracked),
            list(&g.penalised),
            list(&g.measured),
            g.input_max.iter().map(|v| crate::units::significant(*v, 4)).collect::<Vec<_>>().join(", ")
        );
        s += &format!(
            "  designed on a model with effects: {}; closed on a plant with effects: {}\n",
            self.model_effects, self.plant_effects
        );
        for n in &self.prediction {
            s += &format!("  prediction: {n}\n");
        }
        let baseline = format!("PI ({} Hz speed loops)", HARNESS.pi_bandwidth_hz);
        for (who, why) in [("MPC", Some(&self.stopped.mpc)), (baseline.as_str(), self.stopped.baseline.as_ref())] {
            if let Some(Some(w)) = why {
                s += &format!("  {who} loop UNSTABLE: stopped {w}\n");
            }
        }
        let alloc = self.allocations_per_step.map_or("not counted".to_string(), |a| a.to_string());
        s += &format!(
            "  controller step ({} run): median {:.1} µs, p99 {:.1} µs, max {:.1} µs; {:.1} QP iterations; allocations per step: {alloc}; {} fallback(s) in {} steps\n",
            crate::report::words(&self.scenario),
            self.step_time_us.median,
            self.step_time_us.p99,
            self.step_time_us.max,
            self.qp_iterations_mean,
            self.fallbacks,
            self.steps
        );
        s += &match self.u0_error {
            Some(e) => format!(
                "  first input vs the exact optimum: max |u0 − u0*| = {e:.2e} {force} over {} steps\n",
                self.u0_checked_steps
            ),
            None => "  first input vs the exact optimum: not checked (every checked step fell back)\n".to_string(),
        };
        let r = &self.step_response;
        let (step_unit, stepped) = if r.stepped == "reference" {
            (speed, "the tracked speeds' references".to_string())
        } else {
            (force, r.stepped.clone())
        };
        s += &format!(
            "  step of {} {step_unit} in {stepped} at {} s, seen on {} (settling band ±{:.0} %):\n",
            crate::units::significant(r.step, 4),
            r.at_s,
            r.signal,
            r.settling_band * 100.0
        );
        s += &format!(
            "    {:<22} {:>9} {:>9} {:>10} {:>16} {:>17} {:>9}\n",
            "", "overshoot", "settling", "final", "RMS track. err.", "peak |pen. force|", "at bound"
        );
        let row = |who: &str, f: &StepFigures, end: f64, rms: f64, peak: f64, share: f64| {
            format!(
                "    {who:<22} {:>7.1} % {:>7.3} s {:>10} {:>16} {:>17} {:>7.1} %\n",
                f.overshoot * 100.0,
                f.settling_time_s,
                crate::units::significant(end, 4),
                format!("{rms:.4} {speed}"),
                format!("{peak:.2} {force}"),
                share * 100.0
            )
        };
        s += &row(
            "MPC",
            &r.figures.mpc,
            r.final_value.mpc,
            self.tracking_error_rms.mpc,
            self.peak_penalised_force.mpc,
            self.input_at_bound_share.mpc,
        );
        if let (Some(f), Some(end), Some(rms), Some(peak), Some(share)) = (
            &r.figures.baseline,
            r.final_value.baseline,
            self.tracking_error_rms.baseline,
            self.peak_penalised_force.baseline,
            self.input_at_bound_share.baseline,
        ) {
            s += &row(&baseline, f, end, rms, peak, share);
        }
        if let Some(p) = &self.sweep_peak_torque_deviation_nm {
            s += &format!(
                "  sweep: peak side-shaft torque deviation from half the drive torque: MPC {:.2} N·m, PI {:.2} N·m\n",
                p.mpc,
                p.baseline.unwrap_or(f64::NAN)
            );
        }
        s
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

fn run_on(
    prediction: &Prediction,
    truth: &rigtwin_fmu::FmuParams,
    settings: &MpcSettings,
    scenario: &Scenario,
    j_load: f64,
    probes: Probes<'_>,
) -> anyhow::Result<Comparison> {
    let ss = &prediction.model;
    let (_, u0) = mpc::closed_loop::steady_spin(ss, scenario.speed_radps)?;
    let mut make = |_: &nalgebra::DVector<f64>| -> Result<Box<dyn Plant>, String> {
        let (rig, speed) = (&truth.powertrain, scenario.speed_radps);
        let p =
            mpc::DrivePlant::paper_rig(rig, truth.variant, &truth.effects, settings.dt_s, speed, &u0, &ss.output_names)
                .map_err(|e| format!("the plant: {e}"))?;
        Ok(Box::new(p))
    };
    let pi_hz = HARNESS.pi_bandwidth_hz;
    compare(ss, &prediction.input_delays_s, &mut make, settings, scenario, j_load, pi_hz, probes)
        .map_err(|e| anyhow::anyhow!(e))
}

/// Runs the closed loops and measures. `allocations` reads the process's allocation counter
/// (the binary installs `mpc::alloc_counter::Counting`); `export` receives the QPs of the
/// checked steps.
pub fn report(
    params: &rigtwin_fmu::FmuParams,
    truth: &rigtwin_fmu::FmuParams,
    settings: &MpcSettings,
    kind: ScenarioKind,
    duration_s: Option<f64>,
    allocations: Option<fn() -> u64>,
    mut export: Option<&mut Vec<ExportedQp>>,
) -> anyhow::Result<(MpcReport, Comparison)> {
    let prediction = prediction(params)?;
    if truth.drive.is_some() {
        anyhow::bail!("--plant: a drive model; the closed loop runs on the paper rig's powertrain (give a rig file)");
    }
    let ss = &prediction.model;
    let sig = RigSignals::of(ss)?;
    let j_load = params.powertrain.effective(params.variant)?.j_m2;
    let mut scenario = Scenario::new(kind);
    if let Some(d) = duration_s {
        let longest = HARNESS.max_duration_s;
        if !(d.is_finite() && d > scenario.start_s && d <= longest) {
            anyhow::bail!(
                "--duration {d} s: expected more than the scenario's start {} s and at most {longest} s",
                scenario.start_s
            );
        }
        scenario.duration_s = d;
    }
    let mut u0_error: f64 = 0.0;
    let mut checked = 0;
    let mut failure: Option<String> = None;
    let mut hook = |k: usize, c: &Controller, info: &StepInfo| {
        if !k.is_multiple_of(HARNESS.check_every) || info.fallback {
            return;
        }
        match first_input_error(c) {
            Ok((e, rt)) => {
                u0_error = u0_error.max(e);
                checked += 1;
                if let Some(list) = export.as_deref_mut() {
                    list.push(ExportedQp {
                        qp: c.snapshot(),
                        clarabel_u0_nm: rt,
                        clarabel_solve_time_us: info.elapsed_s * 1e6,
                    });
                }
            }
            Err(e) => failure = Some(e.to_string()),
        }
    };
    let run =
        run_on(&prediction, truth, settings, &scenario, j_load, Probes { allocations, after_step: Some(&mut hook) })?;
    if let Some(f) = failure {
        anyhow::bail!("reference solve of the exact optimum failed: {f}");
    }
    let step = if kind == ScenarioKind::Step && duration_s.is_none() {
        run.clone()
    } else {
        run_on(&prediction, truth, settings, &Scenario::new(ScenarioKind::Step), j_load, Probes::default())?
    };
    let k_step = (Scenario::new(ScenarioKind::Step).start_s / settings.dt_s).round() as usize;
    let fig = |t: &mpc::closed_loop::Trace| {
        if t.stopped.is_some() {
            StepFigures { overshoot: f64::NAN, settling_time_s: f64::NAN }
        } else {
            step_figures(&t.output(sig.short_shaft), k_step, settings.dt_s, HARNESS.settling_band)
        }
    };
    let at_bounds =
        |t: &mpc::closed_loop::Trace| mpc::closed_loop::share_at_bounds(&t.inputs, settings, &ss.input_names);
    let speed_rms = |t: &mpc::closed_loop::Trace| {
        if t.stopped.is_some() {
            return f64::NAN;
        }
        let n = t.outputs.len() as f64;
        (t.outputs
            .iter()
            .map(|y| {
                (y[sig.speeds[0]] - scenario.speed_radps).powi(2) + (y[sig.speeds[2]] - scenario.speed_radps).powi(2)
            })
            .sum::<f64>()
            / (2.0 * n))
            .sqrt()
    };
    let sweep_dev = |t: &mpc::closed_loop::Trace| {
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
    let penalised: Vec<usize> =
        signals.penalised.iter().filter_map(|n| ss.output_names.iter().position(|o| o == n)).collect();
    let both =
        |f: &dyn Fn(&mpc::closed_loop::Trace) -> f64| Compared { mpc: f(&step.mpc), baseline: Some(f(&step.baseline)) };
    let times_us: Vec<f64> = run.step_times_s.iter().map(|t| t * 1e6).collect();
    let (median, p99) = median_p99(&times_us);
    let step_scenario = Scenario::new(ScenarioKind::Step);
    let rep = MpcReport {
        model_kind: "paper_rig",
        horizon: settings.horizon,
        dt_s: settings.dt_s,
        formulation: settings.formulation,
        move_blocks: settings.blocks(),
        qp_variables: run.qp_size.0,
        qp_constraints: run.qp_size.1,
        scenario: kind,
        step_time_us: Timing { median, p99, max: times_us.iter().copied().fold(0.0, f64::max) },
        qp_iterations_mean: run.iterations.iter().map(|&i| i as f64).sum::<f64>() / run.iterations.len().max(1) as f64,
        allocations_per_step: allocations.map(|_| run.step_allocations.iter().skip(1).copied().max().unwrap_or(0)),
        allocations_first_step: allocations.map(|_| run.step_allocations.first().copied().unwrap_or(0)),
        fallbacks: run.fallbacks,
        steps: run.step_times_s.len(),
        u0_error: (checked > 0).then_some(u0_error),
        u0_checked_steps: checked,
        step_response: StepResponse {
            stepped: ss.input_names[sig.inputs[1]].clone(),
            step: step_scenario.torque_nm,
            at_s: step_scenario.start_s,
            signal: ss.output_names[sig.short_shaft].clone(),
            settling_band: HARNESS.settling_band,
            figures: Compared { mpc: fig(&step.mpc), baseline: Some(fig(&step.baseline)) },
            final_value: both(&|t| final_mean(t.outputs.iter().map(|y| y[sig.short_shaft]), t.stopped.is_some())),
        },
        tracking_error_rms: Compared { mpc: speed_rms(&run.mpc), baseline: Some(speed_rms(&run.baseline)) },
        peak_penalised_force: both(&|t| peak_abs(&t.outputs, &penalised)),
        input_at_bound_share: both(&at_bounds),
        stopped: Compared { mpc: step.mpc.stopped.clone(), baseline: Some(step.baseline.stopped.clone()) },
        signals,
        prediction: prediction.notes.clone(),
        plant_effects: truth.effects.in_words(),
        model_effects: params.effects.in_words(),
        units: Units::of(plant::Domain::Rotational),
        sweep_peak_torque_deviation_nm: (kind == ScenarioKind::Sweep)
            .then(|| Compared { mpc: sweep_dev(&run.mpc), baseline: Some(sweep_dev(&run.baseline)) }),
    };
    Ok((rep, run))
}

/// SVG: side-shaft torque, load speed and the MPC's inputs over time.
pub fn plot(
    target: &crate::files::Target,
    params: &rigtwin_fmu::FmuParams,
    run: &Comparison,
    kind: ScenarioKind,
) -> anyhow::Result<()> {
    use crate::plot::{lines, Panel};
    let ss = prediction(params)?.model;
    let sig = RigSignals::of(&ss)?;
    let series = |t: &mpc::closed_loop::Trace, j: usize| {
        t.time_s.iter().zip(&t.outputs).map(|(&x, y)| (x, y[j])).collect::<Vec<_>>()
    };
    let input = |t: &mpc::closed_loop::Trace, j: usize| {
        t.time_s.iter().zip(&t.inputs).map(|(&x, u)| (x, u[j])).collect::<Vec<_>>()
    };
    let panels = vec![
        Panel {
            title: "short side-shaft torque".into(),
            x_desc: "time [s]".into(),
            y_desc: "T_short_side_shaft [Nm]".into(),
            log_y: false,
            series: vec![
                ("MPC".into(), series(&run.mpc, sig.short_shaft)),
                ("PI baseline".into(), series(&run.baseline, sig.short_shaft)),
            ],
        },
        Panel {
            title: "load machine M2 speed".into(),
            x_desc: "time [s]".into(),
            y_desc: "w_m2 [rad/s]".into(),
            log_y: false,
            series: vec![
                ("MPC".into(), series(&run.mpc, sig.speeds[0])),
                ("PI baseline".into(), series(&run.baseline, sig.speeds[0])),
            ],
        },
        Panel {
            title: "machine torques with MPC".into(),
            x_desc: "time [s]".into(),
            y_desc: "torque [Nm]".into(),
            log_y: false,
            series: vec![
                ("M_m2".into(), input(&run.mpc, sig.inputs[0])),
                ("M_drive".into(), input(&run.mpc, sig.inputs[1])),
                ("M_m3".into(), input(&run.mpc, sig.inputs[2])),
            ],
        },
    ];
    lines(target, &format!("rigtwin mpc: {} scenario, MPC vs PI speed control", crate::report::words(&kind)), &panels)
}

/// The command line's choices for the controller, applied alike to every model's settings.
#[derive(Debug, Clone, Copy)]
pub struct Tuning {
    /// Number of move blocks (`mpc::exponential_blocks`); 0: every step free.
    pub blocks: usize,
    /// QP formulation.
    pub formulation: mpc::Formulation,
    /// The real-time QP's time limit, s.
    pub time_limit_s: f64,
}

impl Tuning {
    /// Applies the choices to `s` and checks the result.
    pub fn apply(&self, s: &mut MpcSettings) -> anyhow::Result<()> {
        s.move_blocks = if self.blocks == 0 { Vec::new() } else { mpc::exponential_blocks(s.horizon, self.blocks) };
        s.formulation = self.formulation;
        s.solver.time_limit_s = self.time_limit_s;
        s.validate().map_err(|e| anyhow::anyhow!("--horizon/--blocks/--time-limit-us: {e}"))
    }
}

/// The MPC of a drive model with its `[mpc]` section, in closed loop on `truth` (as the FMU
/// integrates it) from rest: every tracked speed's reference steps by `step` at 0.05 s (tracked
/// inputs' references stay 0), for 1 s. The first input is checked against the exact optimum
/// every `HarnessSettings::check_every` steps and the allocations counted, as for the paper rig.
pub fn drive_report(
    model: &plant::DriveModel,
    truth: &plant::DriveModel,
    section: &mpc::MpcSection,
    horizon: usize,
    tuning: &Tuning,
    step: f64,
    allocations: Option<fn() -> u64>,
) -> anyhow::Result<(MpcReport, DriveRun)> {
    let (p, mut settings) = mpc::Design::Drive(model).controller(section, horizon)?;
    tuning.apply(&mut settings)?;
    let (ss, delays, prediction) = (p.model, p.input_delays_s, p.notes);
    if truth.input_names() != model.input_names() || truth.coupling_force_names() != model.coupling_force_names() {
        anyhow::bail!("--plant: its bodies and inputs differ from the model's");
    }
    let mut controller = mpc::Controller::with_input_delays(&ss, &delays, &settings)?;
    let names = controller.reference_names();
    let x0 = nalgebra::DVector::zeros(ss.nstates());
    let u0 = vec![0.0; ss.input_names.len()];
    controller.reset(&x0, &u0);
    let mut plant = mpc::DrivePlant::new(truth, settings.dt_s, &ss.output_names)?;
    let dt = settings.dt_s;
    let samples = (1.0 / dt).round() as usize;
    let k_step = (0.05 / dt).round() as usize;
    let tracked: Vec<usize> = names.iter().filter_map(|n| ss.output_names.iter().position(|o| o == n)).collect();
    let signals = Signals::of(&settings, &model.coupling_force_names());
    let penalised: Vec<usize> =
        signals.penalised.iter().filter_map(|n| ss.output_names.iter().position(|o| o == n)).collect();
    let (mut trace, mut times) = (Vec::with_capacity(samples), Vec::with_capacity(samples));
    let (mut inputs, mut iterations, mut allocs) =
        (Vec::with_capacity(samples), Vec::with_capacity(samples), Vec::with_capacity(samples));
    let mut stopped = None;
    let (mut u0_error, mut checked) = (0.0f64, 0);
    let mut r = vec![0.0; names.len()];
    for k in 0..samples {
        let y = plant.outputs().to_vec();
        for (i, n) in names.iter().enumerate() {
            r[i] = if k >= k_step && ss.output_names.contains(n) { step } else { 0.0 };
        }
        let before = allocations.map(|f| f());
        let (u, info) = controller.step(&y, &r);
        if let (Some(f), Some(b)) = (allocations, before) {
            allocs.push(f() - b);
        }
        let (u, fallback) = (u.to_vec(), info.fallback);
        times.push(info.elapsed_s * 1e6);
        iterations.push(info.solve.iterations as f64);
        if k.is_multiple_of(HARNESS.check_every) && !fallback {
            let (e, _) = first_input_error(&controller)
                .map_err(|e| anyhow::anyhow!("reference solve of the exact optimum failed: {e}"))?;
            u0_error = u0_error.max(e);
            checked += 1;
        }
        trace.push(y);
        inputs.push(u.clone());
        if let Err(e) = mpc::closed_loop::advance(&mut plant, &u) {
            stopped = Some(format!("at {:.4} s: {e}", k as f64 * dt));
            break;
        }
    }
    let response = match (tracked.first(), &stopped) {
        (Some(&j), None) => {
            step_figures(&trace.iter().map(|y| y[j]).collect::<Vec<_>>(), k_step, dt, HARNESS.settling_band)
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
    let (median, p99) = median_p99(&times);
    let input_at_bound_share = mpc::closed_loop::share_at_bounds(&inputs, &settings, &ss.input_names);
    let effects = |m: &plant::DriveModel| {
        let named = crate::report::effects_at(m);
        if named.is_empty() {
            "none".to_string()
        } else {
            named.join(", ")
        }
    };
    let report = MpcReport {
        model_kind: "drive_model",
        horizon,
        dt_s: dt,
        formulation: settings.formulation,
        move_blocks: settings.blocks(),
        qp_variables: controller.qp().nvars(),
        qp_constraints: controller.qp().nrows(),
        scenario: ScenarioKind::Step,
        step_time_us: Timing { median, p99, max: times.iter().copied().fold(0.0, f64::max) },
        qp_iterations_mean: iterations.iter().sum::<f64>() / iterations.len().max(1) as f64,
        allocations_per_step: allocations.map(|_| allocs.iter().skip(1).copied().max().unwrap_or(0)),
        allocations_first_step: allocations.map(|_| allocs.first().copied().unwrap_or(0)),
        fallbacks: controller.fallbacks(),
        steps: times.len(),
        u0_error: (checked > 0).then_some(u0_error),
        u0_checked_steps: checked,
        step_response: StepResponse {
            stepped: "reference".into(),
            step,
            at_s: k_step as f64 * dt,
            signal: tracked.first().map_or("nothing tracked".into(), |&j| ss.output_names[j].clone()),
            settling_band: HARNESS.settling_band,
            figures: Compared { mpc: response, baseline: None },
            final_value: Compared {
                mpc: tracked.first().map_or(f64::NAN, |&j| final_mean(trace.iter().map(|y| y[j]), stopped.is_some())),
                baseline: None,
            },
        },
        tracking_error_rms: Compared { mpc: tracking_error_rms, baseline: None },
        peak_penalised_force: Compared { mpc: peak_abs(&trace, &penalised), baseline: None },
        input_at_bound_share: Compared { mpc: input_at_bound_share, baseline: None },
        stopped: Compared { mpc: stopped, baseline: None },
        signals,
        prediction,
        plant_effects: effects(truth),
        model_effects: effects(model),
        units: Units::of(model.line.domain),
        sweep_peak_torque_deviation_nm: None,
    };
    let run = DriveRun {
        time_s: (0..trace.len()).map(|k| k as f64 * dt).collect(),
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

/// A drive model's closed-loop run: what `rigtwin mpc --plot` draws.
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

/// Draws a drive model's run: tracked outputs with their reference, penalised forces, inputs.
pub fn plot_drive(target: &crate::files::Target, run: &DriveRun, domain: plant::Domain) -> anyhow::Result<()> {
    use crate::plot::{lines, Panel};
    let speed = crate::units::quantity_unit(plant::Quantity::Speed, domain);
    let force = crate::units::quantity_unit(plant::Quantity::CouplingForce, domain);
    let of = |rows: &[Vec<f64>], j: usize| run.time_s.iter().zip(rows).map(|(&t, y)| (t, y[j])).collect::<Vec<_>>();
    let reference: Vec<(f64, f64)> =
        run.time_s.iter().map(|&t| (t, if t >= run.step_at_s { run.reference } else { 0.0 })).collect();
    let mut tracked: Vec<(String, Vec<(f64, f64)>)> =
        run.tracked.iter().map(|&j| (run.output_names[j].clone(), of(&run.outputs, j))).collect();
    tracked.push(("reference".into(), reference));
    let mut panels = vec![Panel {
        title: "tracked outputs and their reference".into(),
        x_desc: "time [s]".into(),
        y_desc: format!("speed [{speed}]"),
        log_y: false,
        series: tracked,
    }];
    if !run.penalised.is_empty() {
        panels.push(Panel {
            title: "penalised coupling forces".into(),
            x_desc: "time [s]".into(),
            y_desc: format!("force [{force}]"),
            log_y: false,
            series: run.penalised.iter().map(|&j| (run.output_names[j].clone(), of(&run.outputs, j))).collect(),
        });
    }
    panels.push(Panel {
        title: "inputs (MPC commands)".into(),
        x_desc: "time [s]".into(),
        y_desc: format!("input [{force}]"),
        log_y: false,
        series: (0..run.input_names.len()).map(|j| (run.input_names[j].clone(), of(&run.inputs, j))).collect(),
    });
    lines(target, "rigtwin mpc: reference step on the drive model", &panels)
}

/// The `[mpc]` section the controller of `file` (read as `model`) is designed with: the file's
/// own; for a `drive_test` bundle without `input_max`, the record's peak |input| as the bounds
/// (`mpc::MpcSection::bound_by_record`), with a note saying so.
pub fn section_of(
    file: &std::path::Path,
    model: &modelfile::ModelFile,
) -> anyhow::Result<(mpc::MpcSection, Option<String>)> {
    let mut section = model.mpc.clone();
    if model.kind.as_deref() != Some("drive_test") || section.input_max.is_some() {
        return Ok((section, None));
    }
    let b = crate::bundle::load_drive_test(file)?;
    section.bound_by_record(&b.input_data);
    let bounds: Vec<String> =
        b.inputs.iter().zip(section.input_max.iter().flatten()).map(|(s, v)| format!("{} {v:.4}", s.column)).collect();
    Ok((
        section,
        Some(format!(
            "note: {} has no [mpc] input_max: the inputs are bounded by the record's peaks ({}); give the actuators' limits in [mpc] input_max",
            file.display(),
            bounds.join(", ")
        )),
    ))
}
