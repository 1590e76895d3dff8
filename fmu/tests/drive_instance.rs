//! A drive model's FMU instance (`FmuParams::drive`), driven through the version-independent
//! instance API the FMI 3 and FMI 2 glue calls: against the test's own integrator of the
//! hand-reduced equations, an exact dead time, a saved and restored state, named refusals.

use rigtwin_fmu::instance::{Instance, Interface, Logger, Status};
use rigtwin_fmu::FmuParams;

use plant::{CoulombFriction, Coupling, Domain, DriveModel, Effect, Line, LineBody, TimeDelay};

struct Quiet;
impl Logger for Quiet {
    fn log(&self, _: Status, _: &str, _: &str) {}
}

fn body(name: &str, inertia: f64, drag: f64) -> LineBody {
    LineBody { name: name.into(), inertia, drag }
}

/// Motor and load through a 4:1 gear stage with a compliant shaft.
fn geared(effects: Vec<Effect>) -> DriveModel {
    DriveModel {
        line: Line {
            domain: Domain::Rotational,
            bodies: vec![body("motor", 0.002, 1e-4), body("load", 0.05, 4e-3)],
            couplings: vec![Coupling::new(2000.0, 0.3, 4.0)],
        },
        inputs: vec![0],
        effects,
    }
}

fn instance(m: DriveModel) -> Instance {
    let p = FmuParams::of_drive(m);
    Instance::new("t", Interface::CoSimulation, Box::new(Quiet), false, &p)
}

fn vr(i: &Instance, name: &str) -> u32 {
    i.table().variables.iter().find(|v| v.name == name).unwrap_or_else(|| panic!("no variable {name}")).vr
}

fn torque(t: f64) -> f64 {
    0.3 * (2.0 * std::f64::consts::PI * 7.0 * t).sin() + 0.1 * (2.0 * std::f64::consts::PI * 31.0 * t).cos()
}

/// The hand-reduced equations (gear: the load's angle seen from the motor is φ_m/r; the shaft
/// torque T = c(φ_m/r − φ_l) + d(ω_m/r − ω_l) drives the load and loads the motor with T/r),
/// integrated by RK4 with 200 sub-steps per millisecond, the torque held over each millisecond.
fn reference(steps: usize, dt: f64) -> Vec<[f64; 3]> {
    let (jm, dm, jl, dl, c, d, r) = (0.002, 1e-4, 0.05, 4e-3, 2000.0, 0.3, 4.0);
    let f = |x: [f64; 4], u: f64| {
        let t = c * (x[0] / r - x[1]) + d * (x[2] / r - x[3]);
        [x[2], x[3], (u - dm * x[2] - t / r) / jm, (t - dl * x[3]) / jl]
    };
    let mut x = [0.0; 4];
    let mut out = Vec::with_capacity(steps);
    let n = 200;
    let h = dt / n as f64;
    for k in 0..steps {
        let u = torque(k as f64 * dt);
        for _ in 0..n {
            let add = |a: [f64; 4], b: [f64; 4], s: f64| std::array::from_fn::<f64, 4, _>(|i| a[i] + s * b[i]);
            let k1 = f(x, u);
            let k2 = f(add(x, k1, h / 2.0), u);
            let k3 = f(add(x, k2, h / 2.0), u);
            let k4 = f(add(x, k3, h), u);
            x = std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        }
        let t = c * (x[0] / r - x[1]) + d * (x[2] / r - x[3]);
        out.push([x[2], x[3], t]);
    }
    out
}

#[test]
fn a_geared_drive_steps_as_the_hand_reduced_equations() {
    let dt = 1e-3;
    let steps = 500;
    let want = reference(steps, dt);
    let mut i = instance(geared(vec![]));
    let (u, wm, wl, tc) = (vr(&i, "M_motor"), vr(&i, "w_motor"), vr(&i, "w_load"), vr(&i, "T_coupling_1"));
    i.enter_initialization_mode(0.0, None).unwrap();
    i.exit_initialization_mode().unwrap();
    let mut worst = [0.0f64; 3];
    let mut range = [0.0f64; 3];
    for (k, w) in want.iter().enumerate() {
        i.set_f64(&[u], &[torque(k as f64 * dt)]).unwrap();
        i.do_step(k as f64 * dt, dt).unwrap();
        let mut y = [0.0; 3];
        i.get_f64(&[wm, wl, tc], &mut y).unwrap();
        for j in 0..3 {
            worst[j] = worst[j].max((y[j] - w[j]).abs());
            range[j] = range[j].max(w[j].abs());
        }
    }
    // exact ZOH against RK4 at 5 µs (error ~ (hλ)^4 ≈ 1e-9 of the range): 1e-7 of the range
    for j in 0..3 {
        assert!(worst[j] <= 1e-7 * range[j], "output {j}: {} of {}", worst[j], range[j]);
    }
}

