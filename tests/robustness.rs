//! Bad input as a careless or hostile user gives it: each case runs the binary with a time
//! limit and checks the exit code, the message (file, line or key, and what was expected) and
//! what is left on disk. Nothing may hang, panic, clobber a file or pass as a result.

mod common;

use common::shared;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs rigtwin in `dir` with `args`, at most `limit_s` seconds (then kills it and fails).
fn run_in(dir: &Path, args: &[&str], limit_s: u64) -> Run {
    run_limited(dir, args, limit_s, None)
}

/// [`run_in`] with the child's data segment (heap, large allocations) capped at `data_bytes`
/// (RLIMIT_DATA): a reader that holds more than that fails its allocation and aborts, which the
/// checks see as a missing message.
fn run_limited(dir: &Path, args: &[&str], limit_s: u64, data_bytes: Option<u64>) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rigtwin"));
    if let Some(limit) = data_bytes {
        common::limit_data(&mut cmd, limit);
    }
    let mut child = cmd
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
    refused_with(1, dir, args, words)
}

/// A command line clap refuses: exit code 2, nothing on stdout, stderr naming each of `words`.
fn usage_refused(dir: &Path, args: &[&str], words: &[&str]) -> String {
    refused_with(2, dir, args, words)
}

fn refused_with(code: i32, dir: &Path, args: &[&str], words: &[&str]) -> String {
    let r = run_in(dir, args, 60);
    assert_eq!(
        r.code,
        Some(code),
        "rigtwin {args:?} should fail with {code}:\nstdout {}\nstderr {}",
        r.stdout,
        r.stderr
    );
    assert!(r.stdout.is_empty(), "rigtwin {args:?} printed a result:\n{}", r.stdout);
    for w in words {
        assert!(r.stderr.contains(w), "rigtwin {args:?}: `{w}` missing in:\n{}", r.stderr);
    }
    r.stderr
}

