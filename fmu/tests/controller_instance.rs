//! The controller FMU's instance: a saved state replays the same commands; tunable settings
//! change mid-run without losing the filter's estimates.

mod common;

use common::{instance, measured};
use rigtwin_fmu::instance::Instance;
use rigtwin_fmu::variables::Slot;

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
