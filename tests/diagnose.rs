//! `rigtwin diagnose`: every effect of the vocabulary found in data made by another model path
//! than the one fitted — the torsional sweeps by an RK4 integration of the equations of motion
//! written out here (10 sub-steps per sample, the torque held as a rig's drive converter holds
//! it), the shake tests by summing the periodic steady state of each line in the time domain
//! and sending it through the impedance estimation — with the parameter within 20 %, the error
//! well below the declared model's; clean data gives `none`; the example bundles end to end.

mod common;

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::process::Command;

use ident::diagnose::{bearing, torsional};
use ident::{Coupling, Impedances, ShakeTest, Structure, Sweep};
use nalgebra::Matrix2;
use num_complex::Complex64;
use plant::{Coefficients, RigParams, Support, Variant};
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// The truth of a synthetic torsional sweep.
#[derive(Clone, Copy, Default)]
struct Truth {
    zeta: Option<f64>,
    delay_s: f64,
    lag_s: f64,
    backlash_rad: f64,
    compliance: Option<(f64, f64)>, // (stiffness, motor fraction)
    set_point_nm: f64,
    /// Coulomb friction of [M2, drive, M3], Nm, smoothed by tanh(w / 0.02 rad/s) (rigtwin
    /// smooths algebraically, at another speed).
    friction_nm: [f64; 3],
}

/// A 20 s sweep 1 → 30 Hz, ±8 Nm about the set point, sampled at 1 kHz, speeds with 2 mrad/s
/// white noise. Equations: J q̈ = −a T(aᵀq, aᵀq̇) − D_drag q̇ (+ compliance) + drive, a = [−1, 2, −1],
/// T the two side shafts in series with a dead zone of half-width b (each shaft's play b).
fn sweep(rig: &RigParams, truth: Truth, seed: u64) -> Sweep {
    let e = rig.effective(Variant::V1).unwrap();
    let rig_d = match truth.zeta {
        Some(z) => rig.with_shaft_damping_ratio(z, Variant::V1).unwrap(),
        None => rig.clone(),
    };
    let ed = rig_d.effective(Variant::V1).unwrap();
    let (cl, cr) = (e.c_left, e.c_right);
    let cs = cl * cr / (cl + cr);
    let ds = ed.d_left * (cr / (cl + cr)).powi(2) + ed.d_right * (cl / (cl + cr)).powi(2);
    let (n, fs, sub) = (20_000usize, 1000.0, 10);
    let dt = 1.0 / fs;
    let torque: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            let phase = 2.0 * PI * (1.0 * t + 0.5 * 29.0 / 20.0 * t * t);
            truth.set_point_nm + 8.0 * phase.sin()
        })
        .collect();
    // held torque, delayed in continuous time
    let held = |t: f64| {
        let s = t - truth.delay_s;
        if s < 0.0 {
            torque[0]
        } else {
            torque[((s / dt).floor() as usize).min(n - 1)]
        }
    };
    // state: q (m2, cage, m3, motor), q̇, lagged torque
    let (jm, jc, jmot, k_int) = match truth.compliance {
        Some((k, f)) => (e.j_m2, (1.0 - f) * e.j_drive, f * e.j_drive, k),
        None => (e.j_m2, e.j_drive, 0.0, 0.0),
    };
    let compliant = truth.compliance.is_some();
    let deriv = |x: &[f64; 9], u: f64| -> [f64; 9] {
        let s = -x[0] + 2.0 * x[1] - x[2];
        let sd = -x[4] + 2.0 * x[5] - x[6];
        let b = truth.backlash_rad;
        let t = if s > b {
            cs * (s - b) + ds * sd
        } else if s < -b {
            cs * (s + b) + ds * sd
        } else {
            0.0
        };
        let drive = if truth.lag_s > 0.0 { x[8] } else { u };
        // the compliance damped like the shafts, stiffness-proportionally (d_s/c_s)·k
        let internal = k_int * (x[3] - x[1]) + ds / cs * k_int * (x[7] - x[5]);
        let mut d = [0.0; 9];
        d[0] = x[4];
        d[1] = x[5];
        d[2] = x[6];
        d[3] = x[7];
        let fric = |k: usize, w: f64| truth.friction_nm[k] * (w / 0.02).tanh();
        d[4] = (t - e.load_drag * x[4] - fric(0, x[4])) / jm;
        d[6] = (t - e.load_drag * x[6] - fric(2, x[6])) / e.j_m3;
        if compliant {
            d[5] = (-2.0 * t + internal) / jc;
            d[7] = (drive - internal - fric(1, x[7])) / jmot;
        } else {
            d[5] = (-2.0 * t + drive - fric(1, x[5])) / jc;
        }
        if truth.lag_s > 0.0 {
            d[8] = (u - x[8]) / truth.lag_s;
        }
        d
    };
    // start at rest on the set point: speeds T0/(2 drag), static twist beyond the play
    let w0 = truth.set_point_nm / (2.0 * e.load_drag);
    let t_shaft = truth.set_point_nm / 2.0;
    let s0 = t_shaft / cs + truth.backlash_rad * t_shaft.signum() * f64::from(t_shaft != 0.0);
    let mut x = [0.0, s0 / 2.0, 0.0, 0.0, w0, w0, w0, w0, truth.set_point_nm];
    if compliant {
        x[3] = x[1] + truth.set_point_nm / k_int;
    }
    let noise = Normal::new(0.0, 0.002).unwrap();
    let mut rng = StdRng::seed_from_u64(seed);
    let (mut w2, mut w3) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let h = dt / sub as f64;
    for k in 0..n {
        w2.push(x[4] + noise.sample(&mut rng));
        w3.push(x[6] + noise.sample(&mut rng));
        for s in 0..sub {
            let t = k as f64 * dt + s as f64 * h;
            let add = |x: &[f64; 9], d: &[f64; 9], f: f64| std::array::from_fn::<f64, 9, _>(|i| x[i] + f * d[i]);
            let k1 = deriv(&x, held(t));
            let k2 = deriv(&add(&x, &k1, h / 2.0), held(t + h / 2.0));
            let k3 = deriv(&add(&x, &k2, h / 2.0), held(t + h / 2.0));
            let k4 = deriv(&add(&x, &k3, h), held(t + h));
            x = std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        }
    }
    Sweep { dt_s: dt, torque_nm: torque, speed_m2_radps: w2, speed_m3_radps: w3 }
}