/// A scratch folder with copies of the example bundle `name` (TOML and data files).
fn scratch(case: &str, names: &[&str]) -> common::Scratch {
    let d = common::Scratch::new(&format!("rigtwin-robust-{}-{case}", std::process::id()));
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
    usage_refused(&d, &["parametrise", "v1_sweep_b.toml", "--samples", "1000000000"], &["--samples", "100000"]);
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

// ---- The second hostile pass: each case as it was reported, with its time limit, exit code,
// message and what is left on disk.

const GEAR: [&str; 2] = ["bench_gear.toml", "bench_gear.csv"];

/// A drive test of `n` bodies in a chain on the example gear bench's record.
fn chain_of(d: &Path, name: &str, n: usize) {
    let bodies: Vec<String> = (0..n).map(|i| format!("  {{ name = \"b{i}\", inertia = 0.01 }}")).collect();
    let couplings: Vec<String> = (1..n).map(|_| "  { stiffness = 800.0, damping = 0.02 }".to_string()).collect();
    std::fs::write(
        d.join(name),
        format!(
            "kind = \"drive_test\"\ndata = \"bench_gear.csv\"\ndomain = \"rotational\"\n[model]\nbodies = [\n{}\n]\n\
             couplings = [\n{}\n]\n[[inputs]]\ncolumn = \"torque_motor_Nm\"\nbody = 1\n[mpc]\ninput_max = [5.0]\n\
             [[outputs]]\ncolumn = \"speed_motor_radps\"\nbody = 1\nquantity = \"speed\"\n",
            bodies.join(",\n"),
            couplings.join(",\n")
        ),
    )
    .unwrap();
}

#[test]
fn an_mdf_group_claiming_records_larger_than_its_file_is_refused() {
    let d = scratch("mdf-record-size", &[]);
    let t: Vec<f64> = (0..2000).map(|k| k as f64 * 1e-3).collect();
    let mut w = falcon_mdf::Mf4Writer::new();
    let g = w.add_group(&t).unwrap();
    for name in ["trq", "n2", "n3"] {
        let v: Vec<f64> = t.iter().map(|t| (t * 37.0).sin()).collect();
        g.add_channel(name, "", &v).unwrap();
    }
    w.write_to_file(d.join("rec.mf4")).unwrap();
    // the channel group block (##CG): after its 24-byte header and its links come the record
    // id (8 bytes), cycle count (8), flags (2), path separator (2), reserved (4), then the
    // record's data bytes (u32): claim 4 GB
    let mut b = std::fs::read(d.join("rec.mf4")).unwrap();
    let cg = b.windows(4).position(|w| w == b"##CG").expect("a channel group block");
    let links = u64::from_le_bytes(b[cg + 16..cg + 24].try_into().unwrap()) as usize;
    let data = cg + 24 + 8 * links;
    b[data + 24..data + 28].copy_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
    std::fs::write(d.join("rec.mf4"), b).unwrap();
    let sweep = std::fs::read_to_string(shared("v1_sweep_b.toml")).unwrap().replace("v1_sweep_b.csv", "rec.mf4")
        + "\n[columns]\ntorque_drive_Nm = { channel = \"trq\", unit = \"Nm\" }\n\
           speed_m2_radps = { channel = \"n2\", unit = \"rad/s\" }\nspeed_m3_radps = { channel = \"n3\", unit = \"rad/s\" }\n";
    std::fs::write(
        d.join("rec.toml"),
        sweep.replace("data = \"rec.mf4\"", "data = \"rec.mf4\"\nsample_rate_hz = 1000.0"),
    )
    .unwrap();
    for cmd in ["check", "diagnose"] {
        refused(&d, &[cmd, "rec.toml"], &["rec.mf4", "4294967280 bytes", "corrupt"]);
    }
}

#[test]
fn a_record_longer_than_rigtwin_takes_is_refused_while_it_is_read() {
    // 10 000 001 rows of the shortest CSV: refused at the row past the bound, with the data
    // segment capped at 1 GiB: the 10 million rows kept as four f64 columns are 320 MB, and a
    // growing vector holds up to twice its length while it grows (a small multiple of it)
    let d = scratch("long-record", &SWEEP);
    let mut csv = b"time_s,torque_drive_Nm,speed_m2_radps,speed_m3_radps\n".to_vec();
    csv.reserve(8 * 10_000_001);
    for _ in 0..10_000_001 {
        csv.extend_from_slice(b"0,0,0,0\n");
    }
    std::fs::write(d.join("v1_sweep_b.csv"), csv).unwrap();
    let r = run_limited(&d, &["check", "v1_sweep_b.toml"], 120, Some(1 << 30));
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    for w in ["v1_sweep_b.csv", "more than 10000000 samples", "at most 10000000"] {
        assert!(r.stderr.contains(w), "`{w}` missing in {}", r.stderr);
    }
}

#[test]
fn a_model_larger_than_the_machine_can_work_is_refused_at_once() {
    let d = scratch("huge-model", &GEAR);
    chain_of(&d, "huge.toml", 10_000);
    for args in [
        &["check", "huge.toml"][..],
        &["diagnose", "huge.toml"],
        &["mpc", "--params", "huge.toml"],
        &["fmu", "--params", "huge.toml", "--out", "o"],
    ] {
        let start = Instant::now();
        refused(&d, args, &["huge.toml", "10000", "at most 32 bodies"]);
        // reading a 10 000-body TOML and refusing it takes milliseconds; 10 s allows a loaded CI
        assert!(start.elapsed() < Duration::from_secs(10), "{args:?} took {:?}", start.elapsed());
    }
    assert!(!d.join("o").exists() || files_in(&d.join("o")).is_empty(), "no FMU written");
    // the largest model accepted is exported at once
    chain_of(&d, "largest.toml", 32);
    let r = run_in(&d, &["fmu", "--params", "largest.toml", "--out", "o"], 60);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}

#[test]
fn csv_lines_without_end_or_with_binary_data_are_refused_in_bounded_memory() {
    let d = scratch("csv-lines", &SWEEP);
    let toml = std::fs::read_to_string(d.join("v1_sweep_b.toml")).unwrap();
    // a 200 MB header without a line break
    let mut long = b"time_s,".to_vec();
    long.resize(200 << 20, b'x');
    std::fs::write(d.join("long.csv"), long).unwrap();
    std::fs::write(d.join("long.toml"), toml.replace("v1_sweep_b.csv", "long.csv")).unwrap();
    // 100 good rows, then 300 MB of NUL bytes
    let csv = std::fs::read_to_string(d.join("v1_sweep_b.csv")).unwrap();
    let mut nul: Vec<u8> = csv.lines().take(101).flat_map(|l| format!("{l}\n").into_bytes()).collect();
    nul.resize(nul.len() + (300 << 20), 0);
    std::fs::write(d.join("nul.csv"), nul).unwrap();
    std::fs::write(d.join("nul.toml"), toml.replace("v1_sweep_b.csv", "nul.csv")).unwrap();
    // the data segment capped at 256 MB: more than the binary needs at rest, less than either
    // file, so a reader that holds a line whole cannot give its message
    let cap = Some(256 << 20);
    for (bundle, words) in
        [("long.toml", ["long.csv:1", "longer than"]), ("nul.toml", ["nul.csv", "line 102: a NUL byte"])]
    {
        let r = run_limited(&d, &["check", bundle], 30, cap);
        assert_eq!(r.code, Some(1), "{bundle}: {}", r.stderr);
        for w in words {
            assert!(r.stderr.contains(w), "{bundle}: `{w}` missing in {}", r.stderr);
        }
    }
}

#[test]
fn contradictory_records_are_refused_not_half_read() {
    let d = scratch("contradictory", &SWEEP);
    // two columns of one name with different data
    let csv = std::fs::read_to_string(d.join("v1_sweep_b.csv")).unwrap();
    let dup: Vec<String> = csv
        .lines()
        .enumerate()
        .map(|(i, l)| if i == 0 { format!("{l},speed_m2_radps") } else { format!("{l},0.0") })
        .collect();
    std::fs::write(d.join("v1_sweep_b.csv"), dup.join("\n") + "\n").unwrap();
    refused(&d, &["check", "v1_sweep_b.toml"], &["v1_sweep_b.csv:1", "`speed_m2_radps` appears 2 times", "[3, 5]"]);
}

#[test]
fn complex_and_corrupt_mat_files_are_refused_in_one_plain_line() {
    let d = scratch("mat", &SWEEP);
    let script = "import numpy as np, scipy.io as s, sys\n\
        t = np.arange(20000) * 1e-3\n\
        s.savemat(sys.argv[1], {'t': t, 'trq': np.sin(t) + 0.5j * np.cos(t), 'n2': np.sin(2 * t), 'n3': np.cos(t)})\n";
    let py = Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/python");
    let ok = Command::new(&py).args(["-c", script, d.join("c.mat").to_str().unwrap()]).status().unwrap().success();
    assert!(ok, "scipy wrote the .mat file");
    let toml = std::fs::read_to_string(d.join("v1_sweep_b.toml"))
        .unwrap()
        .replace("data = \"v1_sweep_b.csv\"", "data = \"c.mat\"\ntime = \"t\"")
        + "\n[columns]\ntorque_drive_Nm = { channel = \"trq\", unit = \"Nm\" }\n\
           speed_m2_radps = { channel = \"n2\", unit = \"rad/s\" }\nspeed_m3_radps = { channel = \"n3\", unit = \"rad/s\" }\n";
    std::fs::write(d.join("c.toml"), toml).unwrap();
    refused(&d, &["check", "c.toml"], &["c.mat", "`trq` is complex"]);
    // a corrupt file: one plain line, no backtrace, no colour codes, no build paths
    let mut b = std::fs::read(d.join("c.mat")).unwrap();
    let n = b.len();
    for (k, v) in b[200..n - 10].iter_mut().enumerate() {
        *v = (k * 7919 % 251) as u8;
    }
    std::fs::write(d.join("c.mat"), b).unwrap();
    let e = refused(&d, &["check", "c.toml"], &["c.mat"]);
    assert_eq!(e.trim_end().lines().count(), 1, "one line:\n{e}");
    assert!(!e.contains('\u{1b}') && !e.contains(".cargo") && !e.contains("backtrace"), "{e}");
}

#[test]
fn outputs_are_checked_together_before_the_first_is_written() {
    let d = scratch("outputs-together", &SWEEP);
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs/paper.toml"), d.join("r.svg")).unwrap();
    std::fs::create_dir_all(d.join("o")).unwrap();
    // a dangling link as an output: the link stays, its target is written
    for (args, link) in [
        (&["diagnose", "v1_sweep_b.toml", "--json", "j.json"][..], "j.json"),
        (&["diagnose", "v1_sweep_b.toml", "--write-model", "m.toml"], "m.toml"),
        (&["diagnose", "v1_sweep_b.toml", "--plot", "p.svg"], "p.svg"),
        (&["mpc", "--duration", "0.2", "--export-qp", "q.json"], "q.json"),
        (&["fmu", "--out", "o"], "o/rigtwin-fmi3.fmu"),
    ] {
        let target = d.join(format!("target-{}", link.replace('/', "-")));
        std::os::unix::fs::symlink(&target, d.join(link)).unwrap();
        let r = run_in(&d, args, 180);
        assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
        assert!(std::fs::symlink_metadata(d.join(link)).unwrap().file_type().is_symlink(), "{link} is still a link");
        assert!(std::fs::metadata(&target).unwrap().len() > 0, "{link}'s target was written");
    }
    // an output named like an input is refused, the input untouched
    std::fs::copy(d.join("v1_sweep_b.toml"), d.join("o/rigtwin-fmi2.fmu")).unwrap();
    let before = std::fs::read(d.join("o/rigtwin-fmi2.fmu")).unwrap();
    refused(&d, &["fmu", "--params", "o/rigtwin-fmi2.fmu", "--out", "o"], &["input", "rigtwin-fmi2.fmu"]);
    assert_eq!(std::fs::read(d.join("o/rigtwin-fmi2.fmu")).unwrap(), before);
    std::fs::write(d.join("o/rigtwin-closed-loop.ssp"), std::fs::read(d.join("r.svg")).unwrap()).unwrap();
    refused(
        &d,
        &["fmu", "--controller", "--plant", "o/rigtwin-closed-loop.ssp", "--out", "o"],
        &["input", "rigtwin-closed-loop.ssp"],
    );
    refused(&d, &["mpc", "--params", "r.svg", "--plot", "r.svg"], &["--plot", "input"]);
    // two options naming one file
    refused(&d, &["diagnose", "v1_sweep_b.toml", "--json", "x", "--write-model", "x"], &["--write-model", "--json"]);
    assert!(!d.join("x").exists());
    // a FIFO as the second FMU: refused before the first is written
    let f = d.join("f");
    std::fs::create_dir_all(&f).unwrap();
    assert!(Command::new("mkfifo").arg(f.join("rigtwin-fmi2.fmu")).status().unwrap().success());
    refused(&d, &["fmu", "--out", "f"], &["rigtwin-fmi2.fmu", "FIFO"]);
    assert_eq!(files_in(&f), ["rigtwin-fmi2.fmu"], "no FMI 3 FMU and no temporary file written");
}

#[test]
fn negative_values_are_refused_by_the_flag_that_took_them() {
    let d = scratch("negative", &SWEEP);
    for (args, flag) in [
        (&["mpc", "--horizon", "-1"][..], "--horizon"),
        (&["mpc", "--duration", "-5"], "--duration"),
        (&["mpc", "--blocks", "-2"], "--blocks"),
        (&["mpc", "--time-limit-us", "-600"], "--time-limit-us"),
        (&["parametrise", "v1_sweep_b.toml", "--samples", "-1"], "--samples"),
        (&["parametrise", "v1_sweep_b.toml", "--sigma-hz", "-0.1"], "--sigma-hz"),
        (&["reduce", "--masses", "-2"], "--masses"),
        (&["design-spring", "--target", "-0.05"], "--target"),
        (&["fmu", "--controller", "--horizon", "-1"], "--horizon"),
    ] {
        usage_refused(&d, args, &[flag, "out of range"]);
    }
    // the same bounds, written with `=`
    usage_refused(&d, &["mpc", "--horizon=-1"], &["--horizon", "out of range"]);
    // a horizon of 0 names the flag, not an empty file name
    let e = usage_refused(&d, &["mpc", "--horizon", "0"], &["--horizon", "from 1 to 200"]);
    assert!(!e.contains("error: :"), "{e}");
}

#[test]
fn a_repeated_bundle_is_named() {
    let d = scratch("repeated", &["variant_V1.toml", "variant_V1.csv"]);
    refused(&d, &["parametrise", "variant_V1.toml", "variant_V1.toml"], &["variant_V1.toml is given twice"]);
    refused(&d, &["parametrise", "variant_V1.toml", "./variant_V1.toml"], &["given twice"]);
}

#[test]
fn an_mpc_that_only_falls_back_says_its_figures_are_not_valid() {
    let d = scratch("fallback", &[]);
    // the longest horizon, sparse, every step free, a 1 µs time limit: no QP is solved in time
    let args = [
        "mpc",
        "--formulation",
        "sparse",
        "--horizon",
        "200",
        "--blocks",
        "0",
        "--duration",
        "0.1",
        "--time-limit-us",
        "1",
        "--json",
    ];
    let r = run_in(&d, &args, 120);
    assert_eq!(r.code, Some(3), "exit code 3 (not valid): {}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["verdict"], "not_valid");
    assert!(v["u0_error"].is_null(), "no u0 error without a checked step: {}", v["u0_error"]);
    assert!(r.stderr.contains("fallback"), "{}", r.stderr);
    // the same run in text says so first
    let r = run_in(&d, &args[..args.len() - 1], 120);
    assert_eq!(r.code, Some(3));
    assert!(r.stdout.starts_with("NOT VALID"), "{}", r.stdout);
    assert!(r.stdout.contains("not checked"), "{}", r.stdout);
}
