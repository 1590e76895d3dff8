//! The FMU instance with drive-path effects, held to properties that do not come from its own
//! code: a dead time is a pure shift of the response, a lag is dx/dt = (u − x)/τ, the
//! directional derivatives are the finite differences of the derivatives, and a saved state
//! (with the dead time's history) replays the same future.

use rigtwin_fmu::instance::{Instance, Interface, Logger, Status};
use rigtwin_fmu::variables::Slot;
use rigtwin_fmu::{FmuParams, RigPlant};

struct Quiet;
impl Logger for Quiet {
    fn log(&self, _status: Status, _category: &str, _message: &str) {}
}

fn params(f: impl FnOnce(&mut plant::rig::DriveEffects)) -> FmuParams {
    let mut r = RigPlant::default();
    f(&mut r.effects);
    FmuParams::of_rig(r)
}

fn instance(p: &FmuParams, interface: Interface) -> Instance {
    Instance::new("t", interface, Box::new(Quiet), false, p)
}

fn vr(i: &Instance, name: &str) -> u32 {
    i.table().variables.iter().find(|v| v.name == name).unwrap_or_else(|| panic!("no {name}")).vr
}

fn get(i: &mut Instance, name: &str) -> f64 {
    let mut v = [0.0];
    i.get_f64(&[vr(i, name)], &mut v).unwrap();
    v[0]
}

fn start_cs(i: &mut Instance) {
    i.enter_initialization_mode(0.0, None).unwrap();
    i.exit_initialization_mode().unwrap();
}

/// w_drive after a 10 Nm drive-torque step at t = 0, sampled at `times` (steps of `h`, the
/// torque set once before the first step).
fn step_response(p: &FmuParams, h: f64, steps: usize) -> Vec<f64> {
    let mut i = instance(p, Interface::CoSimulation);
    start_cs(&mut i);
    i.set_f64(&[vr(&i, "M_drive")], &[10.0]).unwrap();
    let mut out = vec![get(&mut i, "w_drive")];
    for k in 0..steps {
        i.do_step(k as f64 * h, h).unwrap();
        out.push(get(&mut i, "w_drive"));
    }
    out
}

#[test]
fn a_dead_time_shifts_the_response() {
    // τ = 2.5 ms at h = 1 ms: the delayed step starts inside a step (the piece logic) and the
    // response at t equals the undelayed one at t − τ, sampled by 0.5 ms steps.
    let tau = 2.5e-3;
    let delayed = step_response(&params(|e| e.time_delay_s = tau), 1e-3, 40);
    let plain = step_response(&FmuParams::default(), 0.5e-3, 80);
    let scale = plain.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (k, w) in delayed.iter().enumerate() {
        let t = k as f64 * 1e-3;
        let want = if t < tau { 0.0 } else { plain[((t - tau) / 0.5e-3).round() as usize] };
        // both are exact zero-order-hold pieces: round-off of the matrix exponentials
        assert!((w - want).abs() <= 1e-9 * scale, "t = {t}: {w} vs {want}");
    }
}

#[test]
fn the_lag_state_follows_a_first_order_lag() {
    let tau = 4e-3;
    let mut i = instance(&params(|e| e.actuator_lag_s = tau), Interface::CoSimulation);
    assert_eq!(i.nx(), 7, "the rig's 6 states and the lagged torque");
    start_cs(&mut i);
    i.set_f64(&[vr(&i, "M_drive")], &[10.0]).unwrap();
    for k in 0..20 {
        i.do_step(k as f64 * 1e-3, 1e-3).unwrap();
        let t = (k + 1) as f64 * 1e-3;
        let lagged = get(&mut i, "M_drive_lagged");
        // analytic: 10 (1 − e^{−t/τ})
        assert!((lagged - 10.0 * (1.0 - (-t / tau).exp())).abs() < 1e-9, "t = {t}: {lagged}");
        let d = get(&mut i, "der(M_drive_lagged)");
        assert!((d - (10.0 - lagged) / tau).abs() < 1e-6, "der(M_drive_lagged) {d}");
    }
}

