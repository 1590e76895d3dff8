//! The FMUs loaded and stepped by the Rust `fmi` crate: results against `plant`, misuse that
//! must fail with a status (and a log line) without taking the host down, and instances on
//! parallel threads.

mod common;

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi3::import::Fmi3Import;
use fmi::fmi3::{CoSimulation, Common, Fmi3Model, GetSet};
use nalgebra::{DMatrix, DVector};
use plant::Output;
use rigtwin_fmu::FmuParams;

use common::vr;

/// plant's free response of w_drive after an initial drive twist of 0.01 rad, at 1 ms.
fn plant_w_drive(steps: usize) -> Vec<f64> {
    let p = rigtwin_fmu::RigPlant::default();
    let ss = p.powertrain.open_differential(p.variant).unwrap().state_space(&[Output::Speeds]).unwrap();
    let mut x0 = DVector::zeros(6);
    x0[1] = 0.01;
    let y = ss.lsim(&DMatrix::zeros(steps + 1, 3), 1e-3, &x0).unwrap();
    (0..=steps).map(|k| y[(k, 1)]).collect()
}

fn run_fmi3(steps: usize) -> Vec<f64> {
    let import: Fmi3Import = fmi::import::from_path(common::fmu_dir().join("rigtwin-fmi3.fmu")).unwrap();
    let mut inst = import.instantiate_cs("rig", false, true, false, false, &[]).unwrap();
    // a drive twist of 0.01 rad: the twist state 2φ_drive − φ_m2 − φ_m3
    inst.set_float64(&[vr("twist")], &[0.02]).unwrap();
    inst.enter_initialization_mode(None, 0.0, None).unwrap();
    inst.exit_initialization_mode().unwrap();
    let mut out = Vec::with_capacity(steps + 1);
    let (mut ev, mut term, mut early, mut last) = (false, false, false, 0.0);
    for k in 0..=steps {
        let mut w = [0.0];
        inst.get_float64(&[vr("w_drive")], &mut w).unwrap();
        out.push(w[0]);
        if k < steps {
            inst.do_step(k as f64 * 1e-3, 1e-3, true, &mut ev, &mut term, &mut early, &mut last).unwrap();
        }
    }
    out
}

fn close(a: &[f64], b: &[f64]) {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        // both are exact zero-order-hold steps: agreement to round-off of the matrix exponentials
        assert!((x - y).abs() <= 1e-9 * scale, "step {k}: {x} vs {y}");
    }
}

#[test]
fn fmi3_co_simulation_steps_like_the_plant() {
    close(&run_fmi3(500), &plant_w_drive(500));
}

#[test]
fn fmi2_co_simulation_steps_like_the_plant() {
    use fmi::fmi2::instance::{CoSimulation as _, Common as _};
    let import: Fmi2Import = fmi::import::from_path(common::fmu_dir().join("rigtwin-fmi2.fmu")).unwrap();
    let mut inst = import.instantiate_cs("rig", false, true).unwrap();
    inst.setup_experiment(None, 0.0, None).unwrap();
    inst.set_real(&[vr("twist")], &[0.02]).unwrap();
    fmi::fmi2::instance::Common::enter_initialization_mode(&mut inst).unwrap();
    fmi::fmi2::instance::Common::exit_initialization_mode(&mut inst).unwrap();
    let mut out = Vec::new();
    for k in 0..=300 {
        let mut w = [0.0];
        inst.get_real(&[vr("w_drive")], &mut w).unwrap();
        out.push(w[0]);
        if k < 300 {
            inst.do_step(k as f64 * 1e-3, 1e-3, true).unwrap();
        }
    }
    close(&out, &plant_w_drive(300));
}

