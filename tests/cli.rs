//! The command line: JSON contracts, the shipped rig file, and errors for bad rig files.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use approx::assert_abs_diff_eq;
use serde_json::Value;

fn rigtwin(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).output().expect("run rigtwin")
}

fn json(args: &[&str]) -> Value {
    let out = rigtwin(args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

#[test]
fn modal_json_contract_on_the_default_rig_is_figure_14() {
    let v = json(&["modal", "--json"]);
    let f = floats(&v["frequencies_hz"]);
    assert_eq!(f[..2], [0.0, 0.0]);
    assert_abs_diff_eq!(f[2], 12.64, epsilon = 0.005); // Figure 14, two decimals
    assert_eq!(v["shuffle_mode"], 2);
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 3);
    assert_eq!(modes[2].as_array().unwrap().len(), 3);
}

#[test]
fn modal_json_of_the_reduced_model_is_table_5() {
    let v = json(&["modal", "--model", "reduced", "--variant", "V2", "--json"]);
    let f = floats(&v["frequencies_hz"]);
    assert_abs_diff_eq!(f[1], 5.89, epsilon = 0.01);
    assert_abs_diff_eq!(f[2], 12.62, epsilon = 0.01);
    assert_eq!(v["shuffle_mode"], 2);
}

#[test]
fn modal_json_of_the_chain_is_table_a1() {
    let v = json(&["modal", "--model", "chain", "--json"]);
    let f = floats(&v["frequencies_hz"]);
    assert_eq!(f.len(), 15);
    assert_abs_diff_eq!(f[1], 17.59, epsilon = 0.005);
    assert_abs_diff_eq!(f[2], 22.47, epsilon = 0.005);
    assert_eq!(v["shuffle_mode"], 2);
}

#[test]
fn reduce_json_contract_is_table_1() {
    let v = json(&["reduce", "--json"]);
    let j = floats(&v["inertias_kgm2"]);
    let c = floats(&v["stiffnesses_Nm_per_rad"]);
    let f = floats(&v["frequencies_hz"]);
    assert_abs_diff_eq!(j[1], 3.5003, epsilon = 1e-4);
    assert_abs_diff_eq!(c[0], 13_093.0, epsilon = 1.4);
    assert_abs_diff_eq!(f[2], 22.46, epsilon = 0.005);
    let v5 = json(&["reduce", "--masses", "5", "--json"]);
    assert_eq!(floats(&v5["inertias_kgm2"]).len(), 5);
    assert_eq!(floats(&v5["stiffnesses_Nm_per_rad"]).len(), 4);
}

#[test]
fn shipped_rig_file_is_the_embedded_default() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs/paper.toml");
    let rig = modelfile::rig::load_rig(&path).unwrap();
    let default = plant::paper::rig();
    assert_eq!(rig.name, default.name);
    assert_eq!(rig.variant, default.variant);
    // same bodies; the file writes 1.69e6 where the code multiplies 0.0169 × 1e8 (1 ulp apart)
    let (a, b) = (rig.chain.unwrap(), default.chain.unwrap());
    let (sa, sb) = (a.additional_spring.clone().unwrap(), b.additional_spring.clone().unwrap());
    assert_eq!((a.drive, a.short_shaft, a.long_shaft), (b.drive, b.short_shaft, b.long_shaft));
    assert_eq!((sa.left_after, sa.right_after), (sb.left_after, sb.right_after));
    for (x, y) in a.bodies.iter().chain(&sa.bodies).zip(b.bodies.iter().chain(&sb.bodies)) {
        assert_eq!(x.name, y.name);
        approx::assert_relative_eq!(x.inertia_kgm2, y.inertia_kgm2, max_relative = 1e-12);
        approx::assert_relative_eq!(x.stiffness_nm_per_rad, y.stiffness_nm_per_rad, max_relative = 1e-12);
    }
    assert_eq!(a.bodies.len() + sa.bodies.len(), b.bodies.len() + sb.bodies.len());
    // c_long_ratio is written with 16 digits in the file
    assert_abs_diff_eq!(rig.model.c_long(), default.model.c_long(), epsilon = 1e-9);
    assert_eq!(
        (rig.model.d_short, rig.model.d_long, rig.model.load_drag),
        (default.model.d_short, default.model.d_long, default.model.load_drag)
    );
    // `run` also writes the FMUs: the library must be built, and they go to a scratch folder
    let out = common::fmu_dir().join("run");
    let out = out.to_str().unwrap();
    let a = json(&["run", "--json", "--out", out, "--rig", path.to_str().unwrap()]);
    let b = json(&["run", "--json", "--out", out]);
    assert!(std::path::Path::new(out).join("rigtwin-fmi3.fmu").exists());
    assert_abs_diff_eq!(
        a["differential"]["frequencies_hz"][2].as_f64().unwrap(),
        b["differential"]["frequencies_hz"][2].as_f64().unwrap(),
        epsilon = 1e-9
    );
}

