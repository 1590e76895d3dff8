//! The measurement bundles of ../shared/data end to end, and bad bundles.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn rigtwin(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).output().expect("run rigtwin")
}

fn data(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(name);
    assert!(p.exists(), "{} is missing: the example bundles belong beside the repository", p.display());
    p.to_str().unwrap().to_string()
}

fn json(args: &[&str]) -> Value {
    let out = rigtwin(args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

#[test]
fn variant_bundles_parametrise_end_to_end() {
    let files: Vec<String> =
        ["variant_V1.toml", "variant_V2.toml", "variant_V3.toml", "variant_V4.toml"].map(data).to_vec();
    let mut args = vec!["parametrise", "--json", "--samples", "300"];
    args.extend(files.iter().map(|s| s.as_str()));
    let v = json(&args);
    // contract
    for k in ["V1", "V2", "V3", "V4"] {
        assert!(v["measured_hz"][k].as_f64().unwrap() > 1.0);
    }
    let e = &v["estimate"];
    assert_eq!(e["model"], "differential");
    let (j, c) = (e["j_drive"].as_f64().unwrap(), e["c_short"].as_f64().unwrap());
    let jci: Vec<f64> = e["j_drive_ci95"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let cci: Vec<f64> = e["c_short_ci95"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert!(jci[0] < j && j < jci[1] && cci[0] < c && c < cci[1]);
    // Physics, not numbers from the code: every informative pair is an independent solution
    // of the same rig; the open-differential model must make them agree (within 3 %), the
    // measured shuffle frequencies must fall from V1 (stiffest) to V2 (softest) (section 3),
    // and both load machines must swing in phase (section 4.4).
    let pairs = v["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 6);
    let mut n = 0;
    for p in pairs {
        for s in p["solutions"].as_array().unwrap() {
            assert_eq!(s["shuffle"], true);
            assert!((s["j_drive"].as_f64().unwrap() / j - 1.0).abs() < 0.03, "{p}");
            assert!((s["c_short"].as_f64().unwrap() / c - 1.0).abs() < 0.03, "{p}");
            n += 1;
        }
    }
    assert!(n >= 5, "five of six pairs inform j_drive and c_short");
    let f = |k: &str| v["measured_hz"][k].as_f64().unwrap();
    assert!(f("V1") > f("V3") && f("V1") > f("V4") && f("V3") > f("V2") && f("V4") > f("V2"));
    for m in v["measurements"].as_array().unwrap() {
        assert_eq!(m["mode_seen"], "shuffle");
    }
    // the smooth strand cannot explain an open-differential rig (V3 = V4 there, but not in eq. 14)
    let chi_smooth = v["other_model"]["chi2"].as_f64().unwrap();
    assert!(chi_smooth > 100.0 * e["chi2"].as_f64().unwrap(), "{chi_smooth}");
}

#[test]
fn typed_in_frequencies_reproduce_table_4_pairs() {
    let v = json(&[
        "parametrise",
        "--model",
        "smooth",
        "--samples",
        "0",
        "--json",
        "--measured",
        "V1=12.77",
        "--measured",
        "V2=12.62",
        "--measured",
        "V4=12.65",
    ]);
    let pair = |a: &str, b: &str| {
        v["pairs"].as_array().unwrap().iter().find(|p| p["variants"][0] == a && p["variants"][1] == b).unwrap()
            ["solutions"]
            .clone()
    };
    let v1v4 = pair("V1", "V4");
    assert_eq!(v1v4.as_array().unwrap().len(), 2);
    // Table 4 prints 0.736 and 7.570 kg m²; the two-decimal frequencies allow about ±10 %
    // and ±10 % there (see tests/parametrise.rs)
    assert!((v1v4[0]["j_drive"].as_f64().unwrap() / 0.736 - 1.0).abs() < 0.1);
    assert!((v1v4[1]["j_drive"].as_f64().unwrap() / 7.570 - 1.0).abs() < 0.1);
    assert_eq!(v1v4[1]["shuffle"], false);
}

#[test]
fn design_spring_reports_the_paper_spring_as_too_stiff() {
    let v = json(&["design-spring", "--json", "--sigma-hz", "0.05", "--target", "0.05"]);
    let current = &v["design"]["current"][0];
    assert!(current["c_short_rel_ci95"].as_f64().unwrap() > 0.5, "{current}");
    let rec = &v["design"]["recommended"];
    assert!(rec["c_delta"].as_f64().unwrap() < 64_330.0 / 10.0, "{rec}");
    assert_eq!(rec["meets_target"], true);
}

fn tempdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rigtwin-bundles-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const TOML: &str = "kind = \"torsional_sweep\"\ndata = \"s.csv\"\nvariant = \"V1\"\n[model]\nj_m2 = 0.9\nj_drive = 0.5\nj_m3 = 0.9\nc_short = 1500.0\nc_delta = 6e4\n";

fn bad(tag: &str, toml: &str, csv: &str) -> String {
    let d = tempdir(tag);
    std::fs::write(d.join("b.toml"), toml).unwrap();
    std::fs::write(d.join("s.csv"), csv).unwrap();
    let b = d.join("b.toml");
    let c = d.join("b2.toml");
    std::fs::write(&c, toml.replace("V1", "V2")).unwrap();
    let out = rigtwin(&["parametrise", b.to_str().unwrap(), c.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    String::from_utf8_lossy(&out.stderr).to_string()
}

#[test]
fn bad_bundles_name_file_line_and_expectation() {
    let good_rows: String = (0..10).map(|i| format!("{:.3},1.0,2.0,3.0\n", i as f64 * 0.001)).collect();
    let header = "time_s,torque_drive_Nm,speed_m2_radps,speed_m3_radps\n";
    let e = bad("nan", TOML, &format!("{header}{good_rows}0.010,abc,2.0,3.0\n"));
    assert!(e.contains("s.csv:12") && e.contains("torque_drive_Nm") && e.contains("expected a number"), "{e}");
    let e = bad("col", TOML, "time_s,torque_drive_Nm,speed_m2_radps\n0.0,1.0,2.0\n0.001,1.0,2.0\n");
    assert!(e.contains("s.csv:1") && e.contains("missing column `speed_m3_radps`"), "{e}");
    let e = bad("time", TOML, &format!("{header}{good_rows}0.0085,1.0,2.0,3.0\n"));
    assert!(e.contains("s.csv:12") && e.contains("time"), "{e}");
    let e = bad("kind", &TOML.replace("torsional_sweep", "bearing_shake"), &format!("{header}{good_rows}"));
    assert!(e.contains("b.toml") && e.contains("torsional_sweep"), "{e}");
    let e = bad("model", &TOML.replace("j_drive = 0.5", "j_drive = -0.5"), &format!("{header}{good_rows}"));
    assert!(e.contains("b.toml") && e.contains("model.j_drive"), "{e}");
    let e = bad("short", TOML, &format!("{header}{good_rows}"));
    assert!(e.contains("lasts 0.009"), "{e}");
    let e = bad(
        "nodata",
        "kind = \"torsional_sweep\"\nvariant = \"V1\"\n[model]\nj_m2 = 1.0\nj_drive = 1.0\nj_m3 = 1.0\nc_short = 1.0\n",
        "",
    );
    assert!(e.contains("`data`"), "{e}");
}