/// Every effect on, in model exchange, at a state where `twist` is the side shafts' twist.
fn me_instance(twist: f64) -> Instance {
    let p = params(|e| {
        e.time_delay_s = 3e-3;
        e.actuator_lag_s = 4e-3;
        e.backlash_rad = 0.01;
        e.compliance_stiffness_nm_per_rad = 2000.0;
    });
    let mut i = instance(&p, Interface::ModelExchange);
    assert_eq!(i.nx(), 9, "the rig's 6 states, the compliance's 2 and the lag's");
    i.enter_initialization_mode(0.0, None).unwrap();
    i.exit_initialization_mode().unwrap();
    i.enter_continuous_time_mode().unwrap();
    let mut x: Vec<f64> = (0..9).map(|k| 0.01 * ((k * 7 % 5) as f64 - 2.0)).collect();
    // s = −φ_m2 + 2 φ_drive − φ_m3
    x[0] = 0.0;
    x[2] = 0.0;
    x[1] = twist / 2.0;
    i.set_continuous_states(&x).unwrap();
    i.set_f64(&[vr(&i, "M_m2"), vr(&i, "M_drive"), vr(&i, "M_m3")], &[2.0, 30.0, -4.0]).unwrap();
    i
}

#[test]
fn directional_derivatives_are_the_finite_differences() {
    // in contact and inside the play (the backlash model's two linear pieces)
    for twist in [0.05, 0.004] {
        let mut i = me_instance(twist);
        let nx = i.nx();
        let der_vrs: Vec<u32> = (0..nx)
            .map(|k| {
                let slot = match i.table().derivative_state[k] {
                    Some(d) => Slot::State(d),
                    None => Slot::Derivative(k),
                };
                i.table().find(slot).unwrap().vr
            })
            .collect();
        let mut x = vec![0.0; nx];
        i.continuous_states(&mut x).unwrap();
        let mut f0 = vec![0.0; nx];
        i.derivatives(&mut f0).unwrap();
        for j in 0..nx {
            let known = i.table().find(Slot::State(j)).unwrap().vr;
            let mut dd = vec![0.0; nx];
            i.directional_derivative(&der_vrs, &[known], &[1.0], &mut dd).unwrap();
            // central differences of a piecewise-linear function: exact away from the kink
            let h = 1e-6;
            let mut fd = [vec![0.0; nx], vec![0.0; nx]];
            for (s, sign) in [(0, 1.0), (1, -1.0)] {
                let mut xs = x.clone();
                xs[j] += sign * h;
                i.set_continuous_states(&xs).unwrap();
                i.derivatives(&mut fd[s]).unwrap();
            }
            i.set_continuous_states(&x).unwrap();
            for k in 0..nx {
                let num = (fd[0][k] - fd[1][k]) / (2.0 * h);
                let tol = 1e-6 * (1.0 + num.abs());
                assert!((dd[k] - num).abs() <= tol, "twist {twist}: ∂ẋ{k}/∂x{j} {} vs {num}", dd[k]);
            }
        }
        // with the dead time the derivatives do not depend on the present drive torque
        let m_drive = vr(&i, "M_drive");
        let mut dd = vec![0.0; nx];
        i.directional_derivative(&der_vrs, &[m_drive], &[1.0], &mut dd).unwrap();
        let mut before = vec![0.0; nx];
        i.derivatives(&mut before).unwrap();
        i.set_f64(&[m_drive], &[80.0]).unwrap();
        let mut after = vec![0.0; nx];
        i.derivatives(&mut after).unwrap();
        assert_eq!(before, after);
        assert!(dd.iter().all(|v| *v == 0.0));
    }
}

#[test]
fn a_saved_state_with_its_history_replays_the_same_future() {
    let p = params(|e| {
        e.time_delay_s = 3.5e-3;
        e.backlash_rad = 0.002;
    });
    let mut i = instance(&p, Interface::CoSimulation);
    start_cs(&mut i);
    let m = vr(&i, "M_drive");
    let drive = |k: usize| 20.0 * (0.05 * k as f64).sin();
    for k in 0..10 {
        i.set_f64(&[m], &[drive(k)]).unwrap();
        i.do_step(k as f64 * 1e-3, 1e-3).unwrap();
    }
    let saved = rigtwin_fmu::instance::Snapshot::from_bytes(&i.snapshot().to_bytes()).expect("bytes round trip");
    let run = |i: &mut Instance| -> Vec<f64> {
        (10..30)
            .map(|k| {
                i.set_f64(&[m], &[drive(k)]).unwrap();
                i.do_step(k as f64 * 1e-3, 1e-3).unwrap();
                get(i, "w_m2")
            })
            .collect()
    };
    let first = run(&mut i);
    i.restore(&saved).unwrap();
    assert_eq!(run(&mut i), first);
    // a state of an FMU with another state count is refused
    let mut other = instance(&params(|e| e.actuator_lag_s = 1e-3), Interface::CoSimulation);
    assert!(other.restore(&saved).is_err());
}
