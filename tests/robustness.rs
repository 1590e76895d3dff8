//! Bad input as a careless or hostile user gives it: each case runs the binary with a time
//! limit and checks the exit code, the message (file, line or key, and what was expected) and
//! what is left on disk. Nothing may hang, panic, clobber a file or pass as a result.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs rigtwin in `dir` with `args`, at most `limit_s` seconds (then kills it and fails).
fn run_in(dir: &Path, args: &[&str], limit_s: u64) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(limit_s) {
            let _ = child.kill();
            panic!("rigtwin {args:?} did not finish within {limit_s} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let run = Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    };
    assert!(!run.stderr.contains("panicked"), "rigtwin {args:?} panicked:\n{}", run.stderr);
    run
}

/// A refusal: exit code 1, nothing on stdout, and stderr containing each of `words`.
fn refused(dir: &Path, args: &[&str], words: &[&str]) -> String {
    let r = run_in(dir, args, 60);
    assert_eq!(r.code, Some(1), "rigtwin {args:?} should fail:\nstdout {}\nstderr {}", r.stdout, r.stderr);
    assert!(r.stdout.is_empty(), "rigtwin {args:?} printed a result:\n{}", r.stdout);
    for w in words {
        assert!(r.stderr.contains(w), "rigtwin {args:?}: `{w}` missing in:\n{}", r.stderr);
    }
    r.stderr
}

fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(name)
}

/// A scratch folder with copies of the example bundle `name` (TOML and data files).
fn scratch(case: &str, names: &[&str]) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rigtwin-robust-{}-{case}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    for n in names {
        std::fs::copy(shared(n), d.join(n)).unwrap();
    }
    d
}

/// Rewrites line `line` (1-based) of a CSV, column `col`, with `value`.
fn set_cell(file: &Path, line: usize, col: usize, value: &str) {
    let text = std::fs::read_to_string(file).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[line - 1].split(',').map(String::from).collect();
    cells[col] = value.into();
    lines[line - 1] = cells.join(",");
    std::fs::write(file, lines.join("\n") + "\n").unwrap();
}

