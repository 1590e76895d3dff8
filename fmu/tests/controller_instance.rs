//! The controller FMU's instance: a saved state replays the same commands; tunable settings
//! change mid-run without losing the filter's estimates.

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
fn saved_state_replays_and_tuning_keeps_the_estimates() {
    let (mut inst, inputs, outputs) = instance(Default::default());
    let mut out = [0.0; 3];
    let run = |inst: &mut Instance, from: usize, n: usize| -> Vec<[f64; 3]> {
        (from..from + n)
            .map(|k| {
                let mut o = [0.0; 3];
                inst.set_f64(&inputs, &measured(k)).unwrap();
                inst.get_f64(&outputs, &mut o).unwrap();
                inst.do_step(k as f64 * 1e-3, 1e-3).unwrap();
                o
            })
            .collect()
    };
    run(&mut inst, 0, 40);
    // a state saved after the outputs were read at a point is the state before that step
    inst.set_f64(&inputs, &measured(40)).unwrap();
    inst.get_f64(&outputs, &mut out).unwrap();
    let bytes = inst.snapshot().to_bytes();
    let first = run(&mut inst, 40, 30);
    let s = rigtwin_fmu::instance::Snapshot::from_bytes(&bytes).unwrap();
    inst.restore(&s).unwrap();
    assert_eq!(run(&mut inst, 40, 30), first);
    assert!(first.iter().any(|u| u[1] > 30.0), "the drive torque followed its reference");
    // inputs changed after the outputs were read: the step is made again from the state before it
    inst.restore(&s).unwrap();
    inst.set_f64(&inputs, &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    inst.get_f64(&outputs, &mut out).unwrap();
    assert_eq!(run(&mut inst, 40, 30), first);
    // a tunable setting changed in step mode: the controller is rebuilt with its estimates
    inst.restore(&s).unwrap();
    let table = inst.table().clone();
    let weight = table.find(Slot::Param(0)).unwrap().vr;
    inst.set_f64(&[weight], &[100.0]).unwrap(); // the same value: nothing changes
    assert_eq!(run(&mut inst, 40, 30), first);
    inst.restore(&s).unwrap();
    inst.set_f64(&[weight], &[400.0]).unwrap();
    let tuned = run(&mut inst, 40, 30);
    assert_ne!(tuned, first, "a heavier speed weight changes the commands");
    // the commands continue from the estimates (no restart at rest): the first is close
    assert!((tuned[0][1] - first[0][1]).abs() < 5.0, "{:?} vs {:?}", tuned[0], first[0]);
    // a bad setting is refused by name
    let e = inst.set_f64(&[weight], &[-1.0]).unwrap_err();
    assert!(e.message.contains("mpc.speed_weight"), "{}", e.message);
}
