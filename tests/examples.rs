//! The example bundles shipped in `examples/`: they are what `examples/make_examples.rs` writes
//! (byte for byte), and the README's journeys on them give the truth the generator put in —
//! numbers from the generator's source, not from the code under test. These records come from
//! rigtwin's own simulator, so these are checks of the journeys, not a validation of the
//! diagnosis: that is `tests/diagnose*.rs`, on records of integrators that share no code with it.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

/// Runs rigtwin with `args` (paths relative to the repository) and parses its JSON (`--json`).
fn json(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(args)
        .arg("--json")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "rigtwin {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The generator as this checkout builds it: `cargo test` has built it beside this test
/// (target/<profile>/examples); a run filtered to this file builds it with `cargo run`. Running
/// it through cargo after `cargo test --workspace` would build the whole tree again, because a
/// build of the root package alone unifies its dependencies' features differently.
fn generator() -> Command {
    let exe = std::env::current_exe().unwrap();
    let built = exe.parent().and_then(Path::parent).map(|profile| profile.join("examples").join("make_examples"));
    match built.filter(|b| b.is_file()) {
        Some(b) => Command::new(b),
        None => {
            let mut cmd = Command::new(env!("CARGO"));
            cmd.args(["run", "--quiet", "--example", "make_examples", "--"]).current_dir(env!("CARGO_MANIFEST_DIR"));
            cmd
        }
    }
}

fn close(found: f64, truth: f64, rel: f64, what: &str) {
    assert!((found / truth - 1.0).abs() < rel, "{what}: {found} for {truth} (±{} %)", rel * 100.0);
}

#[test]
fn the_shipped_examples_are_what_the_generator_writes() {
    let dir = std::env::temp_dir().join(format!("rigtwin-examples-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = generator().arg(&dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut n = 0;
    for kind in ["sweep", "variants", "bearing", "gear_bench", "linear_axis"] {
        for e in std::fs::read_dir(examples().join(kind)).unwrap() {
            let shipped = e.unwrap().path();
            let written = dir.join(kind).join(shipped.file_name().unwrap());
            assert!(
                std::fs::read(&shipped).unwrap() == std::fs::read(&written).unwrap(),
                "{} differs from what make_examples writes: run `cargo run --release --example make_examples`",
                shipped.display()
            );
            n += 1;
        }
    }
    assert_eq!(n, 2 + 8 + 3 + 2 + 2, "every shipped file was compared");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_sweep_shows_its_dead_time() {
    // make_examples: a 4.0 ms dead time of the drive torque
    let v = json(&["diagnose", "examples/sweep/v1_sweep.toml"]);
    assert_eq!(v["effect"], "time_delay", "{v}");
    // 2 %: the delay is 4 samples of 1 ms, fitted continuously; noise moves it by far less
    close(v["parameters"]["delay_s"].as_f64().unwrap(), 4.0e-3, 0.02, "dead time");
}

#[test]
fn the_variants_give_the_rig_they_were_made_with() {
    // make_examples: j_drive 0.550 kg m², c_short 1400 N m/rad, the declared rig otherwise
    let files: Vec<String> = ["V1", "V2", "V3", "V4"].map(|v| format!("examples/variants/variant_{v}.toml")).to_vec();
    let mut args = vec!["parametrise", "--samples", "0"];
    args.extend(files.iter().map(String::as_str));
    let v = json(&args);
    let a = &v["answer"];
    assert_eq!(a["model"], "differential", "{a}");
    assert_eq!(a["explains_the_variants"], true, "{a}");
    // 1 %: the modal fit of a 30 s sweep places the shuffle within 0.1 % (measured), and the
    // two unknowns follow from four frequencies
    close(a["j_drive_kgm2"].as_f64().unwrap(), 0.550, 0.01, "j_drive");
    close(a["c_short_Nm_per_rad"].as_f64().unwrap(), 1400.0, 0.01, "c_short");
}

#[test]
fn the_shake_tests_show_the_added_mass() {
    // make_examples: K 1.2e6 / 1.5e6 N/m, C 2600 / 2800 N s/m, M 6 kg; declared K-C
    let v = json(&["bearing", "examples/bearing/shake.toml", "--structure", "KCM"]);
    let m = &v["M_kg"];
    let c = &v["C_Ns_per_m"];
    // 1 %: the records carry 0.25 % force and ~0.1 % displacement noise over 4 periods
    close(m[0][0].as_f64().unwrap(), 6.0, 0.01, "Mxx");
    close(m[1][1].as_f64().unwrap(), 6.0, 0.01, "Myy");
    close(c[0][0].as_f64().unwrap(), 2600.0, 0.01, "Cxx");
    close(c[1][1].as_f64().unwrap(), 2800.0, 0.01, "Cyy");
    let d = json(&["diagnose", "examples/bearing/shake.toml"]);
    assert_eq!(d["effect"], "added_mass", "{d}");
}

#[test]
fn the_drive_records_show_their_friction() {
    // make_examples: 0.30 N m at the gear bench's load (MDF 4, rpm), 20 N at the axis (CSV)
    for (bundle, at, truth) in [
        ("examples/gear_bench/bench.toml", "body load", 0.30),
        ("examples/linear_axis/axis.toml", "body carriage", 20.0),
    ] {
        let v = json(&["diagnose", bundle]);
        assert_eq!(v["effect"], "coulomb_friction", "{bundle}: {v}");
        assert_eq!(v["at"], at, "{bundle}");
        let f = v["parameters"].as_object().unwrap().iter().find(|(k, _)| k.starts_with("friction")).unwrap().1;
        // 3 %: friction is fitted beside re-fitted inertias and stiffnesses on a noisy record
        close(f.as_f64().unwrap(), truth, 0.03, bundle);
    }
}
