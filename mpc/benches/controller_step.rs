//! One controller step (estimate + target + QP update + Clarabel solve + bookkeeping) in the
//! closed loop of the drive-torque step scenario, for N = 10, 20, 50, 100 (default settings:
//! condensed QP, 4 move blocks), and for N = 50 with the effects a diagnosis adds (a 4.3 ms
//! dead time of the drive torque as input-delay states, a 5 ms actuator lag as a state).
//! Criterion gives the median; the 99th percentile, the largest step and the allocations per
//! step are printed after each group from 5000 individually timed steps.

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use mpc::closed_loop::{median_p99, rig_plant, steady_spin, LinearPlant, Plant, Scenario, ScenarioKind};
use mpc::{Controller, MpcSettings};

#[global_allocator]
static ALLOCATOR: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;

struct Loop {
    c: Controller,
    p: LinearPlant,
    y: Vec<f64>,
    u: Vec<f64>,
    k: usize,
    scenario: Scenario,
}

impl Loop {
    fn new(horizon: usize, effects: bool) -> Self {
        let (ss, delays) = if effects {
            let e = plant::rig::DriveEffects { time_delay_s: 0.0043, actuator_lag_s: 0.005, ..Default::default() };
            let rig = plant::paper::damped_params();
            let p =
                mpc::Design::Rig { rig: &rig, variant: plant::rig::Variant::V1, effects: &e }.prediction(1e-3).unwrap();
            (p.model, p.input_delays_s)
        } else {
            (rig_plant(&plant::paper::damped_params(), plant::rig::Variant::V1).unwrap(), Vec::new())
        };
        let (x0, u0) = steady_spin(&ss, 10.0).unwrap();
        let mut settings = MpcSettings::powertrain(horizon);
        settings.solver.time_limit_s = 1.0; // measure the solve, never cut it short
        let mut c = Controller::with_input_delays(&ss, &delays, &settings).unwrap();
        c.reset(&x0, &u0);
        let p = LinearPlant::new(&ss, 1e-3, &x0).unwrap();
        Loop { c, p, y: vec![0.0; ss.output_names.len()], u: u0, k: 0, scenario: Scenario::new(ScenarioKind::Step) }
    }

    /// One closed-loop sample; returns the controller step's time. The scenario repeats
    /// every second so that transients and steady state are both in the sample.
    fn tick(&mut self) -> Duration {
        let t = (self.k % 1000) as f64 * 1e-3;
        let r = [10.0, 10.0, self.scenario.drive_torque(t)];
        self.y.copy_from_slice(self.p.outputs());
        let start = Instant::now();
        let (u, _) = self.c.step(&self.y, &r);
        let elapsed = start.elapsed();
        self.u.copy_from_slice(u);
        self.p.advance(&self.u).unwrap();
        self.k += 1;
        elapsed
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("controller_step");
    for (horizon, effects) in [(10, false), (20, false), (50, false), (100, false), (50, true)] {
        let id = if effects { format!("{horizon}_with_delay_and_lag") } else { horizon.to_string() };
        let mut l = Loop::new(horizon, effects);
        group.bench_with_input(BenchmarkId::from_parameter(&id), &horizon, |b, _| {
            b.iter_custom(|iters| (0..iters).map(|_| l.tick()).sum())
        });
        let mut l = Loop::new(horizon, effects);
        let mut times = Vec::with_capacity(5000);
        let before = mpc::alloc_counter::allocations();
        for _ in 0..5000 {
            times.push(l.tick().as_secs_f64() * 1e6);
        }
        let allocs = (mpc::alloc_counter::allocations() - before) as f64 / 5000.0;
        let (median, p99) = median_p99(&times);
        let max = times.iter().copied().fold(0.0, f64::max);
        println!(
            "controller_step/{id}: median {median:.1} µs, p99 {p99:.1} µs, max {max:.1} µs, {allocs:.2} allocations per step"
        );
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(Duration::from_secs(4));
    targets = bench
}
criterion_main!(benches);
