//! The controller FMU's instance: heap allocations per communication step (set the inputs, read
//! the commands, DoStep), counted by a global allocator (alone in its test binary, so no other
//! test's allocations are counted).

#[global_allocator]
static ALLOCATOR: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;

mod common;

use common::{instance, measured};

#[test]
fn a_communication_step_allocates_only_inside_clarabel() {
    for effects in [
        plant::rig::DriveEffects::default(),
        plant::rig::DriveEffects { time_delay_s: 0.0043, actuator_lag_s: 0.005, ..Default::default() },
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
