//! The controller against independent numbers: the unconstrained optimum solved densely, the
//! static torque split of the open differential, offset-free tracking under an unmodelled
//! torque and a mis-set inertia, bounds, the fallback, and both QP formulations.

use mpc::closed_loop::{rig_plant, steady_spin, LinearPlant, Plant, RigSignals};
use mpc::{exponential_blocks, Controller, Formulation, MpcError, MpcSettings};
use nalgebra::{DMatrix, DVector};
use plant::rig::{RigParams, Variant};
use plant::statespace::StateSpace;

fn rig(params: &RigParams) -> StateSpace {
    rig_plant(params, Variant::V1).unwrap()
}

fn nominal() -> StateSpace {
    rig(&plant::paper::damped_params())
}

/// Runs `steps` samples of the MPC on `plant_ss` (the controller built on `model_ss`) with
/// the references [w_m2, w_m3, M_drive]; `extra` adds an unmodelled input torque. Returns
/// outputs and inputs per sample.
fn run(
    model_ss: &StateSpace,
    plant_ss: &StateSpace,
    settings: &MpcSettings,
    steps: usize,
    reference: impl Fn(usize) -> [f64; 3],
    extra: [f64; 3],
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Controller) {
    let (x0, u0) = steady_spin(plant_ss, 10.0).unwrap();
    let mut c = Controller::new(model_ss, settings).unwrap();
    assert_eq!(c.reference_names(), ["w_m2", "w_m3", "M_drive"]);
    c.reset(&x0, &u0);
    let mut p = LinearPlant::new(plant_ss, settings.dt_s, &x0).unwrap();
    let (mut ys, mut us) = (Vec::new(), Vec::new());
    for k in 0..steps {
        let y = p.outputs().to_vec();
        let (u, _) = c.step(&y, &reference(k));
        let u = u.to_vec();
        let applied: Vec<f64> = u.iter().zip(extra).map(|(a, b)| a + b).collect();
        p.advance(&applied).unwrap();
        ys.push(y);
        us.push(u);
    }
    (ys, us, c)
}

fn step_ref(k: usize) -> [f64; 3] {
    [10.0, 10.0, if k >= 50 { 40.0 } else { 0.0 }]
}

/// With no constraint active, the QP's minimiser is −P⁻¹q: solved here densely with nalgebra
/// from the snapshot (an independent solve of the same QP), the first input agrees with
/// Clarabel's to 1e-4 Nm (interior-point gap tolerance 1e-8 on a cost of order 1e4).
#[test]
fn unconstrained_step_matches_the_dense_solution() {
    let mut s = MpcSettings::powertrain(30);
    for y in s.outputs.iter_mut() {
        y.soft_min = None;
        y.soft_max = None;
    }
    // A small reference change keeps every bound inactive.
    let (_, _, c) = run(&nominal(), &nominal(), &s, 3, |_| [10.05, 10.0, 2.0], [0.0; 3]);
    let snap = c.snapshot();
    let n = snap.q.len();
    let p = DMatrix::from_fn(n, n, |i, j| snap.p[i][j]);
    let q = DVector::from_vec(snap.q.clone());
    // The slack variable is pinned at zero by its own bound (its linear cost is positive):
    // solve the equality-free problem in the other variables and set the slack to 0.
    let m = n - 1;
    let zr = p.view((0, 0), (m, m)).into_owned().lu().solve(&(-q.rows(0, m).into_owned())).unwrap();
    let mut z = DVector::zeros(n);
    z.rows_mut(0, m).copy_from(&zr);
    let a = DMatrix::from_fn(snap.b.len(), n, |i, j| snap.a[i][j]);
    let slack = &a * &z - DVector::from_vec(snap.b.clone());
    let active: Vec<usize> = (0..slack.len()).filter(|&i| slack[i] > -1e-9 && a[(i, n - 1)] == 0.0).collect();
    assert!(active.is_empty(), "constraints {active:?} are active: the test's premise fails");
    let u0: Vec<f64> = snap.u0_map.iter().map(|row| row.iter().zip(z.iter()).map(|(r, v)| r * v).sum()).collect();
    let rt = c.planned_first_input();
    for (a, b) in rt.iter().zip(&u0) {
        assert!((a - b).abs() < 1e-4, "Clarabel {rt:?} vs dense {u0:?}");
    }
}

