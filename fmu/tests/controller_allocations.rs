//! The controller FMU's instance: heap allocations per communication step (set the inputs, read
//! the commands, DoStep), counted by a global allocator (alone in its test binary, so no other
//! test's allocations are counted).

#[global_allocator]
static ALLOCATOR: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;

use rigtwin_fmu::controller::ControllerSpec;
use rigtwin_fmu::instance::{Instance, Interface, Logger, Status};
use rigtwin_fmu::variables::Slot;
use rigtwin_fmu::FmuParams;

struct Quiet;
impl Logger for Quiet {
    fn log(&self, _: Status, _: &str, _: &str) {}
}

fn instance(effects: plant::effects::DriveEffects) -> (Instance, [u32; 6], [u32; 3]) {
    let mut p = FmuParams { effects, ..FmuParams::default() };
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
fn measured(k: usize) -> [f64; 6] {
    let t = k as f64 * 1e-3;
    let ring =
        if k >= 20 { 0.3 * (-(t - 0.02) * 8.0).exp() * (2.0 * std::f64::consts::PI * 12.6 * t).sin() } else { 0.0 };
    [10.0 + ring, 10.0 - 0.5 * ring, 10.0 + ring, 10.0, 10.0, if k >= 20 { 40.0 } else { 0.0 }]
}

#[test]
fn a_communication_step_allocates_only_inside_clarabel() {
    for effects in [
        plant::effects::DriveEffects::default(),
        plant::effects::DriveEffects { time_delay_s: 0.0043, actuator_lag_s: 0.005, ..Default::default() },
    ] {
        let (mut inst, inputs, outputs) = instance(effects);
        let mut out = [0.0; 3];
        let mut counts = Vec::new();
        for k in 0..150 {
            let before = mpc::alloc_counter::allocations();
            inst.set_f64(&inputs, &measured(k)).unwrap();
            inst.get_f64(&outputs, &mut out).unwrap();
            inst.do_step(k as f64 * 1e-3, 1e-3).unwrap();
            counts.push(mpc::alloc_counter::allocations() - before);
            assert!(out.iter().all(|v| v.is_finite()));
        }
        // Clarabel 0.11's solve allocates once per call (its timer tree, see
        // mpc/tests/allocations.rs) and more on its first call; a step whose optimum has no
        // active bound does not call it. Everything else in the step allocates nothing.
        let first_call = counts.iter().skip(1).position(|&c| c > 0).map_or(counts.len(), |i| i + 1);
        let odd: Vec<(usize, u64)> =
            counts.iter().copied().enumerate().skip(first_call + 1).filter(|&(_, c)| c > 1).collect();
        assert!(odd.is_empty(), "{effects:?}: steps with more than Clarabel's one allocation: {odd:?}");
        assert!(counts.iter().skip(1).any(|&c| c == 0), "{effects:?}: no step took the unconstrained optimum");
    }
}