fn declared() -> RigParams {
    plant::paper::damped_params()
}

fn run(s: &Sweep, rig: &RigParams) -> torsional::TorsionalDiagnosis {
    torsional::diagnose(s, rig, Variant::V1, &|_| {}).unwrap()
}

fn within(p: &BTreeMap<String, f64>, key: &str, truth: f64, rel: f64) {
    let v = p[key];
    assert!((v - truth).abs() <= rel * truth.abs(), "{key} = {v}, truth {truth}");
}

fn check(d: &torsional::TorsionalDiagnosis, effect: &str) {
    assert_eq!(d.effect, effect, "candidates: {:#?}", d.candidates);
    assert!(d.error_after < 0.5 * d.error_before, "error {} → {}", d.error_before, d.error_after);
    // every candidate is fitted and scored: none and the nine of the vocabulary (friction at
    // each of the three machines and at both load machines)
    assert_eq!(d.candidates.len(), 1 + torsional::Candidate::ALL.len(), "every candidate is fitted and scored");
}

#[test]
fn shaft_damping_is_found() {
    // the declared model has no shaft damping; the rig has ζ = 3 %
    let undamped = RigParams { d_short: 0.0, d_long: 0.0, ..declared() };
    let d = run(&sweep(&undamped, Truth { zeta: Some(0.03), set_point_nm: 40.0, ..Default::default() }, 1), &undamped);
    check(&d, "shaft_damping");
    within(&d.parameters, "damping_ratio", 0.03, 0.2);
}

#[test]
fn time_delay_is_found() {
    let d =
        run(&sweep(&declared(), Truth { delay_s: 0.0063, set_point_nm: 40.0, ..Default::default() }, 2), &declared());
    check(&d, "time_delay");
    within(&d.parameters, "delay_s", 0.0063, 0.2);
}

#[test]
fn actuator_lag_is_found() {
    let d = run(&sweep(&declared(), Truth { lag_s: 0.008, set_point_nm: 40.0, ..Default::default() }, 3), &declared());
    check(&d, "actuator_lag");
    within(&d.parameters, "time_constant_s", 0.008, 0.2);
}

#[test]
fn backlash_is_found() {
    // torque about zero, so the side shafts pass through their play
    let d = run(
        &sweep(&declared(), Truth { backlash_rad: 0.004, set_point_nm: 0.0, ..Default::default() }, 4),
        &declared(),
    );
    check(&d, "backlash");
    within(&d.parameters, "backlash_rad", 0.004, 0.2);
}

/// The highest undamped natural frequency of the paper rig `rig` (V1) with `effects`, Hz.
fn upper_mode_hz(rig: &plant::RigParams, effects: &plant::rig::DriveEffects) -> f64 {
    let m = plant::DriveModel::paper_rig(rig, Variant::V1, effects).unwrap();
    m.line.model().unwrap().modes().unwrap().frequencies_hz.iter().copied().fold(0.0, f64::max)
}

#[test]
fn drive_compliance_is_found() {
    // motor and cage halves; k puts the upper mode in the swept band
    let f = 0.5;
    let j = declared().j_drive;
    let k = 1500.0;
    let truth_rig = declared();
    let upper = upper_mode_hz(
        &truth_rig,
        &plant::rig::DriveEffects {
            compliance_stiffness_nm_per_rad: k,
            compliance_motor_fraction: f,
            ..Default::default()
        },
    );
    assert!(upper < 30.0, "upper mode {upper} Hz outside the sweep: pick another k (j_drive {j})");
    let d = run(
        &sweep(&declared(), Truth { compliance: Some((k, f)), set_point_nm: 40.0, ..Default::default() }, 5),
        &declared(),
    );
    check(&d, "drive_compliance");
    within(&d.parameters, "stiffness_Nm_per_rad", k, 0.2);
    within(&d.parameters, "frequency_hz", upper, 0.2);
}