/// Applies `f` to every data row's cells of a CSV.
fn map_rows(file: &Path, f: impl Fn(usize, &mut Vec<String>)) {
    let text = std::fs::read_to_string(file).unwrap();
    let mut out: Vec<String> = Vec::new();
    for (i, l) in text.lines().enumerate() {
        if i == 0 {
            out.push(l.into());
            continue;
        }
        let mut cells: Vec<String> = l.split(',').map(String::from).collect();
        f(i - 1, &mut cells);
        out.push(cells.join(","));
    }
    std::fs::write(file, out.join("\n") + "\n").unwrap();
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

const SWEEP: [&str; 2] = ["v1_sweep_b.toml", "v1_sweep_b.csv"];
const SHAKE: [&str; 3] = ["sfd_shake.toml", "sfd_shake_x.csv", "sfd_shake_y.csv"];

#[test]
fn a_single_huge_sample_is_named_not_fitted() {
    for value in ["1e200", "1.7e308"] {
        let d = scratch(&format!("huge-{value}"), &SWEEP);
        set_cell(&d.join("v1_sweep_b.csv"), 5001, 2, value);
        for cmd in ["parametrise", "diagnose"] {
            refused(&d, &[cmd, "v1_sweep_b.toml"], &["v1_sweep_b.csv:5001", "speed_m2_radps"]);
        }
        let _ = files_in(&d);
    }
    // a glitch of a normal size is a glitch too
    let d = scratch("glitch", &SWEEP);
    set_cell(&d.join("v1_sweep_b.csv"), 7000, 1, "4e8");
    refused(&d, &["diagnose", "v1_sweep_b.toml"], &["v1_sweep_b.csv:7000", "torque_drive_Nm", "glitch"]);
}

#[test]
fn huge_forces_in_a_shake_test_are_refused() {
    let d = scratch("forces", &SHAKE);
    map_rows(&d.join("sfd_shake_x.csv"), |_, c| {
        for k in [1, 2] {
            c[k] = format!("{:e}", c[k].parse::<f64>().unwrap() * 1e300);
        }
    });
    refused(&d, &["bearing", "sfd_shake.toml"], &["sfd_shake_x.csv:", "force_x_N"]);
    refused(&d, &["diagnose", "sfd_shake.toml"], &["sfd_shake_x.csv:", "force_x_N"]);
}

#[test]
fn time_steps_the_analysis_cannot_use_are_named() {
    // milliseconds written as seconds
    let d = scratch("ms", &SWEEP);
    map_rows(&d.join("v1_sweep_b.csv"), |i, c| c[0] = format!("{i}"));
    for cmd in ["diagnose", "parametrise"] {
        refused(&d, &[cmd, "v1_sweep_b.toml"], &["v1_sweep_b.csv", "looks like milliseconds", "step 1 s"]);
    }
    // 1e-5 s and 1e-9 s steps: the record is then far too short for the model's modes
    for dt in [1e-5, 1e-9] {
        let d = scratch(&format!("dt{dt}"), &SWEEP);
        map_rows(&d.join("v1_sweep_b.csv"), |i, c| c[0] = format!("{:e}", i as f64 * dt));
        refused(&d, &["diagnose", "v1_sweep_b.toml"], &["v1_sweep_b.csv", "lasts"]);
    }
    // a band above the shake test's Nyquist frequency (512 Hz)
    let d = scratch("nyquist", &SHAKE);
    let t = std::fs::read_to_string(d.join("sfd_shake.toml")).unwrap();
    std::fs::write(d.join("sfd_shake.toml"), t.replace("f_max_hz = 85.0", "f_max_hz = 600.0")).unwrap();
    refused(&d, &["bearing", "sfd_shake.toml"], &["sfd_shake_x.csv", "samples per period", "f_max_hz = 600"]);
}

#[test]
fn data_that_cannot_support_an_answer_is_refused() {
    // no excitation
    let d = scratch("zero-torque", &SWEEP);
    map_rows(&d.join("v1_sweep_b.csv"), |_, c| c[1] = "0.0".into());
    refused(&d, &["diagnose", "v1_sweep_b.toml"], &["torque_drive_Nm", "does not vary"]);
    // both shake tests one file
    let d = scratch("same-test", &SHAKE);
    let t = std::fs::read_to_string(d.join("sfd_shake.toml")).unwrap();
    std::fs::write(d.join("sfd_shake.toml"), t.replace("sfd_shake_y.csv", "sfd_shake_x.csv")).unwrap();
    refused(&d, &["bearing", "sfd_shake.toml"], &["tests", "twice"]);
    // one test that does not move
    let d = scratch("still", &SHAKE);
    map_rows(&d.join("sfd_shake_y.csv"), |_, c| {
        c[3] = "0.0".into();
        c[4] = "0.0".into();
    });
    refused(&d, &["bearing", "sfd_shake.toml"], &["sfd_shake_y.csv", "disp_x_m", "does not vary"]);
    // a test that repeats the other's motion (same direction): no line separates them
    let d = scratch("alike", &SHAKE);
    std::fs::copy(d.join("sfd_shake_x.csv"), d.join("sfd_shake_y.csv")).unwrap();
    map_rows(&d.join("sfd_shake_y.csv"), |_, c| {
        for cell in &mut c[1..5] {
            *cell = format!("{:e}", 2.0 * cell.parse::<f64>().unwrap());
        }
    });
    refused(&d, &["bearing", "sfd_shake.toml"], &["not independent"]);
    refused(&d, &["diagnose", "sfd_shake.toml"], &["not independent"]);
    // a missing variant
    let d = scratch("variant", &SWEEP);
    let t = std::fs::read_to_string(d.join("v1_sweep_b.toml")).unwrap();
    let without: String = t.lines().filter(|l| !l.starts_with("variant")).map(|l| format!("{l}\n")).collect();
    std::fs::write(d.join("v1_sweep_b.toml"), without).unwrap();
    refused(&d, &["diagnose", "v1_sweep_b.toml"], &["v1_sweep_b.toml", "variant"]);
    // frequencies no pair of variants explains, and one variant twice
    let here = std::env::temp_dir();
    refused(&here, &["parametrise", "--measured", "V1=12.77", "--measured", "V2=12.77"], &["no pair", "V1"]);
    refused(&here, &["parametrise", "--measured", "V1=12.77", "--measured", "V1=12.62"], &["V1", "twice"]);
}

#[test]
fn outputs_never_replace_devices_links_fifos_or_inputs() {
    use std::os::unix::fs::FileTypeExt;
    let d = scratch("outputs", &SWEEP);
    // a device is written through and stays a device
    let r = run_in(&d, &["diagnose", "v1_sweep_b.toml", "--json", "/dev/null"], 120);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device());
    // a symbolic link stays a link; its target gets the model
    std::fs::write(d.join("target.toml"), "old").unwrap();
    std::os::unix::fs::symlink(d.join("target.toml"), d.join("link.toml")).unwrap();
    let r = run_in(&d, &["diagnose", "v1_sweep_b.toml", "--write-model", "link.toml"], 120);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(std::fs::symlink_metadata(d.join("link.toml")).unwrap().file_type().is_symlink());
    assert!(std::fs::read_to_string(d.join("target.toml")).unwrap().contains("[effects]"));
    // a FIFO is refused at once (writing to it could wait for ever)
    assert!(Command::new("mkfifo").arg(d.join("fifo")).status().unwrap().success());
    refused(&d, &["diagnose", "v1_sweep_b.toml", "--json", "fifo"], &["fifo", "FIFO"]);
    // the bundle and its data are inputs
    let before = std::fs::read(d.join("v1_sweep_b.toml")).unwrap();
    refused(&d, &["diagnose", "v1_sweep_b.toml", "--write-model", "v1_sweep_b.toml"], &["input"]);
    refused(&d, &["diagnose", "v1_sweep_b.toml", "--json", "./v1_sweep_b.csv"], &["input"]);
    assert_eq!(std::fs::read(d.join("v1_sweep_b.toml")).unwrap(), before);
    // a bad --plot is found before anything is computed or written
    let listing = files_in(&d);
    refused(
        &d,
        &["diagnose", "v1_sweep_b.toml", "--json", "d.json", "--write-model", "m.toml", "--plot", "no/such/dir/p.svg"],
        &["--plot", "no/such/dir", "does not exist"],
    );
    assert_eq!(files_in(&d), listing, "nothing written, no .partial left");
}