#[test]
fn damped_rig_reports_poles() {
    let dir = tempdir();
    let f = dir.join("damped.toml");
    std::fs::write(&f, "[model]\nj_m2 = 0.9148\nj_drive = 0.529\nj_m3 = 0.9148\nc_short = 1479.0\nc_long = 1150.33\nd_short = 1.12\nd_long = 0.87\nload_drag = 0.5\n").unwrap();
    let v = json(&["modal", "--rig", f.to_str().unwrap(), "--json"]);
    let poles = v["poles"].as_array().unwrap();
    let shuffle = poles
        .iter()
        .max_by(|a, b| a["natural_hz"].as_f64().unwrap().total_cmp(&b["natural_hz"].as_f64().unwrap()))
        .unwrap();
    // Independent: the shuffle of the rank-one differential with D ∝ a aᵀ plus load drag is
    // close to the undamped 12.64 Hz; its damping ratio is of the order d ω / (2 c).
    assert_abs_diff_eq!(shuffle["natural_hz"].as_f64().unwrap(), 12.64, epsilon = 0.05);
    let z = shuffle["damping_ratio"].as_f64().unwrap();
    assert!(z > 0.001 && z < 0.05, "{z}");
}

fn tempdir() -> common::Scratch {
    common::scratch("cli", &format!("{:?}", std::thread::current().id()))
}

/// Writes `text` as a rig file, runs `modal` (or `reduce`) on it and returns stderr; asserts failure and no stdout.
fn rejected(text: &str, command: &str) -> String {
    let dir = tempdir();
    let f = dir.join(format!("{command}-{}.toml", text.len()));
    std::fs::write(&f, text).unwrap();
    let out = rigtwin(&[command, "--rig", f.to_str().unwrap(), "--json"]);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty(), "nothing half-written on stdout");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(err.contains(f.to_str().unwrap()), "error names the file: {err}");
    err
}

const MODEL: &str = "[model]\nj_m2 = 0.9\nj_drive = 0.5\nj_m3 = 0.9\nc_short = 1500.0\nc_delta = 6e4\n";

#[test]
fn bad_rig_files_get_errors_that_name_the_key() {
    let e = rejected(&MODEL.replace("j_m2 = 0.9", "j_m2 = 0.0"), "modal");
    assert!(e.contains("model.j_m2") && e.contains("positive"), "{e}");
    let e = rejected(&MODEL.replace("j_drive = 0.5", "j_drive = -0.5"), "modal");
    assert!(e.contains("model.j_drive"), "{e}");
    let e = rejected(&format!("{MODEL}c_shrot = 3.0\n"), "modal");
    assert!(e.contains("unknown field `c_shrot`") && e.contains("line 7"), "{e}");
    let e = rejected(&MODEL.replace("j_drive = 0.5\n", ""), "modal");
    assert!(e.contains("missing field `j_drive`"), "{e}");
    let e = rejected(&MODEL.replace("c_short = 1500.0", "c_short = \"stiff\""), "modal");
    assert!(e.contains("line 5") && e.contains("c_short"), "{e}");
    let e = rejected("[model\nj_m2 = 1\n", "modal");
    assert!(e.contains("line 1"), "{e}");
}

