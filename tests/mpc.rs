//! `rigtwin mpc` end to end: the JSON contract, the controller against the FMU (through the
//! `fmi` crate) instead of plant's matrices, and the QPs solved by OSQP and DAQP.

mod common;

use std::process::Command;

use fmi::fmi3::import::Fmi3Import;
use fmi::fmi3::{CoSimulation, Common, Fmi3Model, GetSet};
use mpc::closed_loop::{compare, LinearPlant, Plant, Probes, RigSignals, Scenario, ScenarioKind};
use mpc::MpcSettings;
use rigtwin_fmu::FmuParams;

use common::vr;

fn rigtwin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).output().unwrap()
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
    let u0 = v["u0_error_Nm"].as_f64().unwrap();
    assert!(u0 < 1e-2, "u0 error {u0} Nm");
    let (m, b) = (&v["shuffle"]["mpc"], &v["shuffle"]["baseline"]);
    let f = |x: &serde_json::Value, k: &str| x[k].as_f64().unwrap();
    assert!(f(m, "overshoot") < 0.5 * f(b, "overshoot"), "{m} vs {b}");
    assert!(f(m, "settling_time_s") < 0.5 * f(b, "settling_time_s"), "{m} vs {b}");

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
    let params = FmuParams::default();
    let ss = rigtwin::control::prediction(&params).unwrap().model;
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
    let dir = std::env::temp_dir().join(format!("rigtwin-mpc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
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
