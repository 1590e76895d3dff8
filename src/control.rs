//! `rigtwin mpc`'s words and drawings: the report of `mpc::evaluation` as text, the closed
//! loops as SVG, the command line's choices for the controller, and the `[mpc]` section a
//! model file's controller is designed with.

use mpc::closed_loop::{Comparison, RigSignals, ScenarioKind, StepFigures};
use mpc::evaluation::{DriveRun, MpcReport};
use mpc::MpcSettings;

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

/// `report` as text for the terminal.
pub fn human(report: &MpcReport) -> String {
    let mut s = String::new();
    if let Some(why) = report.invalid() {
        s += &format!("NOT VALID: {why}\n");
    }
    let (speed, force) = (report.units.speed, report.units.force);
    let what = if report.model_kind == "paper_rig" { "the open-differential rig" } else { "the drive model" };
    s += &format!(
        "MPC on {what}: N = {} at {} ms, {} QP, move blocks {} → QP {} variables × {} constraints\n",
        report.horizon,
        report.dt_s * 1e3,
        crate::report::words(&report.formulation),
        blocks_in_words(&report.move_blocks),
        report.qp_variables,
        report.qp_constraints
    );
    let g = &report.signals;
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
        report.model_effects, report.plant_effects
    );
    for n in &report.prediction {
        s += &format!("  prediction: {n}\n");
    }
    let baseline = format!("PI ({} Hz speed loops)", report.harness.pi_bandwidth_hz);
    for (who, why) in [("MPC", Some(&report.stopped.mpc)), (baseline.as_str(), report.stopped.baseline.as_ref())] {
        if let Some(Some(w)) = why {
            s += &format!("  {who} loop UNSTABLE: stopped {w}\n");
        }
    }
    let alloc = report.allocations_per_step.map_or("not counted".to_string(), |a| a.to_string());
    s += &format!(
        "  controller step ({} run): median {:.1} µs, p99 {:.1} µs, max {:.1} µs; {:.1} QP iterations; allocations per step: {alloc} (first step and first solve aside); {} fallback(s) in {} steps\n",
        crate::report::words(&report.scenario),
        report.step_time_us.median,
        report.step_time_us.p99,
        report.step_time_us.max,
        report.qp_iterations_mean,
        report.fallbacks,
        report.steps
    );
    s += &match report.u0_error {
        Some(e) => format!(
            "  first input vs the exact optimum: max |u0 − u0*| = {e:.2e} {force} over {} steps\n",
            report.u0_checked_steps
        ),
        None => "  first input vs the exact optimum: not checked (every checked step fell back)\n".to_string(),
    };
    let r = &report.step_response;
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
        report.tracking_error_rms.mpc,
        report.peak_penalised_force.mpc,
        report.input_at_bound_share.mpc,
    );
    if let (Some(f), Some(end), Some(rms), Some(peak), Some(share)) = (
        &r.figures.baseline,
        r.final_value.baseline,
        report.tracking_error_rms.baseline,
        report.peak_penalised_force.baseline,
        report.input_at_bound_share.baseline,
    ) {
        s += &row(&baseline, f, end, rms, peak, share);
    }
    if let Some(p) = &report.sweep_peak_torque_deviation_nm {
        s += &format!(
            "  sweep: peak side-shaft torque deviation from half the drive torque: MPC {:.2} N·m, PI {:.2} N·m\n",
            p.mpc,
            p.baseline.unwrap_or(f64::NAN)
        );
    }
    s
}

/// SVG: side-shaft torque, load speed and the MPC's inputs over time.
pub fn plot(
    target: &crate::files::Target,
    prediction: &mpc::Prediction,
    run: &Comparison,
    kind: ScenarioKind,
) -> anyhow::Result<()> {
    use crate::plot::{lines, Panel};
    let sig = RigSignals::of(&prediction.model)?;
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

/// The model file `file`, read once, with the `[mpc]` section its controller is designed with:
/// the file's own; for a `drive_test` bundle without `input_max`, the record's peak |input| as
/// the bounds (`mpc::MpcSection::bound_by_record`), with a note saying so.
pub fn read_model(file: &std::path::Path) -> anyhow::Result<(modelfile::ModelFile, Option<String>)> {
    let text = crate::files::read_text(file).map_err(|e| anyhow::anyhow!("{e}"))?;
    let parsed = modelfile::parse(&text, file)?;
    if parsed.kind.as_deref() != Some("drive_test") || parsed.mpc.input_max.is_some() {
        return Ok((parsed, None));
    }
    let b = crate::bundle::drive_test_of(&text, file)?;
    let mut mpc = b.mpc;
    mpc.bound_by_record(&b.input_data);
    let bounds: Vec<String> =
        b.inputs.iter().zip(mpc.input_max.iter().flatten()).map(|(s, v)| format!("{} {v:.4}", s.column)).collect();
    let note = format!(
        "note: {} has no [mpc] input_max: the inputs are bounded by the record's peaks ({}); give the actuators' limits in [mpc] input_max",
        file.display(),
        bounds.join(", ")
    );
    Ok((modelfile::ModelFile { mpc, ..parsed }, Some(note)))
}