#[test]
fn misuse_gets_an_error_status_and_the_host_survives() {
    let import: Fmi3Import = fmi::import::from_path(common::fmu_dir().join("rigtwin-fmi3.fmu")).unwrap();
    let mut inst = import.instantiate_cs("misuse", false, true, false, false, &[]).unwrap();
    let mut v = [0.0];
    // wrong value references
    assert!(inst.get_float64(&[9999], &mut v).is_err());
    assert!(inst.set_float64(&[9999], &[1.0]).is_err());
    assert!(inst.set_float64(&[vr("variant")], &[1.0]).is_err(), "the variant is an Int32");
    // a calculated variable cannot be set
    assert!(inst.set_float64(&[vr("T_short")], &[1.0]).is_err());
    // NaN inputs and non-positive inertias are refused, and nothing is changed
    assert!(inst.set_float64(&[vr("M_drive")], &[f64::NAN]).is_err());
    assert!(inst.set_float64(&[vr("j_drive")], &[0.0]).is_err());
    assert!(inst.set_float64(&[vr("j_m2")], &[-1.0]).is_err());
    inst.get_float64(&[vr("j_drive")], &mut v).unwrap();
    assert_eq!(v[0], 0.529);
    // calls in the wrong state
    let (mut ev, mut term, mut early, mut last) = (false, false, false, 0.0);
    assert!(
        inst.do_step(0.0, 1e-3, true, &mut ev, &mut term, &mut early, &mut last).is_err(),
        "doStep before initialization"
    );
    assert!(inst.exit_initialization_mode().is_err(), "exit before enter");
    inst.enter_initialization_mode(None, 0.0, None).unwrap();
    inst.exit_initialization_mode().unwrap();
    assert!(inst.set_float64(&[vr("j_drive")], &[1.0]).is_err(), "a fixed parameter after initialization");
    assert!(inst.do_step(0.0, -1e-3, true, &mut ev, &mut term, &mut early, &mut last).is_err(), "negative step");
    assert!(
        inst.do_step(5.0, 1e-3, true, &mut ev, &mut term, &mut early, &mut last).is_err(),
        "wrong communication point"
    );
    // ... and the instance still works afterwards
    inst.do_step(0.0, 1e-3, true, &mut ev, &mut term, &mut early, &mut last).unwrap();
    inst.terminate().unwrap();
    assert!(
        inst.do_step(1e-3, 1e-3, true, &mut ev, &mut term, &mut early, &mut last).is_err(),
        "doStep after terminate"
    );
}

#[test]
fn a_variant_without_spring_stiffness_fails_at_initialization() {
    let import: Fmi3Import = fmi::import::from_path(common::fmu_dir().join("rigtwin-fmi3.fmu")).unwrap();
    let mut inst = import.instantiate_cs("v2", false, true, false, false, &[]).unwrap();
    inst.set_float64(&[vr("c_delta")], &[0.0]).unwrap();
    inst.set_int32(&[vr("variant")], &[2]).unwrap();
    inst.enter_initialization_mode(None, 0.0, None).unwrap();
    assert!(inst.exit_initialization_mode().is_err());
    assert!(inst.set_int32(&[vr("variant")], &[7]).is_err());
}

#[test]
fn instances_on_parallel_threads_do_not_interfere() {
    let want = plant_w_drive(400);
    let handles: Vec<_> = (0..2).map(|_| std::thread::spawn(|| run_fmi3(400))).collect();
    for h in handles {
        close(&h.join().unwrap(), &want);
    }
}

#[test]
fn the_checked_in_model_descriptions_are_the_generated_ones() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription");
    let p = FmuParams::default();
    for (sub, version) in [("fmi3", rigtwin_fmu::Version::Fmi3), ("fmi2", rigtwin_fmu::Version::Fmi2)] {
        let file = root.join(sub).join("modelDescription.xml");
        let on_disk = std::fs::read_to_string(&file).unwrap_or_default();
        assert!(
            on_disk == rigtwin_fmu::describe(&p, version),
            "{} is stale: regenerate with `cargo run -- fmu --descriptions modelDescription`",
            file.display()
        );
    }
}
