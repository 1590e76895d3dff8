//! Heap allocations per controller step, counted by a global allocator.

#[global_allocator]
static ALLOCATOR: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;

use mpc::closed_loop::{rig_plant, steady_spin, LinearPlant, Plant};
use mpc::{Controller, MpcSettings};

/// rigtwin's part of a step allocates nothing; Clarabel 0.11's `solve` allocates once per call
/// (its timer tree is cleared and one nested map re-created), so a whole step makes exactly
/// one allocation after the first. The QP update itself (q, b) is allocation-free.
#[test]
fn a_step_allocates_only_inside_clarabel() {
    let ss = rig_plant(&plant::paper::damped_params(), plant::rig::Variant::V1).unwrap();
    let (x0, u0) = steady_spin(&ss, 10.0).unwrap();
    for horizon in [10, 50, 100] {
        let mut settings = MpcSettings::powertrain(horizon);
        // Every step must run a full solve: a step cut short by the clock on a loaded machine
        // (fallback) allocates differently, and this test is about allocations, not time.
        settings.solver.time_limit_s = 1.0;
        let mut c = Controller::new(&ss, &settings).unwrap();
        c.reset(&x0, &u0);
        let mut p = LinearPlant::new(&ss, 1e-3, &x0).unwrap();
        let mut y = vec![0.0; 5];
        let mut u = u0.clone();
        let mut counts = Vec::new();
        for k in 0..200 {
            y.copy_from_slice(p.outputs());
            let r = [10.0, 10.0, if k > 20 { 40.0 } else { 0.0 }];
            let before = mpc::alloc_counter::allocations();
            let (v, _) = c.step(&y, &r);
            u.copy_from_slice(v);
            counts.push(mpc::alloc_counter::allocations() - before);
            p.advance(&u).unwrap();
        }
        let odd: Vec<(usize, u64)> = counts.iter().copied().enumerate().skip(1).filter(|&(_, c)| c != 1).collect();
        assert!(odd.is_empty(), "N = {horizon}: steps with other than one allocation (step, count): {odd:?}");
    }
}