/// After a 40 Nm drive-torque step at constant load speeds the open differential splits the
/// torque evenly: each side shaft carries M_drive/2 = 20 Nm (eq. (30) statically), the loads
/// hold their speed references, and the drive torque settles on its reference.
#[test]
fn step_settles_on_the_static_split() {
    let ss = nominal();
    let sig = RigSignals::of(&ss).unwrap();
    let mut s = MpcSettings::powertrain(50);
    s.solver.time_limit_s = 1.0; // this test is about the answer, not the clock
    let (ys, us, c) = run(&ss, &ss, &s, 1000, step_ref, [0.0; 3]);
    let last = ys.last().unwrap();
    assert!((last[sig.short_shaft] - 20.0).abs() < 1e-3, "T_short {}", last[sig.short_shaft]);
    assert!((last[sig.speeds[0]] - 10.0).abs() < 1e-5 && (last[sig.speeds[2]] - 10.0).abs() < 1e-5);
    assert!((us.last().unwrap()[sig.inputs[1]] - 40.0).abs() < 1e-3);
    assert_eq!(c.fallbacks(), 0);
}

/// Offset-free tracking: the plant has 10 % more drive inertia and 15 % stiffer shafts than
/// the model and an unmodelled −3 Nm drag torque on M2; the input-disturbance estimate must
/// remove the speed offset entirely and find the torque.
#[test]
fn tracking_is_offset_free_under_mismatch() {
    let model = nominal();
    let wrong = RigParams {
        j_drive: 0.529 * 1.1,
        c_short: 1479.0 * 1.15,
        c_long: Some(1479.0 * 7.0 / 9.0 * 1.15),
        ..plant::paper::damped_params()
    };
    let plant_ss = rig(&wrong);
    let sig = RigSignals::of(&model).unwrap();
    let mut s = MpcSettings::powertrain(50);
    s.solver.time_limit_s = 1.0;
    let (ys, _, c) = run(&model, &plant_ss, &s, 2000, step_ref, [-3.0, 0.0, 0.0]);
    let last = ys.last().unwrap();
    assert!((last[sig.speeds[0]] - 10.0).abs() < 1e-4, "w_m2 {}", last[sig.speeds[0]]);
    assert!((last[sig.speeds[2]] - 10.0).abs() < 1e-4, "w_m3 {}", last[sig.speeds[2]]);
    let d = c.disturbance();
    assert!((d[sig.inputs[0]] + 3.0).abs() < 0.1, "disturbance estimate {d:?}");
}

/// Hard bounds and rate limits hold even when the reference asks for more: a 300 Nm step
/// against a 200 Nm drive limit and 40 Nm/ms rate.
#[test]
fn hard_bounds_and_rates_hold() {
    let ss = nominal();
    let s = MpcSettings::powertrain(50);
    let sig = RigSignals::of(&ss).unwrap();
    let (_, us, _) = run(&ss, &ss, &s, 300, |k| [10.0, 10.0, if k >= 20 { 300.0 } else { 0.0 }], [0.0; 3]);
    for (j, &i) in sig.inputs.iter().enumerate() {
        let set = &s.inputs[j];
        let dmax = set.max_rate_nm_per_s * s.dt_s;
        for k in 0..us.len() {
            assert!(
                us[k][i] <= set.max_nm + 1e-9 && us[k][i] >= set.min_nm - 1e-9,
                "{} at {k}: {}",
                set.name,
                us[k][i]
            );
            if k > 0 {
                assert!((us[k][i] - us[k - 1][i]).abs() <= dmax + 1e-9, "{} rate at {k}", set.name);
            }
        }
    }
    assert!(us.iter().any(|u| (u[sig.inputs[1]] - 200.0).abs() < 1e-6), "the drive never reached its bound");
}

