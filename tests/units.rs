//! Channels as rigs record them — rpm, ms, a torque as a voltage times a sensor gain, µm, lbf,
//! other column names — mapped by a bundle's `[columns]` (or a drive_test signal's `unit`,
//! `gain`, `offset`) give the same diagnosis and identification as the SI originals. The
//! converted files are written here from the example bundles with 17 significant digits, so
//! the samples agree to round-off and the results to 1e-6 relative.

mod common;

use std::path::Path;

use common::shared;
use std::process::Command;

use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).output().unwrap();
    assert!(out.status.success(), "rigtwin {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|_| {
        let file = args.iter().position(|a| *a == "--json").map(|i| args[i + 1]).unwrap();
        serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap()
    })
}

/// Writes `csv` with each column transformed: (new header, function of the SI value).
fn convert_csv(from: &Path, to: &Path, columns: &[(&str, &dyn Fn(f64) -> f64)]) {
    let text = std::fs::read_to_string(from).unwrap();
    let mut out = String::new();
    out += &columns.iter().map(|c| c.0).collect::<Vec<_>>().join(",");
    out += "\n";
    for line in text.lines().skip(1) {
        let cells: Vec<f64> = line.split(',').map(|c| c.trim().parse().unwrap()).collect();
        let row: Vec<String> = cells.iter().zip(columns).map(|(v, c)| format!("{:.17e}", (c.1)(*v))).collect();
        out += &row.join(",");
        out += "\n";
    }
    std::fs::write(to, out).unwrap();
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

#[test]
fn a_sweep_in_rpm_ms_and_volts_diagnoses_like_the_si_original() {
    let d = common::scratch("units", "sweep");
    let to_rpm = |w: f64| w * 60.0 / (2.0 * std::f64::consts::PI);
    convert_csv(
        &shared("v1_sweep_b.csv"),
        &d.join("rec.csv"),
        &[("t", &|t| t * 1000.0), ("U_trq", &|m| m / 20.0 - 0.1), ("n_M2", &to_rpm), ("n_M3", &to_rpm)],
    );
    let toml = std::fs::read_to_string(shared("v1_sweep_b.toml")).unwrap();
    let toml = toml.replace("data = \"v1_sweep_b.csv\"", "data = \"rec.csv\"")
        + "\n[columns]\ntime_s = { channel = \"t\", unit = \"ms\" }\n\
           torque_drive_Nm = { channel = \"U_trq\", unit = \"V\", gain = 20.0, offset = 2.0 }\n\
           speed_m2_radps = { channel = \"n_M2\", unit = \"rpm\" }\n\
           speed_m3_radps = { channel = \"n_M3\", unit = \"rpm\" }\n";
    std::fs::write(d.join("rec.toml"), toml).unwrap();
    let (a_json, b_json) = (d.join("a.json"), d.join("b.json"));
    let a = json(&["diagnose", shared("v1_sweep_b.toml").to_str().unwrap(), "--json", a_json.to_str().unwrap()]);
    let b = json(&["diagnose", d.join("rec.toml").to_str().unwrap(), "--json", b_json.to_str().unwrap()]);
    assert_eq!(a["effect"], b["effect"]);
    for (k, v) in a["parameters"].as_object().unwrap() {
        let (x, y) = (v.as_f64().unwrap(), b["parameters"][k].as_f64().unwrap());
        assert!(close(x, y, 1e-6), "{k}: {x} vs {y}");
    }
    assert!(close(a["error_after"].as_f64().unwrap(), b["error_after"].as_f64().unwrap(), 1e-6));
    let conv = b["conversions"].to_string();
    assert!(conv.contains("n_M2 [rpm]") && conv.contains("U_trq [V]") && conv.contains("t [ms]"), "{conv}");
    assert_eq!(a["conversions"], serde_json::json!([]));
    // parametrise's frequency estimate reads the same samples
    let x = rigtwin::bundle::load_torsional(&d.join("rec.toml")).unwrap();
    let y = rigtwin::bundle::load_torsional(&shared("v1_sweep_b.toml")).unwrap();
    assert!(close(x.sweep.dt_s, y.sweep.dt_s, 1e-12));
    let (fx, fy) = (
        x.sweep.analyse(&Default::default()).unwrap().modal_fit.frequency_hz,
        y.sweep.analyse(&Default::default()).unwrap().modal_fit.frequency_hz,
    );
    assert!(close(fx, fy, 1e-6), "{fx} vs {fy} Hz");
}

#[test]
fn a_shake_test_in_micrometres_and_pound_force_identifies_like_the_si_original() {
    let d = common::scratch("units", "shake");
    let lbf = 4.4482216152605;
    for name in ["sfd_shake_x.csv", "sfd_shake_y.csv"] {
        convert_csv(
            &shared(name),
            &d.join(name),
            &[("time_s", &|t| t), ("Fx", &|f| f / lbf), ("Fy", &|f| f / lbf), ("x", &|x| x * 1e6), ("y", &|x| x * 1e6)],
        );
    }
    let toml = std::fs::read_to_string(shared("sfd_shake.toml")).unwrap()
        + "\n[columns]\nforce_x_N = { channel = \"Fx\", unit = \"lbf\" }\nforce_y_N = { channel = \"Fy\", unit = \"lbf\" }\n\
           disp_x_m = { channel = \"x\", unit = \"µm\" }\ndisp_y_m = { channel = \"y\", unit = \"um\" }\n";
    std::fs::write(d.join("sfd.toml"), toml).unwrap();
    let a = json(&["bearing", shared("sfd_shake.toml").to_str().unwrap(), "--json"]);
    let b = json(&["bearing", d.join("sfd.toml").to_str().unwrap(), "--json"]);
    for key in ["K_N_per_m", "C_Ns_per_m"] {
        for i in 0..2 {
            let (x, y) = (a[key][i][i].as_f64().unwrap(), b[key][i][i].as_f64().unwrap());
            assert!(close(x, y, 1e-6), "{key}[{i}][{i}]: {x} vs {y}");
        }
    }
    assert!(b["conversions"].to_string().contains("x [µm]"));
}

#[test]
fn a_unit_of_the_wrong_dimension_is_refused_with_the_key() {
    let d = common::scratch("units", "wrong");
    std::fs::copy(shared("v1_sweep_b.csv"), d.join("v1_sweep_b.csv")).unwrap();
    let base = std::fs::read_to_string(shared("v1_sweep_b.toml")).unwrap();
    for (columns, words) in [
        ("speed_m2_radps = { unit = \"Nm\" }", vec!["columns.speed_m2_radps", "a torque", "an angular speed"]),
        ("torque_drive_Nm = { unit = \"V\" }", vec!["columns.torque_drive_Nm", "gain"]),
        ("speed_m3_radps = { unit = \"furlong/fortnight\" }", vec!["columns.speed_m3_radps", "not known", "rpm"]),
        ("speed_m4_radps = { unit = \"rpm\" }", vec!["columns.speed_m4_radps", "speed_m3_radps"]),
        ("time_s = { channel = \"clock\" }", vec!["v1_sweep_b.csv:1", "clock"]),
    ] {
        std::fs::write(d.join("b.toml"), format!("{base}\n[columns]\n{columns}\n")).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
            .args(["diagnose", d.join("b.toml").to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        let e = String::from_utf8_lossy(&out.stderr);
        for w in words {
            assert!(e.contains(w), "`{w}` missing in: {e}");
        }
    }
    // a drive_test signal recorded in volts with the drive's gain, and in degrees
    std::fs::copy(shared("axis_linear.csv"), d.join("axis_linear.csv")).unwrap();
    let axis = std::fs::read_to_string(shared("axis_linear.toml")).unwrap();
    let wrong = axis.replace("column = \"position_m\"", "column = \"position_m\"\nunit = \"deg\"");
    std::fs::write(d.join("a.toml"), wrong).unwrap();
    let e = rigtwin::bundle::load_drive_test(&d.join("a.toml")).unwrap_err().to_string();
    assert!(e.contains("outputs[1]") && e.contains("an angle") && e.contains("a length"), "{e}");
    let mm = axis.replace("column = \"position_m\"", "column = \"position_m\"\nunit = \"mm\"");
    std::fs::write(d.join("a.toml"), mm).unwrap();
    let a = rigtwin::bundle::load_drive_test(&d.join("a.toml")).unwrap();
    let si = rigtwin::bundle::load_drive_test(&shared("axis_linear.toml")).unwrap();
    assert!(a.output_data[0].iter().zip(&si.output_data[0]).all(|(x, y)| close(*x, 1e-3 * y, 1e-15)));
    assert_eq!(a.conversions.len(), 1, "{:?}", a.conversions);
}
