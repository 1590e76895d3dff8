//! `rigtwin mpc` end to end: the JSON contract, the controller against the FMU (through the
//! `fmi` crate) instead of plant's matrices, and the QPs solved by OSQP and DAQP.

mod common;

use std::process::Command;

use fmi::fmi3::import::Fmi3Import;
use fmi::fmi3::{CoSimulation, Common, Fmi3Model, GetSet};
use mpc::closed_loop::{compare, LinearPlant, Plant, Probes, RigSignals, Scenario, ScenarioKind};
use mpc::MpcSettings;

use common::vr;

fn rigtwin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).output().unwrap()
}

/// Every key path of a JSON document, objects only (the value `null` and a nested object count
/// as the same shape: `null` stands for a figure the model does not have).
fn keys(v: &serde_json::Value) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(o) = v.as_object() {
        for (k, x) in o {
            out.push(k.clone());
            if x.is_object() && x.as_object().unwrap().keys().all(|n| n != "mpc") {
                out.extend(keys(x).into_iter().map(|s| format!("{k}.{s}")));
            }
        }
    }
    out.sort();
    out
}

/// The contract's keys, and figures checked against what is known without the controller:
/// the PI baseline settles on the open differential's static split (the side shaft ends at
/// 20 Nm whichever controller), the MPC damps the shuffle better than the PI loops, the first
/// input is within the 1e-2 Nm of the exact optimum.
#[test]
fn json_contract_and_figures() {
    // a generous time limit: the figures must not depend on how loaded the test machine is
    let out = rigtwin(&["mpc", "--json", "--horizon", "50", "--time-limit-us", "100000"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["horizon"], 50);
    for key in ["median", "p99"] {
        assert!(v["step_time_us"][key].as_f64().unwrap() > 0.0);
    }
    assert!(v["allocations_per_step"].as_u64().is_some());
    assert_eq!(v["units"]["force"], "N.m");
    let u0 = v["u0_error"].as_f64().unwrap();
    assert!(u0 < 1e-2, "u0 error {u0} Nm");
    let r = &v["step_response"];
    assert_eq!(r["stepped"], "M_drive");
    // the open differential splits the drive torque's 40 N·m step in half, whoever controls
    for who in ["mpc", "baseline"] {
        let end = r["final_value"][who].as_f64().unwrap();
        assert!((end - 20.0).abs() < 0.2, "{who}: the short side shaft ends at {end} N·m");
    }
    let (m, b) = (&r["figures"]["mpc"], &r["figures"]["baseline"]);
    let f = |x: &serde_json::Value, k: &str| x[k].as_f64().unwrap();
    assert!(f(m, "overshoot") < 0.5 * f(b, "overshoot"), "{m} vs {b}");
    assert!(f(m, "settling_time_s") < 0.5 * f(b, "settling_time_s"), "{m} vs {b}");

    // a drive model's document has the same keys, with null where it has no PI baseline
    let out =
        rigtwin(&["mpc", "--params", "examples/gear_bench/bench.toml", "--json", "-", "--time-limit-us", "100000"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let d: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(keys(&d), keys(&v), "one shape for the paper rig and a drive model");
    assert_eq!((&d["model_kind"], &v["model_kind"]), (&"drive_model".into(), &"paper_rig".into()));
    assert!(d["step_response"]["figures"]["baseline"].is_null() && d["u0_error"].as_f64().unwrap() < 1e-2, "{d}");

    let bad = rigtwin(&["mpc", "--horizon", "0"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("horizon"));
}

/// The FMU as the plant (FMI 3 co-simulation, 1 ms steps through the `fmi` crate).
struct FmuPlant {
    inst: fmi::fmi3::instance::InstanceCS,
    t: f64,
    y: Vec<f64>,
    outputs: [u32; 5],
    inputs: [u32; 3],
}

impl FmuPlant {
    fn new(x0: &nalgebra::DVector<f64>, names: &[String]) -> Self {
        let import: &'static Fmi3Import =
            Box::leak(Box::new(fmi::import::from_path(common::fmu_dir().join("rigtwin-fmi3.fmu")).unwrap()));
        let mut inst = import.instantiate_cs("rig", false, true, false, false, &[]).unwrap();
        // plant's state [φ_m2, φ_drive, φ_m3, speeds] as the FMU's [φ_m2, twist, φ_m3, speeds]
        let twist = 2.0 * x0[1] - x0[0] - x0[2];
        let states = [("phi_m2", x0[0]), ("twist", twist), ("phi_m3", x0[2])];
        for (s, v) in states.into_iter().chain(["w_m2", "w_drive", "w_m3"].into_iter().zip(x0.iter().skip(3).copied()))
        {
            inst.set_float64(&[vr(s)], &[v]).unwrap();
        }
        inst.enter_initialization_mode(None, 0.0, None).unwrap();
        inst.exit_initialization_mode().unwrap();
        // plant's output order: w_m2, w_drive, w_m3, T_short_side_shaft, T_long_side_shaft
        assert_eq!(names[3], "T_short_side_shaft");
        let outputs = [vr("w_m2"), vr("w_drive"), vr("w_m3"), vr("T_short"), vr("T_long")];
        let mut p =
            FmuPlant { inst, t: 0.0, y: vec![0.0; 5], outputs, inputs: [vr("M_m2"), vr("M_drive"), vr("M_m3")] };
        p.read();
        p
    }
    fn read(&mut self) {
        self.inst.get_float64(&self.outputs, &mut self.y).unwrap();
    }
}

impl Plant for FmuPlant {
    fn outputs(&self) -> &[f64] {
        &self.y
    }
    fn advance(&mut self, u: &[f64]) -> Result<(), String> {
        self.inst.set_float64(&self.inputs, u).map_err(|e| format!("{e:?}"))?;
        let (mut ev, mut term, mut early, mut last) = (false, false, false, 0.0);
        self.inst
            .do_step(self.t, 1e-3, true, &mut ev, &mut term, &mut early, &mut last)
            .map_err(|e| format!("{e:?}"))?;
        self.t += 1e-3;
        self.read();
        Ok(())
    }
}

/// Closed loop against the FMU equals the closed loop against plant's ZOH matrices: both are
/// exact for inputs held over the step, so the controller sees the same outputs (to the
/// round-off of two matrix exponentials) and answers the same. 1e-6 rad/s and 1e-4 Nm leave
/// room for the interior-point solver's sensitivity to 1e-12 differences in its data.
#[test]
fn closed_loop_with_the_fmu_matches_the_plant() {
    let params = rigtwin_fmu::RigPlant::default();
    let design = mpc::Design::Rig { rig: &params.powertrain, variant: params.variant, effects: &params.effects };
    let ss = design.prediction(1e-3).unwrap().model;
    let sig = RigSignals::of(&ss).unwrap();
    let mut settings = MpcSettings::powertrain(50);
    settings.solver.time_limit_s = 1.0; // identical solves in both runs, whatever the clock
    let scenario = Scenario { duration_s: 0.4, ..Scenario::new(ScenarioKind::Step) };
    let j_load = params.powertrain.effective(params.variant).unwrap().j_m2;
    let names = ss.output_names.clone();
    let mut fmu =
        |x0: &nalgebra::DVector<f64>| -> Result<Box<dyn Plant>, String> { Ok(Box::new(FmuPlant::new(x0, &names))) };
    let with_fmu = compare(&ss, &[], &mut fmu, &settings, &scenario, j_load, 5.0, Probes::default()).unwrap();
    let mut lin = |x0: &nalgebra::DVector<f64>| -> Result<Box<dyn Plant>, String> {
        Ok(Box::new(LinearPlant::new(&ss, 1e-3, x0).map_err(|e| e.to_string())?))
    };
    let with_plant = compare(&ss, &[], &mut lin, &settings, &scenario, j_load, 5.0, Probes::default()).unwrap();
    for (a, b) in with_fmu.mpc.outputs.iter().zip(&with_plant.mpc.outputs) {
        for &j in &sig.speeds {
            assert!((a[j] - b[j]).abs() < 1e-6, "speed {j}: FMU {} vs plant {}", a[j], b[j]);
        }
        assert!((a[sig.short_shaft] - b[sig.short_shaft]).abs() < 1e-4);
    }
    // and the loop did something: the side shaft went from 0 to the 20 Nm static split
    let last = with_fmu.mpc.outputs.last().unwrap()[sig.short_shaft];
    assert!((last - 20.0).abs() < 0.05, "T_short at the end {last}");
}

/// The same QPs solved by DAQP (an active-set solver, exact to round-off) and OSQP: rigtwin's
/// real-time Clarabel first input is within the 1e-2 Nm of DAQP's.
#[test]
fn osqp_and_daqp_solve_the_same_qps() {
    let dir = common::scratch("mpc", "qps");
    let (qps, rep) = (dir.join("qps.json"), dir.join("compare.json"));
    let out = rigtwin(&["mpc", "--export-qp", qps.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/qp_compare.py");
    let out = Command::new(common::python()).arg(script).arg(&qps).arg(&rep).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    let e = v["clarabel"]["u0_error_Nm"].as_f64().unwrap();
    assert!(e < 1e-2, "Clarabel's first input {e} Nm from DAQP's");
    assert!(v["osqp"]["median_us"].as_f64().unwrap() > 0.0 && v["daqp"]["median_us"].as_f64().unwrap() > 0.0);
}

/// Issue 16, items 3 and 4: the controller as an FMU. `rigtwin fmu --controller` and `rigtwin
/// fmu` write the controller and plant FMUs of a rig with a 4.3 ms drive dead time; fmpy
/// validates the controller FMUs and fmutool checks them, and a small fmpy master
/// (`tests/closed_loop_fmus.py`) closes the loop FMI 3 with FMI 3 and FMI 2 with FMI 2. The
/// speeds and commands match the in-process closed loop (the controller assembled as `rigtwin
/// mpc` assembles it, the plant as the FMU integrates it) to the 1e-6.
#[test]
fn controller_fmu_closes_the_loop_in_fmpy() {
    let dir = common::scratch("mpc", "ctrl-fmu");
    let rig = dir.join("rig.toml");
    let paper = include_str!("../rigs/paper.toml");
    std::fs::write(&rig, format!("{paper}\n[effects]\ntime_delay_s = 0.0043\n")).unwrap();
    let (plant_dir, ctrl_dir) = (dir.join("plant"), dir.join("controller"));
    for (args, out) in [(vec!["fmu"], &plant_dir), (vec!["fmu", "--controller"], &ctrl_dir)] {
        let mut a = args.clone();
        a.extend(["--params", rig.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let o = rigtwin(&a);
        assert!(o.status.success(), "{a:?}: {}", String::from_utf8_lossy(&o.stderr));
    }

    // the in-process loop: the command of each point applied at once (`delayed` false), or
    // from the next point on (a Jacobi master's sample of computational delay)
    let params = rigtwin::fmu_package::params_of_file(&rig).unwrap();
    let params = params.plant.rig().expect("a rig file");
    let design = mpc::Design::Rig { rig: &params.powertrain, variant: params.variant, effects: &params.effects };
    let p = design.prediction(1e-3).unwrap();
    let mut settings = MpcSettings::powertrain(50);
    settings.solver.time_limit_s = 1.0;
    let speed = 10.0;
    let (x0, u0) = mpc::closed_loop::steady_spin(&p.model, speed).unwrap();
    let (steps, step_at) = (400, 50);
    let in_process = |delayed: bool| -> Vec<[f64; 6]> {
        let mut c = mpc::Controller::with_input_delays(&p.model, &p.input_delays_s, &settings).unwrap();
        c.reset(&x0, &u0);
        let (rig, effects, names) = (&params.powertrain, &params.effects, &p.model.output_names);
        let mut plant =
            mpc::DrivePlant::paper_rig(rig, params.variant, effects, settings.dt_s, speed, &u0, names).unwrap();
        let mut rows = Vec::new();
        let mut previous: Option<Vec<f64>> = None;
        for k in 0..steps {
            let y = plant.outputs().to_vec();
            let r = [speed, speed, if k >= step_at { 40.0 } else { 0.0 }];
            let u = c.step(&y, &r).0.to_vec();
            let applied = if delayed { previous.clone().unwrap_or_else(|| u.clone()) } else { u.clone() };
            rows.push([y[0], y[1], y[2], applied[0], applied[1], applied[2]]);
            plant.advance(&applied).unwrap();
            previous = Some(u);
        }
        rows
    };
    let rows = in_process(false);

    let start = serde_json::json!({
        "plant": {"w_m2": speed, "w_drive": speed, "w_m3": speed, "M_m2": u0[0], "M_drive": u0[1], "M_m3": u0[2]},
        "controller": {"mpc.time_limit": 1.0},
        "references": {"w_m2_ref": speed, "w_m3_ref": speed, "M_drive_ref": 0.0},
        "step_at": step_at, "step": {"M_drive_ref": 40.0},
    });
    let rows: Vec<Vec<f64>> = rows.iter().map(|r| r.to_vec()).collect();
    let delayed: Vec<Vec<f64>> = in_process(true).iter().map(|r| r.to_vec()).collect();
    check_fmus_against(&dir, &plant_dir, &ctrl_dir, &start, steps, 3, &rows, &delayed);
    let last = rows.last().unwrap();
    assert!((last[4] - 40.0).abs() < 1.0, "the drive torque followed its step: {last:?}");
}

/// Runs `tests/closed_loop_fmus.py` on the plant and controller FMUs of `plant_dir` and
/// `ctrl_dir` (with the SSP the controller's export wrote) from `start` for `steps` points, and
/// compares every master's rows (the `measured` plant outputs, then the applied commands) with
/// the in-process loop's: `rows` for fmpy's Gauss-Seidel master (FMI 3 and FMI 2, both FMUs
/// validated by fmpy and checked by fmutool), `delayed` (the command one sample late) for OSP
/// libcosim's Jacobi master on the SSP.
#[allow(clippy::too_many_arguments)]
fn check_fmus_against(
    dir: &std::path::Path,
    plant_dir: &std::path::Path,
    ctrl_dir: &std::path::Path,
    start: &serde_json::Value,
    steps: usize,
    measured: usize,
    rows: &[Vec<f64>],
    delayed: &[Vec<f64>],
) {
    let start_file = dir.join("start.json");
    std::fs::write(&start_file, start.to_string()).unwrap();
    let report = dir.join("report.json");
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/closed_loop_fmus.py");
    let out = Command::new(common::python())
        .arg(script)
        .args([plant_dir, ctrl_dir, &start_file])
        .arg(steps.to_string())
        .arg(&report)
        .arg(ctrl_dir.join("rigtwin-closed-loop.ssp"))
        .output()
        .unwrap();
    assert!(out.status.success(), "closed_loop_fmus.py: {}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let compare = |got: &[serde_json::Value], rows: &[Vec<f64>], what: &str| {
        assert_eq!(got.len(), rows.len());
        let (mut speed_err, mut command_err): (f64, f64) = (0.0, 0.0);
        for (g, r) in got.iter().zip(rows) {
            let g: Vec<f64> = g.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            assert_eq!(g.len(), r.len(), "{what}: row widths");
            for j in 0..r.len() {
                let e = (g[j] - r[j]).abs();
                if j < measured {
                    speed_err = speed_err.max(e);
                } else {
                    command_err = command_err.max(e);
                }
            }
        }
        eprintln!("{what} vs in-process loop: measured {speed_err:.2e}, commands {command_err:.2e}");
        // the same controller and plant code on either side; what differs is the order of
        // floating-point operations through the FMI calls (1e-6 rad/s is the bound)
        assert!(speed_err < 1e-6, "{what}: measurements differ by {speed_err}");
        assert!(command_err < 1e-4, "{what}: commands differ by {command_err}");
    };
    // OSP libcosim ran rigtwin-closed-loop.ssp: its Jacobi master delays the command one sample
    compare(v["libcosim"].as_array().unwrap(), delayed, "libcosim (SSP, one sample of delay)");
    for version in ["fmi3", "fmi2"] {
        let problems = v["validate"][version].as_array().unwrap();
        assert!(problems.is_empty(), "fmpy validate {version}: {problems:?}");
        assert_eq!(v["fmutool"][version]["returncode"], 0, "fmutool {version}: {}", v["fmutool"][version]);
        compare(v[version].as_array().unwrap(), rows, &format!("{version}: fmpy master"));
    }
}

/// Issue 31, item 5: the controller FMU of a drive model. `rigtwin fmu --controller --params`
/// on the gear bench example (its `[mpc]` section: the motor torque bounded at 2 N·m) writes
/// the controller FMUs and the closed-loop SSP with the plant FMU of the same file; fmpy's
/// master (FMI 3, FMI 2) and OSP libcosim (the SSP) close the loop, the load speed's reference
/// stepping to 10 rad/s at 50 ms, and must give the in-process loop's speeds and torques (the
/// controller assembled as `rigtwin mpc --params` assembles it, the plant as the FMU
/// integrates it).
#[test]
fn drive_controller_fmu_closes_the_loop_in_fmpy_and_libcosim() {
    let dir = common::scratch("mpc", "drive-ctrl-fmu");
    let bench = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gear_bench/bench.toml");
    let (plant_dir, ctrl_dir) = (dir.join("plant"), dir.join("controller"));
    for (args, out) in [(vec!["fmu"], &plant_dir), (vec!["fmu", "--controller"], &ctrl_dir)] {
        let mut a = args.clone();
        a.extend(["--params", bench.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let o = rigtwin(&a);
        assert!(o.status.success(), "{a:?}: {}", String::from_utf8_lossy(&o.stderr));
    }
    let file = modelfile::read(&bench).unwrap();
    let modelfile::Model::Drive(model) = &file.model else { panic!("a drive model") };
    let p = mpc::prediction::drive_prediction(model, 1e-3).unwrap();
    let mut settings = file.mpc.drive_settings(&p.model.input_names, &p.model.output_names, 50).unwrap();
    settings.solver.time_limit_s = 1.0;
    let picked = mpc::realtime::measured_outputs(&p.model.output_names, &settings);
    let names: Vec<&str> = picked.iter().map(|&j| p.model.output_names[j].as_str()).collect();
    assert_eq!(names, ["w_motor", "w_hub", "w_load"]);
    let (steps, step_at) = (300, 50);
    let in_process = |delayed: bool| -> Vec<Vec<f64>> {
        let mut c = mpc::Controller::with_input_delays(&p.model, &p.input_delays_s, &settings).unwrap();
        c.reset(&nalgebra::DVector::zeros(p.model.nstates()), &[0.0]);
        let mut plant = mpc::DrivePlant::new(model, settings.dt_s, &p.model.output_names).unwrap();
        let (mut rows, mut previous) = (Vec::new(), None::<Vec<f64>>);
        for k in 0..steps {
            let y = plant.outputs().to_vec();
            let u = c.step(&y, &[if k >= step_at { 10.0 } else { 0.0 }]).0.to_vec();
            let applied = if delayed { previous.clone().unwrap_or_else(|| u.clone()) } else { u.clone() };
            rows.push(picked.iter().map(|&j| y[j]).chain(applied.iter().copied()).collect());
            plant.advance(&applied).unwrap();
            previous = Some(u);
        }
        rows
    };
    let rows = in_process(false);
    let start = serde_json::json!({
        "plant": {},
        "controller": {"mpc.time_limit": 1.0},
        "references": {"w_load_ref": 0.0},
        "step_at": step_at, "step": {"w_load_ref": 10.0},
    });
    check_fmus_against(&dir, &plant_dir, &ctrl_dir, &start, steps, 3, &rows, &in_process(true));
    // the load follows: past half its reference by the end, the motor within its bound
    let last = rows.last().unwrap();
    assert!(last[2] > 5.0, "the load speed follows its 10 rad/s reference: {last:?}");
    assert!(rows.iter().all(|r| r[3].abs() <= 2.0 + 1e-9), "the motor torque stays within its 2 N m");
}

/// Issue 31: `rigtwin mpc` and `rigtwin fmu --controller` take the shared `drive_test` bundle
/// bench_gear.toml, which has no `[mpc]` section: the inputs are bounded by the record's peak
/// |torque| (read here from the CSV itself), and a note on standard error says so.
#[test]
fn a_drive_test_without_mpc_bounds_is_controlled_within_its_records_peaks() {
    let bench = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/bench_gear.toml");
    let csv = std::fs::read_to_string(bench.with_extension("csv")).unwrap();
    let column = csv.lines().next().unwrap().split(',').position(|c| c == "torque_motor_Nm").unwrap();
    let peak = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(column).unwrap().trim().parse::<f64>().unwrap().abs())
        .fold(0.0f64, f64::max);
    let out = rigtwin(&["mpc", "--params", bench.to_str().unwrap(), "--json", "-"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("no [mpc] input_max") && err.contains("record's peaks"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["verdict"], "valid");
    let bound = v["signals"]["input_max"][0].as_f64().unwrap();
    assert!((bound - peak).abs() < 1e-12, "bound {bound} vs the record's peak {peak}");
    let dir = common::scratch("mpc", "bench-ctrl");
    let out = rigtwin(&["fmu", "--controller", "--params", bench.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.join("rigtwin-mpc-fmi3.fmu").exists() && dir.join("rigtwin-closed-loop.ssp").exists());
}