/// The soft side-shaft bound works: lowering it from 60 to 20.5 Nm lowers the peak torque
/// after the 40 Nm step (steady state 20 Nm, so the bound is feasible at rest).
#[test]
fn soft_torque_bound_lowers_the_peak() {
    let ss = nominal();
    let sig = RigSignals::of(&ss).unwrap();
    let peak = |max: f64| {
        let mut s = MpcSettings::powertrain(50);
        s.solver.time_limit_s = 1.0;
        for y in s.outputs.iter_mut().filter(|y| y.name.starts_with("T_")) {
            y.soft_max = Some(max);
            y.weight = 0.01; // leave the peak to the bound, not to the oscillation penalty
        }
        let (ys, _, _) = run(&ss, &ss, &s, 400, step_ref, [0.0; 3]);
        ys.iter().map(|y| y[sig.short_shaft]).fold(f64::MIN, f64::max)
    };
    let (loose, tight) = (peak(60.0), peak(20.5));
    assert!(tight < loose - 0.5, "peak {tight} Nm with the bound vs {loose} Nm without");
    assert!(tight < 21.5, "peak {tight} Nm over a 20.5 Nm soft bound");
}

/// A solve that cannot finish in time falls back to the shifted previous plan: with a 1 ns
/// limit every solve is cut off, no step panics, the inputs stay where they were (no plan
/// yet) and within bounds; after one good solve, the fallback applies the plan's next input.
#[test]
fn late_solves_fall_back_to_the_shifted_plan() {
    let ss = nominal();
    let (x0, u0) = steady_spin(&ss, 10.0).unwrap();
    let y: Vec<f64> = (&ss.c * &x0).iter().copied().collect();
    let mut late = MpcSettings::powertrain(20);
    late.solver.time_limit_s = 1e-9;
    let mut c = Controller::new(&ss, &late).unwrap();
    c.reset(&x0, &u0);
    for _ in 0..5 {
        let (u, info) = c.step(&y, &[10.0, 10.0, 40.0]);
        assert!(info.fallback, "a 1 ns solve was accepted");
        for (a, b) in u.iter().zip(&u0) {
            assert!((a - b).abs() < 1e-12, "without a plan the previous input is held");
        }
    }
    assert_eq!(c.fallbacks(), 5);
}

/// The sparse formulation (states as variables, dynamics as equalities) and the condensed one
/// are different QPs with the same minimiser: solved tightly (1e-11) their inputs agree along
/// an 80-step closed loop to 1e-3 Nm of ≈ 100 Nm (what remains is Clarabel's static KKT
/// regularisation, which acts differently on the two, carried along by the feedback: 6e-5 Nm
/// seen).
#[test]
fn sparse_and_condensed_agree() {
    let ss = nominal();
    let mut runs = Vec::new();
    for f in [Formulation::Condensed, Formulation::Sparse] {
        let mut s = MpcSettings::powertrain(40);
        s.formulation = f;
        s.solver.time_limit_s = 1.0;
        s.solver.tol_gap = 1e-11;
        s.solver.tol_feas = 1e-11;
        s.solver.max_iter = 200;
        let (_, us, c) = run(&ss, &ss, &s, 80, step_ref, [0.0; 3]);
        assert_eq!(c.fallbacks(), 0);
        runs.push(us);
    }
    for (a, b) in runs[0].iter().zip(&runs[1]) {
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-3, "condensed {a:?} vs sparse {b:?}");
        }
    }
}

/// Bad settings name the setting.
#[test]
fn bad_settings_are_named() {
    let ss = nominal();
    let mut s = MpcSettings::powertrain(50);
    s.outputs[0].name = "w_m9".into();
    match Controller::new(&ss, &s) {
        Err(MpcError::UnknownSignal { key, name, .. }) => {
            assert_eq!(key, "outputs[0].name");
            assert_eq!(name, "w_m9");
        }
        other => panic!("expected an unknown-signal error, got {:?}", other.err().map(|e| e.to_string())),
    }
    let mut s = MpcSettings::powertrain(50);
    s.move_blocks = exponential_blocks(40, 4);
    let e = Controller::new(&ss, &s).err().unwrap().to_string();
    assert!(e.contains("move_blocks"), "{e}");
    let mut s = MpcSettings::powertrain(50);
    s.inputs[1].max_nm = -500.0;
    let e = Controller::new(&ss, &s).err().unwrap().to_string();
    assert!(e.contains("inputs[1].min_nm"), "{e}");
    // Disturbances on all three machines cannot be told from a static twist by speeds alone.
    let mut s = MpcSettings::powertrain(50);
    s.inputs[1].disturbance_std_nm = 1.0;
    let e = Controller::new(&ss, &s).err().unwrap().to_string();
    assert!(e.contains("disturbances"), "{e}");
}