#[test]
fn a_dead_time_delays_the_input_exactly_and_survives_a_saved_state() {
    // a free mass: ω(t) = F/m · max(0, t − τ) with the force applied from t = 0
    let m = DriveModel {
        line: Line { domain: Domain::Translational, bodies: vec![body("cart", 2.0, 0.0)], couplings: vec![] },
        inputs: vec![0],
        effects: vec![Effect::TimeDelay(TimeDelay { input: 0, delay_s: 2.5e-3 })],
    };
    let mut i = instance(m);
    let (u, v) = (vr(&i, "F_cart"), vr(&i, "v_cart"));
    i.enter_initialization_mode(0.0, None).unwrap();
    i.exit_initialization_mode().unwrap();
    let dt = 1e-3;
    let mut speeds = Vec::new();
    let mut saved = None;
    for k in 0..10 {
        i.set_f64(&[u], &[4.0]).unwrap();
        i.do_step(k as f64 * dt, dt).unwrap();
        let mut y = [0.0];
        i.get_f64(&[v], &mut y).unwrap();
        speeds.push(y[0]);
        if k == 2 {
            saved = Some(i.snapshot().to_bytes());
        }
    }
    for (k, s) in speeds.iter().enumerate() {
        let t = (k + 1) as f64 * dt;
        let want = 4.0 / 2.0 * (t - 2.5e-3).max(0.0);
        assert!((s - want).abs() < 1e-12, "t = {t}: {s} vs {want}");
    }
    // restored from its bytes at 3 ms (the force's history inside the dead time with it), the
    // instance continues exactly as before
    let back = rigtwin_fmu::instance::Snapshot::from_bytes(&saved.unwrap()).expect("a state of this FMU");
    i.restore(&back).unwrap();
    for (k, want) in speeds.iter().enumerate().skip(3) {
        i.set_f64(&[u], &[4.0]).unwrap();
        i.do_step(k as f64 * dt, dt).unwrap();
        let mut y = [0.0];
        i.get_f64(&[v], &mut y).unwrap();
        assert_eq!(y[0], *want, "step {k} after the restore");
    }
}

#[test]
fn parameters_are_settable_and_refused_by_name() {
    let mut i = instance(geared(vec![Effect::CoulombFriction(CoulombFriction {
        body: 1,
        friction: 0.2,
        smoothing_speed: 0.01,
    })]));
    let j = vr(&i, "load.inertia");
    let e = i.set_f64(&[j], &[-1.0]).unwrap_err();
    assert!(e.message.contains("load.inertia") && e.message.contains("> 0"), "{}", e.message);
    i.set_f64(&[j], &[0.1]).unwrap();
    let f = vr(&i, "load.friction");
    i.set_f64(&[f], &[0.5]).unwrap();
    i.enter_initialization_mode(0.0, None).unwrap();
    i.exit_initialization_mode().unwrap();
    // fixed parameters cannot change after initialisation
    assert!(i.set_f64(&[j], &[0.2]).is_err());
    // 0.5 N·m of friction at the load is 0.125 N·m at the motor through 4:1: a motor torque of
    // 0.05 N·m (0.2 N·m at the load) does not break it away; it creeps at the speed where the
    // smoothed friction balances it, v_s·0.4/√(1 − 0.16) = 4.4 mrad/s (without the friction it
    // would reach 0.3 rad/s in the 0.2 s)
    let (u, wl) = (vr(&i, "M_motor"), vr(&i, "w_load"));
    for k in 0..200 {
        i.set_f64(&[u], &[0.05]).unwrap();
        i.do_step(k as f64 * 1e-3, 1e-3).unwrap();
    }
    let mut y = [0.0];
    i.get_f64(&[wl], &mut y).unwrap();
    assert!(y[0].abs() < 0.01, "the load moved at {} rad/s against its friction", y[0]);
}
