//! MATLAB `.mat` records (v5 and compressed v7, written by scipy.io.savemat from the example
//! bundles' CSV) read straight into the bundles: the same samples give the same diagnosis to
//! 1e-6; a time from a variable or from `sample_rate_hz`; v7.3, truncated and garbage files are
//! refused with the file named, never a panic.

mod common;

use std::path::Path;

use common::shared;
use std::process::Command;

fn make_mat(csv: &Path, out: &Path, compress: bool, vars: &[&str]) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/make_mat.py");
    let status = Command::new(common::python())
        .arg(script)
        .arg(csv)
        .arg(out)
        .arg(if compress { "1" } else { "0" })
        .args(vars)
        .status()
        .unwrap();
    assert!(status.success(), "make_mat.py failed");
}

fn diagnose(bundle: &Path, dir: &Path, tag: &str) -> serde_json::Value {
    let json = dir.join(format!("{tag}.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["diagnose", bundle.to_str().unwrap(), "--json", json.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

#[test]
fn a_sweep_in_a_mat_file_diagnoses_like_its_csv() {
    let d = common::scratch("records", "sweep");
    let reference = diagnose(&shared("v1_sweep_b.toml"), &d, "csv");
    let toml = std::fs::read_to_string(shared("v1_sweep_b.toml")).unwrap();
    let rpm = 60.0 / (2.0 * std::f64::consts::PI);
    for compress in [false, true] {
        let mat = d.join(format!("rec{}.mat", u8::from(compress)));
        make_mat(
            &shared("v1_sweep_b.csv"),
            &mat,
            compress,
            &[
                "t=time_s*1",
                "trq=torque_drive_Nm*1",
                &format!("n2=speed_m2_radps*{rpm}"),
                &format!("n3=speed_m3_radps*{rpm}"),
            ],
        );
        let bundle = d.join(format!("rec{}.toml", u8::from(compress)));
        let text = toml.replace("data = \"v1_sweep_b.csv\"", &format!("data = \"{}\"\ntime = \"t\"", mat.file_name().unwrap().to_str().unwrap()))
            + "\n[columns]\ntorque_drive_Nm = { channel = \"trq\" }\nspeed_m2_radps = { channel = \"n2\", unit = \"rpm\" }\nspeed_m3_radps = { channel = \"n3\", unit = \"rpm\" }\n";
        std::fs::write(&bundle, text).unwrap();
        let v = diagnose(&bundle, &d, &format!("mat{compress}"));
        assert_eq!(v["effect"], reference["effect"]);
        for (k, want) in reference["parameters"].as_object().unwrap() {
            let (got, want) = (v["parameters"][k].as_f64().unwrap(), want.as_f64().unwrap());
            assert!((got - want).abs() <= 1e-6 * want.abs(), "{k}: {got} vs {want} (compressed {compress})");
        }
    }
}

#[test]
fn a_drive_axis_in_a_mat_file_with_a_sample_rate_and_a_gain() {
    let d = common::scratch("records", "axis");
    // the force as a voltage of the drive's 35.15 N/V, the position in integer micrometres
    make_mat(
        &shared("axis_linear.csv"),
        &d.join("axis.mat"),
        true,
        &["vir=force_N*0.028449502133712661", "pos_i32=position_m*1000000"],
    );
    let toml = std::fs::read_to_string(shared("axis_linear.toml"))
        .unwrap()
        .replace("data = \"axis_linear.csv\"", "data = \"axis.mat\"\nsample_rate_hz = 1000.0")
        .replace("column = \"force_N\"", "column = \"vir\"\nunit = \"V\"\ngain = 35.15")
        .replace("column = \"position_m\"", "column = \"pos_i32\"\nunit = \"µm\"");
    std::fs::write(d.join("axis.toml"), toml).unwrap();
    let b = rigtwin::bundle::load_drive_test(&d.join("axis.toml")).unwrap();
    let si = rigtwin::bundle::load_drive_test(&shared("axis_linear.toml")).unwrap();
    assert!((b.dt_s - si.dt_s).abs() < 1e-12);
    for (x, y) in b.input_data[0].iter().zip(&si.input_data[0]) {
        assert!((x - y).abs() <= 1e-9 * y.abs().max(1.0), "{x} vs {y}");
    }
    // rounded to whole micrometres: within half a micrometre of the CSV
    for (x, y) in b.output_data[0].iter().zip(&si.output_data[0]) {
        assert!((x - y).abs() <= 0.5e-6 + 1e-12, "{x} vs {y}");
    }
    assert_eq!(b.conversions.len(), 2, "{:?}", b.conversions);
}

#[test]
fn v73_truncated_and_garbage_mat_files_are_refused() {
    let d = common::scratch("records", "bad");
    make_mat(&shared("axis_linear.csv"), &d.join("good.mat"), true, &["t=time_s*1", "f=force_N*1", "x=position_m*1"]);
    let good = std::fs::read(d.join("good.mat")).unwrap();
    let mut v73 = b"MATLAB 7.3 MAT-file, Platform: GLNXA64".to_vec();
    v73.resize(1024, 0);
    let mut flipped = good.clone();
    for k in (200..flipped.len()).step_by(37) {
        flipped[k] ^= 0x5a;
    }
    for (name, bytes, expect) in [
        ("v73.mat", v73, "v7.3"),
        ("short.mat", good[..good.len() / 2].to_vec(), "short.mat"),
        ("flipped.mat", flipped, "flipped.mat"),
        ("text.mat", b"time_s,force_N\n0,1\n".to_vec(), "not a MATLAB"),
    ] {
        std::fs::write(d.join(name), &bytes).unwrap();
        let r = std::panic::catch_unwind(|| rigtwin::bundle::read_mat(&d.join(name), &["t", "f"]));
        let e = r.expect("no panic").expect_err("refused").to_string();
        assert!(e.contains(expect), "{name}: {e}");
    }
    // through the command line: the file named, exit 1, no panic message
    let sweep = std::fs::read_to_string(shared("v1_sweep_b.toml"))
        .unwrap()
        .replace("data = \"v1_sweep_b.csv\"", "data = \"flipped.mat\"");
    std::fs::write(d.join("sweep.toml"), sweep).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["diagnose", d.join("sweep.toml").to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked") && stderr.contains("flipped.mat"), "{stderr}");
    let toml = std::fs::read_to_string(shared("axis_linear.toml"))
        .unwrap()
        .replace("data = \"axis_linear.csv\"", "data = \"flipped.mat\"");
    std::fs::write(d.join("flipped.toml"), toml).unwrap();
    let r = std::panic::catch_unwind(|| rigtwin::bundle::load_drive_test(&d.join("flipped.toml")));
    let e = r.expect("no panic").expect_err("refused").to_string();
    assert!(e.contains("flipped.mat"), "{e}");
    let e = rigtwin::bundle::read_mat(&d.join("good.mat"), &["t", "speed"]).unwrap_err().to_string();
    assert!(e.contains("no variable `speed`") && e.contains("f, t, x") || e.contains("no variable `speed`"), "{e}");
}

fn make_mf4(out: &Path, mode: &str) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/make_mf4.py");
    let status =
        Command::new(common::python()).arg(script).arg(shared("v1_sweep_b.csv")).arg(out).arg(mode).status().unwrap();
    assert!(status.success(), "make_mf4.py failed");
}

/// An MDF 4 file written by asammdf: with every channel in one compressed group the diagnosis
/// equals the CSV's (the channels' own units, rpm, are applied); with the torque in a second
/// group at half the rate (in kNm) the channels are resampled onto the speeds' 1 kHz by linear
/// interpolation, and the diagnosis finds the same effect with its parameter within 5 % (the
/// interpolation error of a 30 Hz sine sampled at 500 Hz is about 0.2 % of its amplitude).
#[test]
fn a_sweep_in_an_mdf4_file_diagnoses_like_its_csv() {
    let d = common::scratch("records", "mf4");
    let reference = diagnose(&shared("v1_sweep_b.toml"), &d, "csv");
    let toml = std::fs::read_to_string(shared("v1_sweep_b.toml")).unwrap();
    for mode in ["one", "two"] {
        let mf4 = d.join(format!("{mode}.mf4"));
        make_mf4(&mf4, mode);
        let bundle = d.join(format!("{mode}.toml"));
        let text = toml.replace("data = \"v1_sweep_b.csv\"", &format!("data = \"{mode}.mf4\""))
            + "\n[columns]\ntorque_drive_Nm = { channel = \"Trq_Drv\" }\nspeed_m2_radps = { channel = \"n_M2\" }\nspeed_m3_radps = { channel = \"n_M3\" }\n";
        std::fs::write(&bundle, text).unwrap();
        let v = diagnose(&bundle, &d, mode);
        assert_eq!(v["effect"], reference["effect"], "{mode}");
        let tol = if mode == "one" { 1e-6 } else { 0.05 };
        for (k, want) in reference["parameters"].as_object().unwrap() {
            let (got, want) = (v["parameters"][k].as_f64().unwrap(), want.as_f64().unwrap());
            assert!((got - want).abs() <= tol * want.abs(), "{mode} {k}: {got} vs {want}");
        }
        let conversions = v["conversions"].to_string();
        assert!(conversions.contains("n_M2 [rpm]"), "{conversions}");
        if mode == "two" {
            assert!(
                conversions.contains("Trq_Drv [kNm]") && conversions.contains("linear interpolation"),
                "{conversions}"
            );
        }
    }
    // a channel the file does not have, and a file that is not MDF
    let bad = toml.replace("data = \"v1_sweep_b.csv\"", "data = \"one.mf4\"");
    std::fs::write(d.join("bad.toml"), bad).unwrap();
    let e = rigtwin::bundle::load_torsional(&d.join("bad.toml")).unwrap_err().to_string();
    assert!(e.contains("one.mf4") && e.contains("no channel `torque_drive_Nm`"), "{e}");
    std::fs::write(d.join("not.mf4"), b"MDF     4.10    garbage").unwrap();
    let text = toml.replace("data = \"v1_sweep_b.csv\"", "data = \"not.mf4\"");
    std::fs::write(d.join("not.toml"), text).unwrap();
    let e = rigtwin::bundle::load_torsional(&d.join("not.toml")).unwrap_err().to_string();
    assert!(e.contains("not.mf4"), "{e}");
}

/// `--save-signals`: the saved measured and simulated speeds give back the report's errors
/// (‖y − ŷ‖/‖y‖ over both speeds, recomputed here from the CSV's columns), one row per sample.
#[test]
fn saved_signals_reproduce_the_reported_errors() {
    let d = common::scratch("records", "save");
    let (json, csv) = (d.join("d.json"), d.join("signals.csv"));
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["diagnose", shared("v1_sweep_b.toml").to_str().unwrap()])
        .args(["--json", json.to_str().unwrap(), "--save-signals", csv.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|c| c.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 60_000);
    let (mut meas, mut before, mut after) = (0.0, 0.0, 0.0);
    for r in &rows {
        for m in ["m2", "m3"] {
            let y = r[col(&format!("speed_{m}_measured_radps"))];
            meas += y * y;
            before += (y - r[col(&format!("speed_{m}_declared_radps"))]).powi(2);
            after += (y - r[col(&format!("speed_{m}_extended_radps"))]).powi(2);
            assert!(
                (r[col(&format!("speed_{m}_residual_extended_radps"))]
                    - (y - r[col(&format!("speed_{m}_extended_radps"))]))
                .abs()
                    < 1e-8
            );
        }
    }
    let (eb, ea) = ((before / meas).sqrt(), (after / meas).sqrt());
    // 10 printed digits per value: the recomputed errors agree to far better than 1e-6
    assert!((eb - v["error_before"].as_f64().unwrap()).abs() < 1e-6 * eb, "{eb} vs {}", v["error_before"]);
    assert!((ea - v["error_after"].as_f64().unwrap()).abs() < 1e-6 * ea, "{ea} vs {}", v["error_after"]);
    // a shake test: one row per excited line, the four impedances measured, declared, extended
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["diagnose", shared("sfd_shake.toml").to_str().unwrap(), "--save-signals", csv.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("frequency_hz,Hxx_measured_re_N_per_m"));
    assert_eq!(text.lines().next().unwrap().split(',').count(), 25);
    assert!(text.lines().count() > 20);
}

/// Stamps with a repeated sample and a gap: refused with the line and the way out named; with
/// `resample = true` the repeated stamp is dropped and the gap bridged linearly onto the median
/// step — exact for signals linear in time, as these are (input 2 t + 1, output 3 − t).
#[test]
fn irregular_stamps_are_refused_unless_resampling_is_asked_for() {
    let dir = common::scratch("records", "resample");
    let mut stamps: Vec<f64> = (0..3000).map(|k| k as f64 * 1e-3).collect();
    stamps.insert(1200, 1.199); // a repeated stamp (data line 1202)
    stamps.retain(|t| !(2.0..2.0049).contains(t)); // five samples missing: a 6 ms gap
    let mut csv = String::from("time_s,force_N,position_m\n");
    for t in &stamps {
        csv += &format!("{t:.6},{:.9},{:.9}\n", 2.0 * t + 1.0, 3.0 - t);
    }
    std::fs::write(dir.join("a.csv"), csv).unwrap();
    let bundle = |resample: &str| {
        format!("kind = \"drive_test\"\ndata = \"a.csv\"\ndomain = \"translational\"\n{resample}[model]\nbodies = [{{ name = \"carriage\", inertia = 20.0, drag = 60.0 }}]\n[[inputs]]\ncolumn = \"force_N\"\nbody = 1\n[[outputs]]\ncolumn = \"position_m\"\nbody = 1\nquantity = \"position\"\n")
    };
    std::fs::write(dir.join("b.toml"), bundle("")).unwrap();
    let e = rigtwin::bundle::load_drive_test(&dir.join("b.toml")).unwrap_err().to_string();
    assert!(e.contains("a.csv") && e.contains("a.csv:1202:") && e.contains("resample = true"), "{e}");
    std::fs::write(dir.join("b.toml"), bundle("resample = true\n")).unwrap();
    let b = rigtwin::bundle::load_drive_test(&dir.join("b.toml")).unwrap();
    assert!((b.dt_s - 1e-3).abs() < 1e-12, "{}", b.dt_s);
    assert_eq!(b.input_data[0].len(), 3000);
    for (k, (u, y)) in b.input_data[0].iter().zip(&b.output_data[0]).enumerate() {
        let t = k as f64 * 1e-3;
        assert!((u - (2.0 * t + 1.0)).abs() < 1e-9 && (y - (3.0 - t)).abs() < 1e-9, "sample {k}: {u} {y}");
    }
    let note = b.conversions.join("; ");
    assert!(note.contains("1 samples with a repeated") && note.contains("largest gap 0.006"), "{note}");
    // a sample rate has no stamps to resample
    std::fs::write(dir.join("b.toml"), bundle("resample = true\nsample_rate_hz = 1000.0\n")).unwrap();
    assert!(rigtwin::bundle::load_drive_test(&dir.join("b.toml")).unwrap_err().to_string().contains("sample_rate_hz"));
}
