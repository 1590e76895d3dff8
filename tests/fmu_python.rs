//! The FMUs in the tools engineers check them with (fmpy, fmutool, OSP libcosim), against
//! `plant`'s own solution of the same model.

mod common;

use std::process::Command;

use nalgebra::{DMatrix, DVector};
use plant::Output;
use rigtwin_fmu::FmuParams;
use serde_json::Value;

fn report() -> Value {
    let dir = common::fmu_dir();
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fmu_checks.py");
    let out = Command::new(common::python()).arg(script).arg(dir).output().expect("run python");
    assert!(out.status.success(), "fmu_checks.py failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(dir.join("report.json")).expect("fmu_checks.py writes report.json");
    serde_json::from_str(&text).expect("JSON from fmu_checks.py")
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// The default powertrain as `plant` builds it: the reference every FMU run is held to.
fn powertrain() -> plant::StateSpace {
    let p = FmuParams::default();
    p.powertrain
        .open_differential(p.variant)
        .unwrap()
        .state_space(&[Output::Angles, Output::Speeds, Output::SpringTorques])
        .unwrap()
}

/// Frequency of the largest peak of |FFT(x − mean)|, zero-padded 64×, refined by a parabola
/// through the three largest bins.
fn fft_peak_hz(x: &[f64], dt: f64) -> f64 {
    use rustfft::{num_complex::Complex64, FftPlanner};
    let n = (x.len() * 64).next_power_of_two();
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let mut buf: Vec<Complex64> = x
        .iter()
        .map(|v| Complex64::new(v - mean, 0.0))
        .chain(std::iter::repeat(Complex64::new(0.0, 0.0)))
        .take(n)
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let mag: Vec<f64> = buf[..n / 2].iter().map(|c| c.norm()).collect();
    let k = (1..mag.len() - 1).max_by(|&a, &b| mag[a].total_cmp(&mag[b])).unwrap();
    let (a, b, c) = (mag[k - 1].ln(), mag[k].ln(), mag[k + 1].ln());
    let shift = 0.5 * (a - c) / (a - 2.0 * b + c);
    (k as f64 + shift) / (n as f64 * dt)
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
        let f = fft_peak_hz(&w, 1e-3);
        assert!(
            (f / shuffle.damped_hz - 1.0).abs() < 0.005,
            "{key}: FFT peak {f} Hz vs shuffle {} Hz",
            shuffle.damped_hz
        );
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
    // Directional derivatives against plant's matrices: ∂ẇ_drive/∂φ_drive = −C[1,1]/J_drive,
    // ∂ẇ_drive/∂M_drive = 1/J_drive, ∂T_short/∂φ_drive = the torque row's angle entry.
    let p = FmuParams::default();
    let m = p.powertrain.open_differential(p.variant).unwrap();
    let k = m.stiffness_matrix();
    let j = p.powertrain.j_drive;
    let torque_row = &m.springs[0];
    for v in ["fmi3", "fmi2"] {
        let d = &r["derivative"][v];
        let close =
            |got: f64, want: f64| assert!((got - want).abs() <= 1e-12 * want.abs().max(1.0), "{v}: {got} vs {want}");
        close(floats(&d["dwdot_dphi"])[0], -k[(1, 1)] / j);
        close(floats(&d["dwdot_dM"])[0], 1.0 / j);
        close(floats(&d["dT_dphi"])[0], torque_row.stiffness * torque_row.elongation[1]);
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
}
