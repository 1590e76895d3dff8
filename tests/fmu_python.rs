//! The FMUs in the tools engineers check them with (fmpy, fmutool, OSP libcosim), against
//! `plant`'s own solution of the same model.

mod common;

use std::process::Command;

use nalgebra::{DMatrix, DVector};
use plant::Output;
use rigtwin_fmu::RigPlant;
use serde_json::Value;

/// A rig file with drive-path effects (dead time, actuator lag, drive compliance) on the
/// default rig, whose FMUs get the model-exchange check at default settings too.
const EFFECTS_RIG: &str = r#"
variant = "V1"
[model]
j_m2 = 0.9148
j_drive = 0.529
j_m3 = 0.9148
c_short = 1479.0
c_long = 1150.33
c_delta = 64330.0
d_short = 1.12
d_long = 0.87
load_drag = 0.5
[effects]
time_delay_s = 0.002
actuator_lag_s = 0.005
compliance_stiffness_nm_per_rad = 3000.0
"#;

fn report() -> Value {
    let dir = common::fmu_dir();
    let effects = dir.join("effects");
    std::fs::create_dir_all(&effects).unwrap();
    let rig = effects.join("rig.toml");
    std::fs::write(&rig, EFFECTS_RIG).unwrap();
    let made = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["fmu", "--params", rig.to_str().unwrap(), "--out", effects.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    let drive = dir.join("drive");
    std::fs::create_dir_all(&drive).unwrap();
    let bench = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/bench_gear.toml");
    let made = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["fmu", "--params", bench.to_str().unwrap(), "--out", drive.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fmu_checks.py");
    let out =
        Command::new(common::python()).arg(script).arg(dir).arg(&effects).arg(&drive).output().expect("run python");
    assert!(out.status.success(), "fmu_checks.py failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(dir.join("report.json")).expect("fmu_checks.py writes report.json");
    serde_json::from_str(&text).expect("JSON from fmu_checks.py")
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// The default powertrain as `plant` builds it: the reference every FMU run is held to.
fn powertrain() -> plant::StateSpace {
    let p = RigPlant::default();
    p.powertrain
        .open_differential(p.variant)
        .unwrap()
        .state_space(&[Output::Angles, Output::Speeds, Output::SpringTorques])
        .unwrap()
}

/// Frequency of the largest peak of the discrete-time Fourier transform |X(f)| of x − mean in
/// [lo, hi] Hz: the largest value on a grid of 1/(8T) Hz (T the record's length; the main lobe
/// is 2/T wide, so the grid cannot step over the peak), then a golden-section search within one
/// grid step either side. X(f) = Σ x_k e^{−i2πf k dt} is summed with the phase advanced by one
/// complex product per sample.
fn spectral_peak_hz(x: &[f64], dt: f64, lo: f64, hi: f64) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let magnitude = |f: f64| {
        let (c, s) = ((2.0 * std::f64::consts::PI * f * dt).cos(), -(2.0 * std::f64::consts::PI * f * dt).sin());
        let (mut pr, mut pi, mut re, mut im) = (1.0, 0.0, 0.0, 0.0);
        for v in x {
            re += (v - mean) * pr;
            im += (v - mean) * pi;
            (pr, pi) = (pr * c - pi * s, pr * s + pi * c);
        }
        re.hypot(im)
    };
    let step = 1.0 / (8.0 * x.len() as f64 * dt);
    let points = ((hi - lo) / step).ceil() as usize;
    let grid: Vec<(f64, f64)> = (0..=points).map(|k| lo + k as f64 * step).map(|f| (f, magnitude(f))).collect();
    let best = grid.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap().0;
    // golden section: each step keeps one inner point and its value, and evaluates one new one
    let (mut a, mut b) = ((best - step).max(lo), (best + step).min(hi));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut mc, mut md) = (magnitude(c), magnitude(d));
    while b - a > 1e-9 * b.abs().max(1.0) {
        if mc > md {
            (b, d, md) = (d, c, mc);
            c = b - g * (b - a);
            mc = magnitude(c);
        } else {
            (a, c, mc) = (c, d, md);
            d = a + g * (b - a);
            md = magnitude(d);
        }
    }
    0.5 * (a + b)
}

#[test]
fn fmus_pass_validation_simulate_like_the_plant_and_run_in_libcosim() {
    let r = report();
    for v in ["fmi3", "fmi2"] {
        assert_eq!(r["validate"][v].as_array().unwrap().len(), 0, "fmpy validate {v}: {}", r["validate"][v]);
        let t = &r["fmutool"][v];
        assert_eq!(t["returncode"], 0, "{}", t["output"]);
        assert!(t["output"].as_str().unwrap().contains("No semantic error"), "{}", t["output"]);
    }

    // Free response: oscillates at the damped shuffle frequency of plant's model (0.5 %).
    let ss = powertrain();
    let shuffle = ss.damp().unwrap().into_iter().max_by(|a, b| a.natural_hz.total_cmp(&b.natural_hz)).unwrap();
    for key in ["fmi3_cs", "fmi3_me", "fmi2_cs", "fmi2_me"] {
        let w = floats(&r["free"][key]["w_drive"]);
        let f = spectral_peak_hz(&w, 1e-3, 0.0, 500.0);
        assert!(
            (f / shuffle.damped_hz - 1.0).abs() < 0.005,
            "{key}: spectral peak {f} Hz vs shuffle {} Hz",
            shuffle.damped_hz
        );
    }

    // Model exchange at fmpy's default solver settings (rtol 1e-5, atol = rtol · nominal): the
    // ring after a drive-torque step at the co-simulation frequency within 0.2 % (the bound of
    // the issue; with absolute angles as states it was 1.8 % off). The ring is taken from the
    // speed's first difference over the 2 s after the step (the slow rise, time constant
    // ≈ 2.4 s, is then almost constant) and searched in 8-20 Hz.
    for set in ["default", "effects"] {
        for v in ["fmi3", "fmi2"] {
            let ring = |kind: &str| {
                let s = &r["defaults"][format!("{set}_{v}_{kind}")];
                let (t, w) = (floats(&s["time"]), floats(&s["w_m2"]));
                let after: Vec<f64> =
                    t.iter().zip(&w).filter(|(t, _)| **t > 0.1 && **t <= 2.1).map(|(_, w)| *w).collect();
                let diff: Vec<f64> = after.windows(2).map(|p| p[1] - p[0]).collect();
                spectral_peak_hz(&diff, 1e-3, 8.0, 20.0)
            };
            let (cs, me) = (ring("cs"), ring("me"));
            eprintln!("{set} {v}: ring at fmpy's ME defaults {me:.4} Hz, CS {cs:.4} Hz");
            assert!((me / cs - 1.0).abs() < 0.002, "{set} {v}: ME at defaults {me} Hz vs CS {cs} Hz");
            if set == "default" {
                assert!((cs / shuffle.damped_hz - 1.0).abs() < 0.005, "{v}: CS ring {cs} Hz");
            }
        }
    }

    // A drive model spun up to 10^4 rad (bench_gear, 1 N m on the motor for 20 s): model exchange
    // at fmpy's defaults (CVode, rtol 1e-4, atol = rtol * nominal) keeps the couplings' torques
    // within 1 % of their peak of the exact co-simulation (measured 0.4 %: the twists are
    // states with a 1 mrad nominal; with absolute angles as states the torque was off by 18 N m,
    // four times its peak, the twist lost in the angles' digits)
    for v in ["fmi3", "fmi2"] {
        let spin = |kind: &str| &r["drive_spin"][format!("{v}_{kind}")];
        assert!(floats(&spin("cs")["phi_load"]).last().unwrap() > &5000.0, "the load spun up");
        for name in ["T_coupling_1", "T_coupling_2"] {
            let (cs, me) = (floats(&spin("cs")[name]), floats(&spin("me")[name]));
            let peak = cs.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let worst = cs.iter().zip(&me).fold(0.0f64, |a, (c, m)| a.max((c - m).abs()));
            eprintln!("drive {v} {name}: ME at defaults within {worst:.2e} N m of CS (peak {peak:.3} N m)");
            assert!(worst < 0.01 * peak, "drive {v} {name}: ME at defaults off by {worst} N m (peak {peak})");
        }
    }

    // Drive-torque step: plant's exact (zero-order-hold) solution, 1e-6 of each signal's range.
    let n = 1001;
    let u = DMatrix::from_fn(n, 3, |_, j| if j == 1 { 10.0 } else { 0.0 });
    let y = ss.lsim(&u, 1e-3, &DVector::zeros(6)).unwrap();
    let col = |name: &str| ss.output_names.iter().position(|o| o == name).unwrap();
    for key in ["fmi3_cs", "fmi3_me", "fmi2_cs", "fmi2_me"] {
        let s = &r["step"][key];
        assert_eq!(floats(&s["time"]).len(), n, "{key}");
        for (fmu_name, plant_name) in [
            ("w_m2", "w_m2"),
            ("w_drive", "w_drive"),
            ("phi_drive", "phi_drive"),
            ("T_short", "T_short_side_shaft"),
            ("T_long", "T_long_side_shaft"),
        ] {
            let got = floats(&s[fmu_name]);
            let want: Vec<f64> = (0..n).map(|k| y[(k, col(plant_name))]).collect();
            let range = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let err = got.iter().zip(&want).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(err <= 1e-6 * range, "{key} {fmu_name}: max error {err} vs range {range}");
        }
    }

    // FMU state: restoring it (also from its serialized bytes) repeats the same 100 steps exactly
    for v in ["fmi3", "fmi2"] {
        let st = &r["state"][v];
        assert_eq!(floats(&st["first"]), floats(&st["again"]), "{v}: set FMU state");
        assert_eq!(floats(&st["first"]), floats(&st["from_bytes"]), "{v}: deserialized FMU state");
    }
    // Directional derivatives against plant's matrices. The state is the twist s = 2φ_drive −
    // φ_m2 − φ_m3, and the stiffness acts through s only, so a change of s is a change of
    // φ_drive by half of it: ∂ẇ_drive/∂s = −K[1,1]/(2 J_drive), ∂T_short/∂s = half the torque
    // row's φ_drive entry; ∂ẇ_drive/∂M_drive = 1/J_drive; φ_drive = (s + φ_m2 + φ_m3)/2.
    let p = RigPlant::default();
    let m = p.powertrain.open_differential(p.variant).unwrap();
    let k = m.stiffness_matrix();
    let j = p.powertrain.j_drive;
    let torque_row = &m.springs[0];
    for v in ["fmi3", "fmi2"] {
        let d = &r["derivative"][v];
        let close =
            |got: f64, want: f64| assert!((got - want).abs() <= 1e-12 * want.abs().max(1.0), "{v}: {got} vs {want}");
        close(floats(&d["dwdot_dtwist"])[0], -k[(1, 1)] / (2.0 * j));
        close(floats(&d["dwdot_dM"])[0], 1.0 / j);
        close(floats(&d["dT_dtwist"])[0], torque_row.stiffness * torque_row.elongation[1] / 2.0);
        close(floats(&d["dphi_dtwist"])[0], 0.5);
        close(floats(&d["dphi_dphi_m2"])[0], 0.5);
    }

    // libcosim ran the FMI 2 FMU from the same twist: compare with plant's free response at 0.5 s.
    let lc = &r["libcosim"];
    assert_eq!(lc["ok"], true);
    let mut x0 = DVector::zeros(6);
    x0[1] = 0.01;
    let y = ss.lsim(&DMatrix::zeros(501, 3), 1e-3, &x0).unwrap();
    let w_plant = y[(500, col("w_drive"))];
    let w = lc["w_drive"].as_f64().unwrap();
    let scale = (0..501).map(|k| y[(k, col("w_drive"))].abs()).fold(0.0, f64::max);
    assert!((w - w_plant).abs() <= 1e-6 * scale, "libcosim w_drive {w} vs plant {w_plant}");

    // Ecos ran both FMUs from the same twist: plant's free response at the time it reached.
    for v in ["fmi3", "fmi2"] {
        let e = &r["ecos"][v];
        let t = e["time_s"].as_f64().unwrap();
        let k = (t / 1e-3).round() as usize;
        assert!((t - k as f64 * 1e-3).abs() < 1e-9 && k > 400, "{v}: Ecos stopped at {t} s");
        let w = e["w_drive"].as_f64().unwrap();
        let w_plant = y[(k, col("w_drive"))];
        assert!((w - w_plant).abs() <= 1e-6 * scale, "Ecos {v} w_drive {w} vs plant {w_plant} at {t} s");
    }
}