#[test]
fn concurrent_fmu_exports_into_one_folder_all_succeed() {
    let d = scratch("concurrent", &[]);
    let children: Vec<_> = (0..8)
        .map(|_| {
            Command::new(env!("CARGO_BIN_EXE_rigtwin"))
                .args(["fmu", "--out", "fmus"])
                .current_dir(&d)
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let out = c.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    assert_eq!(files_in(&d.join("fmus")), ["rigtwin-fmi2.fmu", "rigtwin-fmi3.fmu"], "no temporary file left");
}

#[test]
fn special_and_huge_inputs_are_refused_before_reading() {
    let d = scratch("special", &SWEEP);
    let t = std::fs::read_to_string(d.join("v1_sweep_b.toml")).unwrap();
    std::fs::write(d.join("zero.toml"), t.replace("data = \"v1_sweep_b.csv\"", "data = \"/dev/zero\"")).unwrap();
    refused(&d, &["diagnose", "zero.toml"], &["/dev/zero", "not a regular file"]);
    std::fs::write(d.join("empty.toml"), t.replace("data = \"v1_sweep_b.csv\"", "data = \"\"")).unwrap();
    refused(&d, &["diagnose", "empty.toml"], &["empty.toml", "`data` is empty"]);
    refused(&d, &["fmu", "--params", "/dev/zero", "--out", "x"], &["/dev/zero", "not a regular file"]);
    refused(&d, &["modal", "--rig", "/dev/zero"], &["/dev/zero", "not a regular file"]);
    refused(&d, &["parametrise", "v1_sweep_b.toml", "--samples", "1000000000"], &["--samples", "100000"]);
    // a semicolon-separated CSV is named as such
    let csv = std::fs::read_to_string(d.join("v1_sweep_b.csv")).unwrap();
    std::fs::write(d.join("v1_sweep_b.csv"), csv.replace(',', ";")).unwrap();
    refused(&d, &["diagnose", "v1_sweep_b.toml"], &["v1_sweep_b.csv:1", "semicolons"]);
}

#[test]
fn messages_name_the_path_or_the_parameter() {
    let d = scratch("messages", &[]);
    // a folder that cannot be made (even as root: /proc takes no new folders)
    refused(
        &d,
        &["fmu", "--descriptions", "/proc/rigtwin-descriptions", "--out", "x"],
        &["/proc/rigtwin-descriptions"],
    );
    refused(&d, &["fmu", "--out", "/proc/rigtwin-out"], &["--out", "/proc/rigtwin-out"]);
    // the MPC on an absurd inertia names the rig's parameters, not a Riccati residual
    let paper = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs/paper.toml")).unwrap();
    std::fs::write(d.join("absurd.toml"), paper.replace("j_drive = 0.529", "j_drive = 1e-9")).unwrap();
    refused(&d, &["mpc", "--params", "absurd.toml"], &["[model]", "j_drive = 0.000000001"]);
}
