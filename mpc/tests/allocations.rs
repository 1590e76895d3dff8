//! Heap allocations per controller step, counted by a global allocator.

#[global_allocator]
static ALLOCATOR: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;

use mpc::closed_loop::{rig_plant, steady_spin, LinearPlant, Plant};
use mpc::{Controller, MpcSettings};

/// rigtwin's part of a step allocates nothing; Clarabel 0.11's `solve` allocates once per call
/// (its timer tree is cleared and one nested map re-created; its first call more), so a step
/// that runs the interior-point method makes exactly one allocation after Clarabel's first
/// call, and a step whose optimum has no active inequality (the unconstrained check, no
/// Clarabel call) makes none. The QP update itself (q, b) is allocation-free.
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
        let mut clarabel_calls = 0;
        let (mut fast, mut ipm) = (0, 0);
        for k in 0..200 {
            y.copy_from_slice(p.outputs());
            let r = [10.0, 10.0, if k > 20 { 40.0 } else { 0.0 }];
            let before = mpc::alloc_counter::allocations();
            let (v, info) = c.step(&y, &r);
            u.copy_from_slice(v);
            let count = mpc::alloc_counter::allocations() - before;
            p.advance(&u).unwrap();
            if k == 0 {
                // the controller's and Clarabel's first step
                clarabel_calls += usize::from(info.solve.iterations > 0);
                continue;
            }
            if info.solve.iterations == 0 {
                fast += 1;
                counts.push((k, count, 0));
            } else {
                ipm += 1;
                clarabel_calls += 1;
                if clarabel_calls > 1 {
                    counts.push((k, count, 1));
                }
            }
        }
        let odd: Vec<_> = counts.iter().filter(|&&(_, c, want)| c != want).collect();
        assert!(
            odd.is_empty(),
            "N = {horizon}: steps with other allocations than Clarabel's (step, count, expected): {odd:?}"
        );
        assert!(fast > 0 && ipm > 0, "N = {horizon}: both paths taken ({fast} unconstrained, {ipm} interior-point)");
    }
}