#[test]
fn bad_chains_get_errors_that_name_the_key() {
    let paper = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs/paper.toml")).unwrap();
    let e = rejected(&paper.replace("right_after = 10 ", "right_after = 15 "), "reduce");
    assert!(e.contains("chain.additional_spring.right_after") && e.contains("15"), "{e}");
    let e = rejected(&paper.replace("drive = 8 ", "drive = 40 "), "reduce");
    assert!(e.contains("chain.drive"), "{e}");
    let e = rejected(&paper.replace("j_kgm2 = 0.0003,", "j_kgm2 = 0.0,"), "reduce");
    assert!(e.contains("chain.bodies[7].j_kgm2"), "{e}");
    let e = rejected(
        &paper.replace(
            "{ name = \"J4 adapter segment 2\", j_kgm2 = 0.0007, c_Nm_per_rad = 1.69e6 }",
            "{ name = \"J4\", j_kgm2 = 0.0007 }",
        ),
        "reduce",
    );
    assert!(e.contains("chain.bodies[4].c_Nm_per_rad") && e.contains("missing"), "{e}");
    let e = rejected(
        &paper.replace(
            "{ name = \"J4 adapter segment 2\", j_kgm2 = 0.0007, c_Nm_per_rad = 1.69e6 }",
            "{ name = \"J4\", outer_diameter_m = 0.02, inner_diameter_m = 0.03, length_m = 0.1 }",
        ),
        "reduce",
    );
    assert!(e.contains("chain.bodies[4].inner_diameter_m"), "{e}");
    // a model-only rig cannot be reduced, and says why
    let e = rejected(MODEL, "reduce");
    assert!(e.contains("[chain]"), "{e}");
}