/// A saved state restored into the same controller, or into a fresh one of the same
/// structure, replays the same inputs (the FMU's get/set/serialize state rests on this).
#[test]
fn saved_state_replays_the_same_inputs() {
    let ss = nominal();
    let mut s = MpcSettings::powertrain(30);
    s.solver.time_limit_s = 1.0;
    let (x0, u0) = steady_spin(&ss, 10.0).unwrap();
    let mut c = Controller::new(&ss, &s).unwrap();
    c.reset(&x0, &u0);
    let mut p = LinearPlant::new(&ss, 1e-3, &x0).unwrap();
    let run = |c: &mut Controller, p: &mut LinearPlant, from: usize, n: usize| -> Vec<Vec<f64>> {
        (from..from + n)
            .map(|k| {
                let y = p.outputs().to_vec();
                let u = c.step(&y, &step_ref(k)).0.to_vec();
                p.advance(&u).unwrap();
                u
            })
            .collect()
    };
    run(&mut c, &mut p, 0, 60);
    let mut saved = vec![0.0; c.state_len()];
    c.save_state(&mut saved);
    let p_saved = p.state().clone();
    let first = run(&mut c, &mut p, 60, 40);
    // into the same controller
    assert!(c.restore_state(&saved));
    let mut p2 = LinearPlant::new(&ss, 1e-3, &p_saved).unwrap();
    assert_eq!(run(&mut c, &mut p2, 60, 40), first);
    // into a fresh one
    let mut fresh = Controller::new(&ss, &s).unwrap();
    assert!(fresh.restore_state(&saved));
    let mut p3 = LinearPlant::new(&ss, 1e-3, &p_saved).unwrap();
    assert_eq!(run(&mut fresh, &mut p3, 60, 40), first);
    // a record of another length, or with a NaN, is refused
    assert!(!fresh.restore_state(&saved[1..]));
    let mut bad = saved.clone();
    bad[0] = f64::NAN;
    assert!(!fresh.restore_state(&bad));
    assert!(first.iter().flatten().any(|&u| u > 30.0), "the step was taken");
}

/// The unconstrained check gives the exact optimum: at every step of a step run where it was
/// taken (no interior-point iteration), its first input equals the interior-point method's
/// solved to a 1e-12 gap on the same QP (`exact_first_input`) within 1e-6 Nm — the reference
/// solver's own accuracy on a cost of order 1e4; and it was taken on most steps.
#[test]
fn unconstrained_check_is_the_exact_optimum() {
    let ss = nominal();
    let mut s = MpcSettings::powertrain(50);
    s.solver.time_limit_s = 1.0;
    let (x0, u0) = steady_spin(&ss, 10.0).unwrap();
    let mut c = Controller::new(&ss, &s).unwrap();
    c.reset(&x0, &u0);
    let mut p = LinearPlant::new(&ss, 1e-3, &x0).unwrap();
    let (mut fast, mut worst) = (0, 0.0f64);
    for k in 0..400 {
        let y = p.outputs().to_vec();
        let (u, info) = c.step(&y, &step_ref(k));
        let u = u.to_vec();
        if info.solve.iterations == 0 && !info.fallback {
            fast += 1;
            if k % 10 == 0 {
                let exact = c.exact_first_input().unwrap();
                let rt = c.planned_first_input();
                worst = rt.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(worst, f64::max);
            }
        }
        p.advance(&u).unwrap();
    }
    assert!(fast > 200, "the check was taken on {fast} of 400 steps");
    assert!(worst < 1e-6, "first input {worst} Nm from the exact optimum");
}