/// Motor-heavy compliances (most of the drive's inertia on the motor side), the first
/// record kind: the shuffle falls far below the declared model's, and a re-fit of the declared
/// model alone bends j_drive and c_short to a fraction of their values (reported as `none`,
/// exit 0, before). The contract is the issue's: the parameters are right (stiffness and shafts
/// to a fifth, share to 0.125), or the report says they are no finding (the declared mechanics
/// had to move: NOT EXPLAINED) or not determined (equally good fits listed). Seeds 21 and 47–51
/// were seen while the search for equally good fits was written; 52–54 were written after.
/// Measured (docs/validation.md, step 25): the compliance is found and right for seeds 48 and 54
/// (901 and 999 N·m/rad for 900 and 1000, shares 0.750 for 0.75); the other seven end as the
/// flagged `none` (the compliance's grid, 1.2–8 times the declared shuffle, misses their
/// valleys: finding them is left); no confident wrong answer. (Seed 48's compliance was found at
/// 74.7 Hz, share 0.96, once a mode above the sweep was no longer rejected out of hand; its fit
/// is now restarted from the declared mechanics too, step 25.)
const MOTOR_HEAVY: [(f64, f64, f64, u64); 9] = [
    (600.0, 0.7, 1.0, 21),
    (400.0, 0.8, 1.0, 47),
    (900.0, 0.75, 1.25, 48),
    (700.0, 0.8, 1.0, 49),
    (500.0, 0.65, 1.15, 50),
    (1200.0, 0.7, 1.0, 51),
    (800.0, 0.75, 1.1, 52),
    (450.0, 0.7, 1.0, 53),
    (1000.0, 0.75, 1.2, 54),
];

#[test]
fn motor_heavy_compliances_are_right_or_said_to_be_undetermined() {
    let mut misses = Vec::new();
    for (k, f, shafts, seed) in MOTOR_HEAVY {
        let (right, said) = motor_heavy_outcome(k, f, shafts, seed);
        if !(right || said) {
            misses.push(seed);
        }
    }
    const MISSES: [u64; 0] = [];
    assert_eq!(misses, MISSES, "records with a confident wrong answer (by seed)");
}

/// Held out, written after the plausibility rule became per effect (a compliance may stiffen
/// the shafts: `ident::diagnose::verdict::declared_moved`) and the compliance's mode had to lie
/// where the record excites the rig, and run once: motor-heavy compliances with shafts 1.3 to
/// 1.45 times stiffer than declared, which the former rule (j_drive and c_short within 1.3 of
/// the declared values, whatever the effect) could only call distorted — the first
/// record, whose right answer moved c_short ×1.37. Same contract as above. (Seed 72 was first
/// written with 1100 N·m/rad and share 0.75, whose upper mode, 31 Hz, lies outside the sweep:
/// replaced before it was diagnosed, by a truth chosen on its modes alone.)
const MOTOR_HEAVY_STIFFER_SHAFTS: [(f64, f64, f64, u64); 6] = [
    (1000.0, 0.7, 1.35, 71),
    (850.0, 0.7, 1.45, 72),
    (900.0, 0.7, 1.45, 73),
    (1200.0, 0.65, 1.3, 74),
    (950.0, 0.72, 1.38, 75),
    (1050.0, 0.68, 1.42, 76),
];

#[test]
fn held_out_motor_heavy_compliances_with_stiffer_shafts() {
    let mut misses = Vec::new();
    let mut right_count = 0;
    for (k, f, shafts, seed) in MOTOR_HEAVY_STIFFER_SHAFTS {
        let (right, said) = motor_heavy_outcome(k, f, shafts, seed);
        right_count += usize::from(right);
        if !(right || said) {
            misses.push(seed);
        }
    }
    eprintln!("right: {right_count} of {}", MOTOR_HEAVY_STIFFER_SHAFTS.len());
    const MISSES: [u64; 0] = [];
    assert_eq!(misses, MISSES, "records with a confident wrong answer (by seed)");
}

/// Whether the diagnosis of a motor-heavy record ([`motor_heavy`]) is right (the compliance
/// found, stiffness and c_short within 20 %, motor share within 0.125) and whether it says the
/// record does not determine the answer (equally good fits) or that the answer is no finding.
fn motor_heavy_outcome(k: f64, f: f64, shafts: f64, seed: u64) -> (bool, bool) {
    let d = motor_heavy(k, f, shafts, seed);
    let p = &d.parameters;
    let near = |key: &str, truth: f64, tol: f64| p.get(key).is_some_and(|v| (v - truth).abs() <= tol);
    let c_short = declared().c_short * shafts;
    let right = d.effect == "drive_compliance"
        && near("stiffness_Nm_per_rad", k, 0.2 * k)
        && near("motor_fraction", f, 0.125)
        && near("c_short_Nm_per_rad", c_short, 0.2 * c_short);
    (right, !d.equivalents.is_empty() || d.distorted.is_some())
}

/// The diagnosis of a sweep of the declared rig with its shafts × `shafts` and a compliance
/// (`k`, motor share `f`).
fn motor_heavy(k: f64, f: f64, shafts: f64, seed: u64) -> torsional::TorsionalDiagnosis {
    let mut truth = declared();
    truth.c_short *= shafts;
    truth.c_long = truth.c_long.map(|c| c * shafts);
    let effects = plant::rig::DriveEffects {
        compliance_stiffness_nm_per_rad: k,
        compliance_motor_fraction: f,
        ..Default::default()
    };
    let upper = upper_mode_hz(&truth, &effects);
    assert!(upper < 30.0, "upper mode {upper} Hz outside the sweep");
    let d = run(
        &sweep(&truth, Truth { compliance: Some((k, f)), set_point_nm: 40.0, ..Default::default() }, seed),
        &declared(),
    );
    eprintln!(
        "k {k} f {f} shafts ×{shafts}: {} {:?} equivalents {:?} distorted {:?} error {:.4} → {:.4}",
        d.effect, d.parameters, d.equivalents, d.distorted, d.error_before, d.error_after
    );
    d
}