#[test]
fn chain_variant_without_spring_description_is_an_error() {
    let paper = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs/paper.toml")).unwrap();
    let cut = &paper[..paper.find("[chain.additional_spring]").unwrap()];
    let dir = tempdir();
    let f = dir.join("nospring.toml");
    std::fs::write(&f, cut).unwrap();
    let ok = rigtwin(&["reduce", "--rig", f.to_str().unwrap()]);
    assert!(ok.status.success());
    let out = rigtwin(&["reduce", "--rig", f.to_str().unwrap(), "--variant", "V2"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("chain.additional_spring"));
}

#[test]
fn a_torsional_bundle_is_a_rig_file() {
    // The example bundles sit in ../shared/data beside the repository (DATA.md).
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    let v2 = data.join("variant_V2.toml");
    assert!(v2.exists(), "{} is missing: the example bundles belong beside the repository", v2.display());
    let v = json(&["modal", "--model", "reduced", "--rig", v2.to_str().unwrap(), "--json"]);
    assert_eq!(v["variant"], "V2");
    // Independent: the declared V2 model (j 0.9148/3.5003/0.9148, c 13,093 and 10,183 in series
    // with 64,330 Nm/rad) is a three-mass chain whose frequencies follow from the cubic
    // det(C − ω² J) = 0 — here solved in closed form for the two non-zero roots.
    let (j1, j2, j3) = (0.9148_f64, 3.5003_f64, 0.9148_f64);
    let s = |a: f64, b: f64| a * b / (a + b);
    let (k1, k2) = (s(13_093.0, 64_330.0), s(10_183.444444444445, 64_330.0));
    // ω⁴ − ω² (k1/j1 + k1/j2 + k2/j2 + k2/j3) + k1 k2 (j1 + j2 + j3)/(j1 j2 j3) = 0
    let b = k1 / j1 + k1 / j2 + k2 / j2 + k2 / j3;
    let c = k1 * k2 * (j1 + j2 + j3) / (j1 * j2 * j3);
    let disc = (b * b - 4.0 * c).sqrt();
    let f = floats(&v["frequencies_hz"]);
    let tau = 2.0 * std::f64::consts::PI;
    assert_abs_diff_eq!(f[1], ((b - disc) / 2.0).sqrt() / tau, epsilon = 1e-9);
    assert_abs_diff_eq!(f[2], ((b + disc) / 2.0).sqrt() / tau, epsilon = 1e-9);
    // a bearing bundle is not a rig
    let out = rigtwin(&["modal", "--rig", data.join("sfd_shake.toml").to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("torsional_sweep"));
}

#[test]
fn damping_ratio_option_damps_the_shuffle_mode() {
    // the paper's rig without the load machines' drag, so that the shaft damping alone sets
    // the shuffle mode's damping ratio
    let paper = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs/paper.toml")).unwrap();
    assert!(paper.contains("load_drag = 0.5 "));
    let dir = tempdir();
    let rig = dir.join("no_drag.toml");
    std::fs::write(&rig, paper.replace("load_drag = 0.5 ", "load_drag = 0.0 ")).unwrap();
    let v = json(&["modal", "--rig", rig.to_str().unwrap(), "--damping-ratio", "0.04", "--json"]);
    let poles = v["poles"].as_array().unwrap();
    let top = poles.last().unwrap();
    assert_abs_diff_eq!(top["damping_ratio"].as_f64().unwrap(), 0.04, epsilon = 1e-9);
    // natural frequency unchanged by damping: 12.64 Hz (Figure 14)
    assert_abs_diff_eq!(top["natural_hz"].as_f64().unwrap(), 12.64, epsilon = 0.005);
    let out = rigtwin(&["modal", "--damping-ratio", "-1"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("damping"));
}

#[test]
fn design_spring_checks_the_bending_of_a_described_shaft_line() {
    // A steel shaft, 40 mm solid, on bearings at 0 and 0.6 m, overhanging 0.4 m to a joint
    // that carries no moment: Roark's tip deflection of a beam with one overhang under its own
    // weight w, w a (4a²L − L³ + 3a³)/(24 E I), is the largest deflection here.
    let dir = tempdir();
    let f = dir.join("bending.toml");
    let text = format!(
        "{MODEL}[bending]\nbearing_a_m = 0.0\nbearing_b_m = 0.6\nsegments = [\n  {{ length_m = 0.6, outer_diameter_m = 0.04 }},\n  {{ length_m = 0.4, outer_diameter_m = 0.04 }},\n]\n"
    );
    std::fs::write(&f, text).unwrap();
    let v = json(&["design-spring", "--rig", f.to_str().unwrap(), "--json"]);
    let (span, a, d) = (0.6_f64, 0.4_f64, 0.04_f64);
    let area = std::f64::consts::PI * d * d / 4.0;
    let i = std::f64::consts::PI * d.powi(4) / 64.0;
    let w = 7850.0 * area * 9.80665;
    let tip = w * a * (4.0 * a * a * span - span.powi(3) + 3.0 * a.powi(3)) / (24.0 * 210e9 * i);
    let got = v["bending"]["max_m"].as_f64().unwrap();
    approx::assert_relative_eq!(got, tip, max_relative = 1e-3);
    assert_abs_diff_eq!(v["bending"]["at_m"].as_f64().unwrap(), 1.0, epsilon = 1e-3);
    // a bearing beyond the shaft is refused with the key
    std::fs::write(&f, format!("{MODEL}[bending]\nbearing_a_m = 0.0\nbearing_b_m = 2.0\nsegments = [ {{ length_m = 0.6, outer_diameter_m = 0.04 }} ]\n")).unwrap();
    let out = rigtwin(&["design-spring", "--rig", f.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("bending.bearing_b_m"));
}

/// The README's command table lists every flag each command has (`--help` is clap's own list).
#[test]
fn readme_lists_every_flag() {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let help = String::from_utf8(rigtwin(&["--help"]).stdout).unwrap();
    // the subcommands: the indented names under "Commands:" (help excluded)
    let commands: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(commands.len() >= 9, "{help}");
    for c in commands {
        let rows: String = readme
            .lines()
            .filter(|l| l.starts_with(&format!("| `rigtwin {c} ")) || l.starts_with(&format!("| `rigtwin {c}`")))
            .collect();
        assert!(!rows.is_empty(), "README has no row for `rigtwin {c}`");
        let sub = String::from_utf8(rigtwin(&[c, "--help"]).stdout).unwrap();
        // the options: lines of the help that begin with `--name` or `-x, --name`
        let flags = sub.lines().filter_map(|l| {
            let l = l.trim_start();
            let l = if l.starts_with('-') && l.get(2..4) == Some(", ") { &l[4..] } else { l };
            l.starts_with("--").then(|| l.split(|ch: char| ch.is_whitespace() || ch == '=').next().unwrap())
        });
        for flag in flags.filter(|f| *f != "--help") {
            assert!(
                rows.contains(&format!("{flag} "))
                    || rows.contains(&format!("{flag}]"))
                    || rows.contains(&format!("{flag}=")),
                "README's row of `rigtwin {c}` lacks {flag}"
            );
        }
    }
}

/// One JSON convention: `--json` and `--json -` print the JSON (only) to standard output,
/// `/dev/stdout` too when it is a pipe, `--json FILE` writes the file and prints the text; every
/// document carries `schema_version`.
#[test]
fn every_command_writes_json_one_way() {
    let d = common::scratch("cli", "json-convention");
    let sweep = common::shared("v1_sweep_b.toml");
    let sweep = sweep.to_str().unwrap();
    let commands: Vec<Vec<&str>> = vec![
        vec!["modal"],
        vec!["reduce"],
        vec!["design-spring"],
        vec!["parametrise", "--measured", "V1=12.77", "--measured", "V2=12.62", "--samples", "0"],
        vec!["mpc", "--duration", "0.2"],
        vec!["diagnose", sweep],
    ];
    for args in &commands {
        for flag in [&["--json"][..], &["--json", "-"], &["--json", "/dev/stdout"]] {
            let all: Vec<&str> = args.iter().copied().chain(flag.iter().copied()).collect();
            let out = Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(&all).current_dir(&d).output().unwrap();
            assert!(out.status.success(), "{all:?}: {}", String::from_utf8_lossy(&out.stderr));
            let v: Value = serde_json::from_slice(&out.stdout)
                .unwrap_or_else(|e| panic!("{all:?}: stdout is not one JSON document ({e})"));
            assert_eq!(v["schema_version"], 1, "{all:?}");
        }
        assert!(!d.join("-").exists(), "{args:?}: no file named `-`");
        // a file: the JSON there, the text on stdout
        let file = d.join("report.json");
        let all: Vec<&str> = args.iter().copied().chain(["--json", file.to_str().unwrap()]).collect();
        let out = Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(&all).current_dir(&d).output().unwrap();
        assert!(out.status.success(), "{all:?}: {}", String::from_utf8_lossy(&out.stderr));
        let v: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        assert_eq!(v["schema_version"], 1);
        assert!(serde_json::from_slice::<Value>(&out.stdout).is_err(), "{all:?}: the text, not JSON, on stdout");
        std::fs::remove_file(&file).unwrap();
    }
}

/// A drive bundle without `[mpc]` runs in the controller with the record's peaks as the bounds
/// and a note, and the paper rig's controller runs on the embedded default; a diagnosed model
/// as written is run by `tests/diagnose_drive.rs` (`the_example_drive_bundles`, on the model its
/// diagnosis of the example writes).
#[test]
fn a_drive_bundle_and_the_rig_run_in_the_controller() {
    let d = common::scratch("cli", "bundle-mpc");
    for f in ["bench_gear.toml", "bench_gear.csv"] {
        std::fs::copy(common::shared(f), d.join(f)).unwrap();
    }
    let run = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).current_dir(&d).output().unwrap();
    let out = run(&["mpc", "--params", "bench_gear.toml"]);
    assert_eq!(out.status.code(), Some(0));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("no [mpc] input_max") && e.contains("record's peaks"), "{e}");
    let rig = run(&["mpc", "--duration", "0.2", "--json"]);
    let r: Value = serde_json::from_slice(&rig.stdout).unwrap();
    assert_eq!((r["verdict"].as_str(), r["model_kind"].as_str()), (Some("valid"), Some("paper_rig")), "{r}");
}

/// The README is a guide a user follows from a clone: short, its journeys on files in the
/// repository (not `../shared`), every document it links present.
#[test]
fn the_readme_is_a_guide_on_files_in_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(lines <= 200, "README.md has {lines} lines: the details belong in docs/");
    assert!(!readme.contains("../shared"), "the README's journeys use the repository's examples");
    for link in readme.split("](").skip(1).filter_map(|s| s.split(')').next()) {
        assert!(root.join(link).exists(), "README links {link}, which is missing");
    }
    for path in readme.split_whitespace().filter(|w| w.starts_with("examples/") && w.ends_with(".toml")) {
        // a glob (variant_V*.toml) names the files it matches
        let found = match path.split_once('*') {
            Some((head, tail)) => {
                let dir = root.join(Path::new(head).parent().unwrap());
                let stem = Path::new(head).file_name().unwrap().to_str().unwrap().to_string();
                std::fs::read_dir(dir).unwrap().filter_map(|e| e.ok()).any(|e| {
                    let n = e.file_name().to_string_lossy().into_owned();
                    n.starts_with(&stem) && n.ends_with(tail)
                })
            }
            None => root.join(path).exists(),
        };
        assert!(found, "README uses {path}, which is missing");
    }
}

/// The diagnosis plot a person reads: the zoom where the declared model misses most and the
/// frequency responses beside the whole record, one colour per role in every panel (the
/// measurement black), tick labels without floating-point noise, a unit on every axis.
#[test]
fn the_diagnosis_plot_reads_as_a_plot() {
    let d = common::scratch("cli", "plot");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (bundle, svg) in [("examples/sweep/v1_sweep.toml", "sweep.svg"), ("examples/gear_bench/bench.toml", "gear.svg")]
    {
        let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
            .args(["diagnose", root.join(bundle).to_str().unwrap(), "--plot", d.join(svg).to_str().unwrap()])
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let text = std::fs::read_to_string(d.join(svg)).unwrap();
        assert!(text.contains("zoom where the declared model misses most"), "{bundle}: no zoom panel");
        assert!(text.contains("frequency response"), "{bundle}: no frequency response panel");
        assert!(!text.contains("99999999") && !text.contains("00000001"), "{bundle}: tick labels with round-off");
        // one colour per role in every panel: each series and its legend line in its role's
        // colour (measured black, the declared model blue, the extended model red), so the
        // count of lines in a colour is twice (series and legend) the panels showing that role;
        // the measured series is drawn thin, so only its legend line is black and 2 px wide
        let lines = |colour: &str, width: u8| {
            text.matches(&format!("stroke=\"{colour}\" stroke-width=\"{width}\" points")).count()
        };
        let legends = |label: &str| text.lines().filter(|l| l.starts_with(label)).count();
        let panels = legends("measured");
        assert!(panels >= 4, "{bundle}: the measurement in every panel ({panels})");
        assert_eq!(lines("#000000", 2), panels, "{bundle}: the measurement is black everywhere");
        assert_eq!(
            lines("#1F77B4", 2),
            2 * legends("declared model"),
            "{bundle}: the declared model is blue everywhere"
        );
        assert_eq!(lines("#D62728", 2), 2 * legends("with "), "{bundle}: the extended model is red everywhere");
        // axis titles carry their units (plotters rotates the y title: it is its own <text>)
        for axis in ["time [s]", "frequency [Hz]"] {
            assert!(text.contains(axis), "{bundle}: no `{axis}` axis");
        }
    }
}

/// A record the declared model and no candidate can explain (the example V1 sweep with two
/// sines of 7.3 and 3.1 Hz added to M2's speed, which no effect of the input makes): the verdict
/// is `not_explained` in text and JSON, the exit code 3, and no extended model is written.
#[test]
fn a_record_nothing_explains_is_said_to_be_not_explained() {
    let d = common::scratch("cli", "not-explained");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/variants");
    let csv = std::fs::read_to_string(root.join("variant_V1.csv")).unwrap();
    let mut out: Vec<String> = Vec::new();
    for (i, line) in csv.lines().enumerate() {
        if i == 0 {
            out.push(line.into());
            continue;
        }
        let mut c: Vec<String> = line.split(',').map(String::from).collect();
        let t: f64 = c[0].parse().unwrap();
        let w: f64 = c[2].parse().unwrap();
        let tau = std::f64::consts::TAU;
        c[2] = format!("{:e}", w + 0.5 * (tau * 7.3 * t).sin() + 0.3 * (tau * 3.1 * t + 1.0).sin());
        out.push(c.join(","));
    }
    std::fs::write(d.join("disturbed.csv"), out.join("\n") + "\n").unwrap();
    let toml =
        std::fs::read_to_string(root.join("variant_V1.toml")).unwrap().replace("variant_V1.csv", "disturbed.csv");
    std::fs::write(d.join("disturbed.toml"), toml).unwrap();
    let run = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).current_dir(&d).output().unwrap();
    let r = run(&["diagnose", "disturbed.toml", "--write-model", "m.toml"]);
    assert_eq!(r.status.code(), Some(3), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(String::from_utf8_lossy(&r.stdout).contains("NOT EXPLAINED"));
    assert!(String::from_utf8_lossy(&r.stderr).contains("not explained"));
    assert!(!d.join("m.toml").exists(), "no model written for an unexplained record");
    let r = run(&["diagnose", "disturbed.toml", "--json"]);
    assert_eq!(r.status.code(), Some(3));
    let v: Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["verdict"], "not_explained", "{v}");
    assert!(!v["verdict_reasons"].as_array().unwrap().is_empty());
    // the undisturbed record is explained by the declared model re-fitted, or by an effect
    let r = run(&["diagnose", root.join("variant_V1.toml").to_str().unwrap(), "--json"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v: Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_ne!(v["verdict"], "not_explained", "{v}");
}

/// The paper rig's FMU has no bearing block (importers warned of its unconnected forces); a rig
/// file with a `[bearing]` section, as the diagnosis of a shake test writes it, brings the
/// block's variables at the value references they always had.
#[test]
fn the_bearing_block_is_in_the_fmu_only_where_the_rig_has_one() {
    let d = common::scratch("cli", "bearing_fmu");
    let model = d.join("with_bearing.toml");
    let out = rigtwin(&["diagnose", "examples/bearing/shake.toml", "--write-model", model.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let describe = |params: Option<&Path>, dir: &str| {
        let dir = d.join(dir);
        let mut args = vec!["fmu", "--descriptions", dir.to_str().unwrap(), "--out", d.to_str().unwrap()];
        if let Some(p) = params {
            args.extend(["--params", p.to_str().unwrap()]);
        }
        let out = rigtwin(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        std::fs::read_to_string(dir.join("fmi3/modelDescription.xml")).unwrap()
    };
    let plain = describe(None, "plain");
    assert!(!plain.contains("bearing"), "the paper rig has no bearing block");
    let with = describe(Some(&model), "with");
    for (name, vr) in [("bearing.K_xx", 12), ("bearing.x", 37), ("bearing.F_x", 51)] {
        assert!(with.contains(&format!("name=\"{name}\" valueReference=\"{vr}\"")), "{name} at {vr}");
    }
    // the variables both have keep their value references
    for line in plain.lines().filter(|l| l.contains(" name=\"") && l.contains("valueReference=")) {
        assert!(with.contains(line.trim()), "{line}");
    }
}

/// A controller FMU is refused before anything is written when its model or its plant cannot
/// make one: a drive model without `[mpc] input_max` (the message shows the lines to add), and a
/// plant that lacks the signals the controller measures (the gear bench's controller on the
/// paper rig).
#[test]
fn a_controller_fmu_that_cannot_be_made_is_refused_by_name() {
    let d = common::scratch("cli", "controller_refusals");
    let bare = d.join("bench_without_mpc.toml");
    let text = std::fs::read_to_string("examples/gear_bench/bench.toml").unwrap();
    // a drive_model file (a drive_test bundle would take the bounds from its record)
    let without = text[..text.find("[mpc]").unwrap()].replace("kind = \"drive_test\"", "kind = \"drive_model\"");
    std::fs::write(&bare, without).unwrap();
    let out_dir = d.join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    let out = rigtwin(&["fmu", "--controller", "--params", bare.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("[mpc]\ninput_max = [LIMIT]") && err.contains("bench_without_mpc.toml"), "{err}");
    let out = rigtwin(&[
        "fmu",
        "--controller",
        "--params",
        "examples/gear_bench/bench.toml",
        "--plant",
        "rigs/paper.toml",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("--plant") && err.contains("`w_motor`"), "{err}");
    assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 0, "nothing written");
}

/// The paper rig's sweep asked of a drive model is refused by name, not silently replaced by
/// the drive model's reference step; `--duration` sets that step's run: 2 s at the loop's 1 ms
/// are 2000 steps, and a run that ends before its step (0.05 s) or beyond the 120 s every run
/// is bounded by is refused. Nothing is written by a refused run.
#[test]
fn a_drive_models_run_takes_a_duration_and_refuses_the_rigs_sweep() {
    let d = common::scratch("cli", "drive_run");
    let json = d.join("mpc.json");
    let args = |extra: &[&'static str]| -> Vec<String> {
        let mut a: Vec<String> =
            ["mpc", "--params", "examples/gear_bench/bench.toml", "--json"].map(String::from).into();
        a.push(json.to_str().unwrap().into());
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    for (extra, says) in [
        (&["--scenario", "sweep"][..], "--scenario sweep is the paper rig's run"),
        (&["--duration", "0.01"], "--duration 0.01 s"),
        (&["--duration", "200"], "--duration 200 s"),
    ] {
        let a = args(extra);
        let out = rigtwin(&a.iter().map(String::as_str).collect::<Vec<_>>());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.contains(says), "{extra:?}: {err}");
        assert!(!json.exists(), "{extra:?}: nothing written");
    }
    let a = args(&["--duration", "2"]);
    let out = rigtwin(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["steps"], 2000, "2 s of 1 ms steps");
    assert_eq!(report["step_response"]["at_s"], 0.05);
}
