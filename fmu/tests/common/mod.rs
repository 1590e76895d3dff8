//! The FMU instances as the tests drive them (each test binary uses some of it).
#![allow(dead_code)]

use rigtwin_fmu::instance::{Instance, Interface, Logger, Status};
use rigtwin_fmu::variables::Slot;
use rigtwin_fmu::ControllerSpec;
use rigtwin_fmu::{FmuParams, RigPlant};

pub struct Quiet;
impl Logger for Quiet {
    fn log(&self, _: Status, _: &str, _: &str) {}
}

pub fn instance(effects: plant::rig::DriveEffects) -> (Instance, [u32; 6], [u32; 3]) {
    let mut p = FmuParams::of_rig(RigPlant { effects, ..RigPlant::default() });
    let mut spec = ControllerSpec::new(50, 4);
    spec.values[8] = 1.0; // time limit: every solve runs to the end, whatever the machine's load
    p.controller = Some(spec);
    let mut inst = Instance::new("ctrl", Interface::CoSimulation, Box::new(Quiet), false, &p);
    let table = inst.table().clone();
    let vr = |slot| table.find(slot).unwrap().vr;
    let inputs = [0, 1, 2, 3, 4, 5].map(|i| vr(Slot::Input(i)));
    let outputs = [0, 1, 2].map(|i| vr(Slot::Command(i)));
    inst.set_f64(&inputs, &[10.0, 10.0, 10.0, 10.0, 10.0, 0.0]).unwrap();
    inst.enter_initialization_mode(0.0, None).unwrap();
    inst.exit_initialization_mode().unwrap();
    (inst, inputs, outputs)
}

/// A measured speed that rings like the rig's shuffle after a drive-torque step.
pub fn measured(k: usize) -> [f64; 6] {
    let t = k as f64 * 1e-3;
    let ring =
        if k >= 20 { 0.3 * (-(t - 0.02) * 8.0).exp() * (2.0 * std::f64::consts::PI * 12.6 * t).sin() } else { 0.0 };
    [10.0 + ring, 10.0 - 0.5 * ring, 10.0 + ring, 10.0, 10.0, if k >= 20 { 40.0 } else { 0.0 }]
}