#[test]
fn clean_data_gives_none_with_the_parameters_refitted() {
    // the rig differs from the declared model only in j_drive and c_short (8 % and 5 %)
    let truth = RigParams {
        j_drive: 0.529 * 1.08,
        c_short: 1479.0 * 1.05,
        c_long: Some(1479.0 * 1.05 * 7.0 / 9.0),
        ..declared()
    };
    let d = run(&sweep(&truth, Truth { set_point_nm: 40.0, ..Default::default() }, 6), &declared());
    assert_eq!(d.effect, "none", "candidates: {:#?}", d.candidates);
    within(&d.parameters, "j_drive_kgm2", truth.j_drive, 0.02);
    within(&d.parameters, "c_short_Nm_per_rad", truth.c_short, 0.02);
    assert!(d.error_after < 0.5 * d.error_before);
}

// ---- bearing ----

fn support() -> Support {
    Support { k_x: 3.68e6, k_y: 3.85e6, c_x: 1226.0, c_y: 1313.0, m_x: 18.14, m_y: 18.14 }
}

fn kc() -> Coefficients {
    Coefficients {
        k_n_per_m: [[4.0e5, 0.0], [0.0, 5.0e5]],
        c_ns_per_m: [[2600.0, 0.0], [0.0, 2800.0]],
        m_kg: [[0.0; 2]; 2],
    }
}

/// Two periodic shake tests (1 Hz lines 5–85 Hz, random phases; the second shaker adds a
/// tenth out of step), 16 s at 1024 Hz: the displacement is the sum over the lines of the
/// steady state Z = H⁻¹ F of the true system with `eta` hysteretic damping, delayed by `tau`
/// in the sensors; white noise of 0.5 % of its RMS.
fn shake(element: &Coefficients, eta: f64, tau: f64, seed: u64) -> Impedances {
    let (fs, n) = (1024.0, 1024 * 16);
    let mut rng = StdRng::seed_from_u64(seed);
    let mut uniform = || rand::Rng::random::<f64>(&mut rng);
    let lines: Vec<(f64, f64)> = (5..=85).map(|f| (f as f64, uniform() * 2.0 * PI)).collect();
    let h = |w: f64| -> Matrix2<Complex64> {
        let mut h = element.impedance(w) + support().coefficients().impedance(w);
        for i in 0..2 {
            for j in 0..2 {
                h[(i, j)] += Complex64::new(0.0, eta * element.k_n_per_m[i][j]);
            }
        }
        h
    };
    let mut tests = Vec::new();
    for dir in 0..2 {
        let mut fx = vec![0.0; n];
        let mut fy = vec![0.0; n];
        let mut zx = vec![0.0; n];
        let mut zy = vec![0.0; n];
        for &(f, ph) in &lines {
            let w = 2.0 * PI * f;
            let main = Complex64::from_polar(25.0, ph);
            let other = main * 0.1 * Complex64::from_polar(1.0, -w * 0.009);
            let force =
                if dir == 0 { nalgebra::Vector2::new(main, other) } else { nalgebra::Vector2::new(other, main) };
            let z = h(w).try_inverse().unwrap() * force * Complex64::from_polar(1.0, -w * tau);
            for k in 0..n {
                let e = Complex64::from_polar(1.0, w * k as f64 / fs);
                fx[k] += (force[0] * e).re;
                fy[k] += (force[1] * e).re;
                zx[k] += (z[0] * e).re;
                zy[k] += (z[1] * e).re;
            }
        }
        let rms = (zx.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let noise = Normal::new(0.0, 0.005 * rms).unwrap();
        for v in zx.iter_mut().chain(zy.iter_mut()) {
            *v += noise.sample(&mut rng);
        }
        tests.push(ShakeTest { dt_s: 1.0 / fs, force_x_n: fx, force_y_n: fy, disp_x_m: zx, disp_y_m: zy });
    }
    Impedances::from_tests([&tests[0], &tests[1]], (5.0, 85.0)).unwrap()
}

fn check_bearing(d: &bearing::BearingDiagnosis, effect: &str) {
    assert_eq!(d.effect, effect, "candidates: {:#?}", d.candidates);
    assert!(d.error_after < 0.3 * d.error_before, "error {} → {}", d.error_before, d.error_after);
    assert_eq!(d.candidates.len(), bearing::EFFECTS.len());
}

#[test]
fn added_mass_is_found() {
    let el = Coefficients { m_kg: [[5.4, 0.0], [0.0, 5.9]], ..kc() };
    let d = bearing::diagnose(&shake(&el, 0.0, 0.0, 11), &support(), Structure::KC, Coupling::Direct).unwrap();
    check_bearing(&d, "added_mass");
    within(&d.parameters, "m_xx_kg", 5.4, 0.2);
    within(&d.parameters, "m_yy_kg", 5.9, 0.2);
}

#[test]
fn cross_coupled_stiffness_is_found() {
    let el = Coefficients { k_n_per_m: [[4.0e5, 1.5e5], [-1.2e5, 5.0e5]], ..kc() };
    let d = bearing::diagnose(&shake(&el, 0.0, 0.0, 12), &support(), Structure::KC, Coupling::Direct).unwrap();
    check_bearing(&d, "cross_coupled_stiffness");
    within(&d.parameters, "k_xy_N_per_m", 1.5e5, 0.2);
    within(&d.parameters, "k_yx_N_per_m", -1.2e5, 0.2);
}

#[test]
fn structural_damping_is_found() {
    let d = bearing::diagnose(&shake(&kc(), 0.3, 0.0, 13), &support(), Structure::KC, Coupling::Direct).unwrap();
    check_bearing(&d, "structural_damping");
    within(&d.parameters, "loss_factor", 0.3, 0.2);
}

#[test]
fn sensor_delay_is_found() {
    let d = bearing::diagnose(&shake(&kc(), 0.0, 0.0008, 14), &support(), Structure::KC, Coupling::Direct).unwrap();
    check_bearing(&d, "sensor_delay");
    within(&d.parameters, "delay_s", 0.0008, 0.2);
}

#[test]
fn declared_structure_enough_gives_none() {
    let d = bearing::diagnose(&shake(&kc(), 0.0, 0.0, 15), &support(), Structure::KC, Coupling::Direct).unwrap();
    assert_eq!(d.effect, "none", "candidates: {:#?}", d.candidates);
    within(&d.parameters, "k_xx_N_per_m", 4.0e5, 0.05);
    within(&d.parameters, "c_yy_Ns_per_m", 2800.0, 0.05);
}

// ---- the example bundles, end to end ----

fn rigtwin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).output().unwrap()
}

fn bundle(name: &str) -> String {
    format!("{}/../shared/data/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

fn diagnose_bundle(name: &str) -> serde_json::Value {
    let dir = common::scratch("diagnose", name);
    let (json, svg, model) = (dir.join("d.json"), dir.join("d.svg"), dir.join("model.toml"));
    let out = rigtwin(&[
        "diagnose",
        &bundle(name),
        "--json",
        json.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
        "--write-model",
        model.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for key in ["effect", "parameters", "error_before", "error_after", "candidates"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    for c in v["candidates"].as_array().unwrap() {
        assert!(c["effect"].is_string() && c["error_after"].is_number() && c["score"].is_number());
    }
    // the written model is a rig file the rest of rigtwin reads
    modelfile::rig::load_rig(&model).unwrap();
    v
}

/// The declared model has no shaft damping (DATA.md): the diagnosis must add it, with a
/// damping ratio near the 3 % that the declared dampings of the other bundles give
/// (d_short = 1.12 Nm s/rad at the shuffle: ζ = d ω / 2c ≈ 0.03).
#[test]
fn bundle_undamped_model() {
    let v = diagnose_bundle("v1_sweep_undamped_model");
    assert_eq!(v["effect"], "shaft_damping");
    let z = v["parameters"]["damping_ratio"].as_f64().unwrap();
    let rig = declared();
    let e = rig.effective(Variant::V1).unwrap();
    let cs = e.c_left * e.c_right / (e.c_left + e.c_right);
    let w = (cs * (1.0 / e.j_m2 + 4.0 / e.j_drive + 1.0 / e.j_m3)).sqrt();
    let zeta_declared = 0.5 * w * e.d_left / e.c_left;
    assert!((z - zeta_declared).abs() < 0.3 * zeta_declared, "ζ {z} vs {zeta_declared}");
    assert!(v["error_after"].as_f64().unwrap() < 0.1 * v["error_before"].as_f64().unwrap());
}

/// "Something in the drive path is not in the model" (DATA.md): a drive-path effect, and the
/// error falls by far.
#[test]
fn bundle_drive_path() {
    let v = diagnose_bundle("v1_sweep_b");
    let effect = v["effect"].as_str().unwrap();
    assert!(["time_delay", "actuator_lag", "drive_compliance", "backlash"].contains(&effect), "{effect}");
    assert!(v["error_after"].as_f64().unwrap() < 0.2 * v["error_before"].as_f64().unwrap());
}

/// The squeeze-film damper declared KC: the inertia it lacks, with the masses that the KCM
/// identification of the same bundle gives (tests/bearing.rs: 5.44 / 5.89 kg).
#[test]
fn bundle_sfd_shake() {
    let v = diagnose_bundle("sfd_shake");
    assert_eq!(v["effect"], "added_mass");
    let p = &v["parameters"];
    assert!((p["m_xx_kg"].as_f64().unwrap() - 5.44).abs() < 0.2);
    assert!((p["m_yy_kg"].as_f64().unwrap() - 5.89).abs() < 0.2);
}

// ---- the extended model in the FMU ----

/// Writes `s` as a torsional bundle (DATA.md) declaring `rig` in V1; returns the TOML's path.
fn write_bundle(dir: &std::path::Path, s: &Sweep, rig: &RigParams) -> std::path::PathBuf {
    use std::fmt::Write as _;
    std::fs::create_dir_all(dir).unwrap();
    let mut csv = String::from("time_s,torque_drive_Nm,speed_m2_radps,speed_m3_radps\n");
    for k in 0..s.torque_nm.len() {
        let _ = writeln!(
            csv,
            "{:.4},{:.6},{:.6},{:.6}",
            k as f64 * s.dt_s,
            s.torque_nm[k],
            s.speed_m2_radps[k],
            s.speed_m3_radps[k]
        );
    }
    std::fs::write(dir.join("sweep.csv"), csv).unwrap();
    let toml = format!("kind = \"torsional_sweep\"\ndata = \"sweep.csv\"\nvariant = \"V1\"\n\n{}", model_section(rig));
    let path = dir.join("sweep.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

/// ‖hp(y) − hp(ŷ)‖ / ‖hp(y)‖ over both speeds: the diagnosis's error (DATA.md's normalised
/// RMS error with offsets and drift removed by the same zero-phase high-pass, its corner set by
/// the record's length).
fn speed_error(measured: [&[f64]; 2], model: [&[f64]; 2], dt: f64) -> f64 {
    let corner = torsional::high_pass_hz(measured[0].len(), dt);
    let hp = |x: &[f64]| ident::signal::filtfilt_high_pass(x, dt, corner);
    let (mut num, mut den) = (0.0, 0.0);
    for c in 0..2 {
        let (m, y) = (hp(measured[c]), hp(model[c]));
        num += m.iter().zip(&y).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        den += m.iter().map(|a| a * a).sum::<f64>();
    }
    (num / den).sqrt()
}

/// The whole loop on a bundle with `truth` in it: `rigtwin diagnose --write-model` names the
/// effect, `rigtwin fmu --params` exports the written model, and fmpy replays the measured drive
/// torque through both FMUs (co-simulation over the whole record, model exchange over the first
/// 3 s): the FMU's error against the measurement is the diagnosis's error_after.
fn fmu_reproduces_the_diagnosis(truth: Truth, seed: u64, effect: &str) {
    let fmu_lib_built = common::fmu_dir(); // builds the FMU's shared library
    let _ = fmu_lib_built;
    let dir = common::scratch("diagnose-fmu", effect);
    let s = sweep(&declared(), truth, seed);
    let bundle = write_bundle(&dir, &s, &declared());
    let (json, model, fmus) = (dir.join("d.json"), dir.join("model.toml"), dir.join("fmus"));
    let out = rigtwin(&[
        "diagnose",
        bundle.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--write-model",
        model.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["effect"], effect, "{v:#}");
    let out = rigtwin(&["fmu", "--params", model.to_str().unwrap(), "--out", fmus.to_str().unwrap()]);
    assert!(out.status.success(), "rigtwin fmu: {}", String::from_utf8_lossy(&out.stderr));

    // start in the written model's steady state under the first torque sample
    let rig = modelfile::rig::load_rig(&model).unwrap();
    let m = plant::DriveModel::paper_rig(&rig.model, rig.variant, &rig.effects).unwrap();
    // the measured initial speed, as the diagnosis starts its simulation: about 0 Nm with play
    // the response depends on the start (a speed 1e-4 rad/s off is a drag torque of 5e-5 Nm
    // that decides on which side of the play the shafts rattle), so the replay starts where
    // the diagnosis did
    let speed0 = 0.5 * (s.speed_m2_radps[0] + s.speed_m3_radps[0]);
    let x0 = plant::record_start(&m, s.torque_nm[0], speed0);
    let mut start = serde_json::Map::new();
    // the FMU's states are the twists, not the drive's and the motor's absolute angles
    let names = m.state_names();
    let of = |n: &str| names.iter().position(|x| x == n).map(|i| x0[i]).unwrap();
    for (name, &value) in names.iter().zip(&x0) {
        let (name, value) = match name.as_str() {
            "phi_drive" => ("twist".to_string(), 2.0 * value - of("phi_m2") - of("phi_m3")),
            "phi_motor" => ("twist_motor".to_string(), value - of("phi_drive")),
            // the drive torque's lag, on the motor when the drive is compliant
            lagged if lagged.ends_with("_lagged") => ("M_drive_lagged".to_string(), value),
            other => (other.to_string(), value),
        };
        start.insert(name, value.into());
    }
    start.insert("M_drive".into(), s.torque_nm[0].into());
    let start_file = dir.join("start.json");
    std::fs::write(&start_file, serde_json::Value::Object(start).to_string()).unwrap();
    let replay = dir.join("replay.json");
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fmu_replay.py");
    let me_seconds = 3.0;
    let out = Command::new(common::python())
        .arg(script)
        .arg(&fmus)
        .arg(dir.join("sweep.csv"))
        .arg("torque_drive_Nm=M_drive")
        .arg(&start_file)
        .arg("w_m2,w_m3")
        .arg(&replay)
        .arg(me_seconds.to_string())
        .output()
        .unwrap();
    assert!(out.status.success(), "fmu_replay.py: {}", String::from_utf8_lossy(&out.stderr));
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&replay).unwrap()).unwrap();
    for version in ["fmi3", "fmi2"] {
        assert_eq!(r["validate"][version], serde_json::json!([]), "fmpy validate {version}");
        let t = &r["fmutool"][version];
        assert!(t["returncode"] == 0 && t["output"].as_str().unwrap().contains("No semantic error"), "fmutool: {t}");
    }
    let speeds = |key: &str, name: &str| -> Vec<f64> {
        r[key][name].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
    };
    let (before, after) = (v["error_before"].as_f64().unwrap(), v["error_after"].as_f64().unwrap());
    let n = s.torque_nm.len();
    for version in ["fmi3", "fmi2"] {
        let (a, b) = (speeds(&format!("{version}_cs"), "w_m2"), speeds(&format!("{version}_cs"), "w_m3"));
        assert_eq!(a.len(), n, "{version}: one sample per measured sample");
        let e = speed_error([&s.speed_m2_radps, &s.speed_m3_radps], [&a, &b], s.dt_s);
        eprintln!("{effect} {version} CS: FMU error {e:.4}, diagnosis {before:.4} → {after:.4}");
        // The FMU integrates the model the diagnosis fitted, so it has the diagnosis's error.
        // Not to round-off: the FMU shifts the held torque by the dead time exactly where the
        // diagnosis interpolates between samples, and the high-pass sees the start transient
        // differently; 3 % of error_after covers both (seen: equal to 4 digits).
        assert!((e - after).abs() <= 0.03 * after, "{effect} {version}: FMU error {e} vs diagnosis {after}");
        assert!(e < 0.5 * before);
        // model exchange: the importer's CVode (rtol 1e-9) against the co-simulation
        let (ma, mb) = (speeds(&format!("{version}_me"), "w_m2"), speeds(&format!("{version}_me"), "w_m3"));
        let k = ma.len();
        assert_eq!(k, (me_seconds / s.dt_s).round() as usize + 1);
        let range = a[..k].iter().chain(&b[..k]).fold(0.0f64, |m, x| m.max((x - speed0).abs()));
        // Compared up to where the model's own sensitivity shows: the first sample at which
        // CVode at 1e-9 and at 1e-8 differ by more than 1e-4 of the range (a grazing contact
        // in a rattling play decides a side by round-off, and the trajectories part for any
        // two integrations, ME or CS). The whole window for a model without such a point; at
        // least a third of it in any case.
        let (la, lb) = (speeds(&format!("{version}_me_loose"), "w_m2"), speeds(&format!("{version}_me_loose"), "w_m3"));
        let horizon = (0..k).find(|&i| (ma[i] - la[i]).abs().max((mb[i] - lb[i]).abs()) > 1e-4 * range).unwrap_or(k);
        assert!(horizon >= k / 3, "{effect} {version}: ME at 1e-9 and 1e-8 part after {horizon} of {k} samples");
        let diff = ma[..horizon]
            .iter()
            .zip(&a)
            .chain(mb[..horizon].iter().zip(&b))
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        eprintln!("{effect} {version} ME vs CS over {horizon} of {k} samples: max |Δw| {diff:.2e} rad/s of {range:.3}");
        assert!(diff <= 1e-3 * range, "{effect} {version}: ME and CS differ by {diff} rad/s (range {range})");
    }
}

#[test]
fn fmu_carries_a_time_delay() {
    fmu_reproduces_the_diagnosis(Truth { delay_s: 0.0063, set_point_nm: 40.0, ..Default::default() }, 21, "time_delay");
}

#[test]
fn fmu_carries_an_actuator_lag() {
    fmu_reproduces_the_diagnosis(Truth { lag_s: 0.008, set_point_nm: 40.0, ..Default::default() }, 22, "actuator_lag");
}

#[test]
fn fmu_carries_backlash() {
    fmu_reproduces_the_diagnosis(
        Truth { backlash_rad: 0.004, set_point_nm: 0.0, ..Default::default() },
        23,
        "backlash",
    );
}

#[test]
fn fmu_carries_a_drive_compliance() {
    fmu_reproduces_the_diagnosis(
        Truth { compliance: Some((1500.0, 0.5)), set_point_nm: 40.0, ..Default::default() },
        24,
        "drive_compliance",
    );
}

#[test]
fn fmu_carries_coulomb_friction() {
    fmu_reproduces_the_diagnosis(
        Truth { friction_nm: [1.5, 0.0, 1.0], set_point_nm: 0.0, ..Default::default() },
        25,
        "coulomb_friction",
    );
}

/// Side-shaft play about a 10 Nm set point (±8 Nm: the drive torque never crosses zero, the
/// shaft torques at resonance nearly do): this sweep used to send a fit's matrices non-finite
/// and the matrix exponential into an endless loop. The diagnosis must return, with finite
/// numbers only.
#[test]
fn backlash_about_a_set_point_returns_with_finite_numbers() {
    let s = sweep(&declared(), Truth { backlash_rad: 0.004, set_point_nm: 10.0, ..Default::default() }, 7);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(run(&s, &declared()));
    });
    let d = rx.recv_timeout(std::time::Duration::from_secs(300)).expect("the diagnosis returns within 300 s");
    assert!(d.error_before.is_finite() && d.error_after.is_finite() && d.error_after <= d.error_before);
    for c in &d.candidates {
        assert!(c.error_after.is_finite(), "{}: {}", c.effect, c.error_after);
        assert!(c.parameters.values().all(|v| v.is_finite()), "{}: {:?}", c.effect, c.parameters);
    }
}

/// The `[model]` section of `rig`, as bundles and rig files write it.
fn model_section(rig: &RigParams) -> String {
    format!(
        "[model]\nj_m2 = {}\nj_drive = {}\nj_m3 = {}\nc_short = {}\nc_long = {}\nc_delta = {}\nd_short = {}\n\
         d_long = {}\nload_drag = {}\n",
        rig.j_m2,
        rig.j_drive,
        rig.j_m3,
        rig.c_short,
        rig.c_long(),
        rig.c_delta,
        rig.d_short,
        rig.d_long,
        rig.load_drag
    )
}

/// A rig file (the format `--write-model` writes) with `rig`'s parameters and `truth`'s effects.
fn rig_file(path: &std::path::Path, rig: &RigParams, truth: &Truth) {
    let (k, f) = truth.compliance.unwrap_or((0.0, 0.5));
    let text = format!(
        "name = \"truth\"\nvariant = \"V1\"\n\n{}\n[effects]\ntime_delay_s = {}\nactuator_lag_s = {}\n\
         backlash_rad = {}\ncompliance_stiffness_nm_per_rad = {k}\ncompliance_motor_fraction = {f}\n",
        model_section(rig),
        truth.delay_s,
        truth.lag_s,
        truth.backlash_rad
    );
    std::fs::write(path, text).unwrap();
}

/// Issue 16, item 2: for each drive-path effect, a sweep of the true rig (this file's
/// integrator) is diagnosed by `rigtwin diagnose --write-model`, and `rigtwin mpc --plant TRUE`
/// closes the loop on the true rig (the FMU's integrator) with the controller designed on the
/// declared model and on the diagnosed one; the PI baseline beside them. The table is printed
/// (`cargo test --test diagnose controller -- --nocapture`). What must hold whatever the tuning:
/// the diagnosed-model controller is stable and damps the shuffle better than the PI loops;
/// for the effects the prediction carries (dead time, lag, compliance) it overshoots less than
/// the declared-model controller; backlash is named as left out of the prediction.
#[test]
fn controller_on_the_diagnosed_model() {
    let dir = common::scratch("diagnose", "closed-loop");
    let cases = [
        ("time_delay", Truth { delay_s: 0.0063, set_point_nm: 40.0, ..Default::default() }, 31),
        ("actuator_lag", Truth { lag_s: 0.008, set_point_nm: 40.0, ..Default::default() }, 32),
        ("backlash", Truth { backlash_rad: 0.004, set_point_nm: 0.0, ..Default::default() }, 33),
        ("drive_compliance", Truth { compliance: Some((1500.0, 0.5)), set_point_nm: 40.0, ..Default::default() }, 34),
    ];
    let mut table = String::from(
        "effect            controller on                  overshoot %  settling s  RMS speed error rad/s  at bound %  stopped\n",
    );
    for (effect, truth, seed) in cases {
        let case = dir.join(effect);
        let bundle = write_bundle(&case, &sweep(&declared(), truth, seed), &declared());
        let model = case.join("diagnosed.toml");
        let out = rigtwin(&["diagnose", bundle.to_str().unwrap(), "--write-model", model.to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let true_file = case.join("true.toml");
        rig_file(&true_file, &declared(), &truth);
        let declared_file = case.join("declared.toml");
        rig_file(&declared_file, &declared(), &Truth::default());
        let mpc_on = |plant: &std::path::Path, params: &std::path::Path| -> serde_json::Value {
            let out = rigtwin(&[
                "mpc",
                "--json",
                "--plant",
                plant.to_str().unwrap(),
                "--params",
                params.to_str().unwrap(),
                // the figures must not depend on how loaded the test machine is
                "--time-limit-us",
                "100000",
            ]);
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            serde_json::from_slice(&out.stdout).unwrap()
        };
        let mpc = |params: &std::path::Path| mpc_on(&true_file, params);
        let (dec, diag) = (mpc(&declared_file), mpc(&model));
        let f = |v: &serde_json::Value, path: [&str; 2]| v[path[0]][path[1]].as_f64().unwrap_or(f64::NAN);
        let mut row = |who: &str, v: &serde_json::Value, side: &str| {
            let shuffle = &v["step_response"]["figures"][side];
            table += &format!(
                "{effect:17} {who:30} {:11.1} {:11.3} {:22.4} {:11.1}  {}\n",
                shuffle["overshoot"].as_f64().unwrap_or(f64::NAN) * 100.0,
                shuffle["settling_time_s"].as_f64().unwrap_or(f64::NAN),
                f(v, ["tracking_error_rms", side]),
                f(v, ["input_at_bound_share", side]) * 100.0,
                v["stopped"][side].as_str().unwrap_or("-")
            );
        };
        row("declared (MPC)", &dec, "mpc");
        row("diagnosed (MPC)", &diag, "mpc");
        row("PI baseline", &diag, "baseline");
        let over =
            |v: &serde_json::Value| v["step_response"]["figures"]["mpc"]["overshoot"].as_f64().unwrap_or(f64::INFINITY);
        assert!(diag["stopped"]["mpc"].is_null(), "{effect}: {}", diag["stopped"]);
        assert!(over(&diag) < v_pi(&diag), "{effect}: MPC {} vs PI {}", over(&diag), v_pi(&diag));
        if effect == "backlash" {
            let notes = diag["prediction"].to_string();
            assert!(notes.contains("NOT in the prediction"), "{notes}");
            // what the play costs: the same controller on the rig without it
            let free = mpc_on(&declared_file, &model);
            row("diagnosed, plant without play", &free, "mpc");
        } else {
            assert!(over(&diag) < over(&dec), "{effect}: diagnosed {} vs declared {}", over(&diag), over(&dec));
        }
    }
    eprintln!("closed loop on the true rig, 40 Nm drive-torque step at 10 rad/s:\n{table}");
}

fn v_pi(v: &serde_json::Value) -> f64 {
    v["step_response"]["figures"]["baseline"]["overshoot"].as_f64().unwrap()
}
