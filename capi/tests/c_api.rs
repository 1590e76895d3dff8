//! The C API from C: `tests/c/replay.c` is compiled against `include/rigtwin_mpc.h` and linked
//! once with the static and once with the shared library; it replays the measurements and
//! references of a Rust closed loop — `rigtwin mpc`'s controller (`mpc::Controller` on the
//! model's prediction) on the rig with a dead time and on a geared drive model, each as its FMU
//! integrates it — and must command the same. It also checks the API's refusals (a missing
//! file named, NULL, NaN).

use std::path::{Path, PathBuf};
use std::process::Command;

use mpc::closed_loop::{steady_spin, Plant};
use mpc::{Controller, MpcSettings};

/// target/<profile>, where cargo puts this crate's static and shared library: `cargo test`
/// builds only the rlib the tests link, so the libraries a C program links are built here (in
/// the same target directory and profile). The build selects the whole workspace with its tests,
/// as `cargo test --workspace` does: a build of this package alone unifies its dependencies'
/// features differently and would compile the tree again.
fn library_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().unwrap().parent().unwrap().to_path_buf();
    let profile = dir.file_name().unwrap().to_str().unwrap().to_string();
    let target = dir.parent().unwrap();
    let mut cmd = Command::new(env!("CARGO"));
    cmd.args(["build", "--quiet", "--workspace", "--lib", "--tests", "--target-dir"]).arg(target);
    match profile.as_str() {
        "debug" => {}
        "release" => {
            cmd.arg("--release");
        }
        other => {
            cmd.args(["--profile", other]);
        }
    }
    let out = cmd.output().unwrap();
    assert!(out.status.success(), "cargo build -p rigtwin-mpc: {}", String::from_utf8_lossy(&out.stderr));
    dir
}

fn compile(out: &Path, link: &[&str]) {
    compile_source("tests/c/replay.c", out, link);
}

/// Compiles the C file `source` (relative to capi/) against the header, linking `link`.
fn compile_source(source: &str, out: &Path, link: &[&str]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let status = Command::new("cc")
        .arg("-std=c99")
        .arg("-Wall")
        .arg("-Werror")
        .arg("-I")
        .arg(root.join("include"))
        .arg(root.join(source))
        .arg("-o")
        .arg(out)
        .args(link)
        .output()
        .expect("a C compiler `cc`");
    assert!(status.status.success(), "cc: {}", String::from_utf8_lossy(&status.stderr));
}

/// A Rust closed loop's record: the operating speed, then per step the measurements (in the
/// C API's order: the measured outputs in model output order) and the references it gave its
/// controller, and the commands the controller returned.
struct Record {
    speed: f64,
    rows: Vec<(Vec<f64>, Vec<f64>)>,
    commands: Vec<Vec<f64>>,
}

impl Record {
    fn text(&self) -> String {
        let mut t = format!("{}\n", self.speed);
        for (m, r) in &self.rows {
            let all: Vec<String> = m.iter().chain(r).map(|v| format!("{v:.17e}")).collect();
            t += &(all.join(" ") + "\n");
        }
        t
    }
}

/// The measured outputs' indices in model output order, as the C API lists them.
fn measured(p: &mpc::Prediction, settings: &MpcSettings) -> Vec<usize> {
    (0..p.model.output_names.len())
        .filter(|&j| settings.outputs.iter().any(|o| o.name == p.model.output_names[j] && o.noise_std.is_some()))
        .collect()
}

/// 300 steps of `c` on `plant` from `speed` with the references `reference(k)`: the record of
/// the outputs `picked` and the commands (every solve must succeed).
fn close_loop(
    c: &mut Controller,
    plant: &mut impl Plant,
    picked: &[usize],
    speed: f64,
    reference: impl Fn(usize) -> Vec<f64>,
) -> Record {
    let mut record = Record { speed, rows: Vec::new(), commands: Vec::new() };
    for k in 0..300 {
        let y = plant.outputs().to_vec();
        let r = reference(k);
        let (u, info) = c.step(&y, &r);
        assert!(!info.fallback);
        let u = u.to_vec();
        record.rows.push((picked.iter().map(|&j| y[j]).collect(), r));
        record.commands.push(u.clone());
        plant.advance(&u).unwrap();
    }
    record
}

/// Runs the C program on `model` and `record` with both libraries: it names `names` and
/// commands what the Rust loop commanded, to round-off.
fn replay_in_c(dir: &Path, model: &Path, record: &Record, names: &str) {
    let record_file = dir.join("record.txt");
    std::fs::write(&record_file, record.text()).unwrap();
    let lib = library_dir();
    let stat = dir.join("replay_static");
    compile(&stat, &[lib.join("librigtwin_mpc.a").to_str().unwrap(), "-lm", "-lpthread", "-ldl"]);
    let shared = dir.join("replay_shared");
    let rpath = format!("-Wl,-rpath,{}", lib.display());
    compile(&shared, &["-L", lib.to_str().unwrap(), "-lrigtwin_mpc", &rpath, "-lm"]);
    for exe in [stat, shared] {
        let out = Command::new(&exe).arg(model).arg(&record_file).output().unwrap();
        assert!(
            out.status.success(),
            "{}: exit {:?}: {}",
            exe.display(),
            out.status.code(),
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(names));
        let rows: Vec<Vec<f64>> = lines.map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect()).collect();
        assert_eq!(rows.len(), record.commands.len());
        let mut worst: f64 = 0.0;
        for (row, u) in rows.iter().zip(&record.commands) {
            assert_eq!(row[u.len()], 0.0, "status {} (0 = OK)", row[u.len()]);
            for j in 0..u.len() {
                worst = worst.max((row[j] - u[j]).abs());
            }
        }
        // the same code on the same numbers: equal to round-off (the record is printed with
        // 17 digits, so the C side sees the Rust side's doubles exactly)
        assert!(worst < 1e-9, "{}: commands differ by up to {worst:e}", exe.display());
    }
}

#[test]
fn c_program_commands_what_the_rust_loop_commands() {
    let dir = std::env::temp_dir().join(format!("rigtwin-capi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // the paper rig with a 4.3 ms dead time of the drive torque: input-delay states in the
    // prediction, a split sample in the plant
    let rig = dir.join("rig.toml");
    let paper = include_str!("../../rigs/paper.toml");
    std::fs::write(&rig, format!("{paper}\n[effects]\ntime_delay_s = 0.0043\n")).unwrap();

    // the Rust closed loop, assembled as `rigtwin mpc` assembles it
    let modelfile::Model::Rig(params) = modelfile::read(&rig).unwrap().model else { panic!("a rig file") };
    let design = mpc::Design::Rig { rig: &params.model, variant: params.variant, effects: &params.effects };
    let p = design.prediction(1e-3).unwrap();
    let mut settings = MpcSettings::powertrain(50);
    settings.solver.time_limit_s = 1.0;
    let mut c = Controller::with_input_delays(&p.model, &p.input_delays_s, &settings).unwrap();
    let speed = 10.0;
    let (x0, u0) = steady_spin(&p.model, speed).unwrap();
    c.reset(&x0, &u0);
    let mut plant = mpc::DrivePlant::paper_rig(
        &params.model,
        params.variant,
        &params.effects,
        settings.dt_s,
        speed,
        &u0,
        &p.model.output_names,
    )
    .unwrap();
    let picked = measured(&p, &settings);
    let record =
        close_loop(&mut c, &mut plant, &picked, speed, |k| vec![speed, speed, if k >= 50 { 40.0 } else { 0.0 }]);
    let step = record.commands.iter().map(|u| u[1]).fold(0.0f64, f64::max);
    assert!(step > 30.0, "the drive torque followed its step ({step} Nm)");
    replay_in_c(
        &dir,
        &rig,
        &record,
        "measured: w_m2 w_drive w_m3 | references: w_m2 w_m3 M_drive | commands: M_m2 M_drive M_m3",
    );
}

/// The drive model `file` (relative to the repository) closed in Rust as `rigtwin mpc --params`
/// closes it — its prediction and `[mpc]` settings, the plant integrated as its FMU integrates
/// it, from rest, the references `reference(k)` — and replayed through the C program, which
/// must name `names` and command the same; the Rust loop's record.
fn drive_model_in_c(file: &str, case: &str, names: &str, reference: impl Fn(usize) -> Vec<f64>) -> Record {
    let dir = std::env::temp_dir().join(format!("rigtwin-capi-{case}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(file);
    let read = modelfile::read(&path).unwrap();
    let modelfile::Model::Drive(model) = &read.model else { panic!("a drive model") };
    let (p, mut settings) = mpc::Design::Drive(model).controller(&read.mpc, 50).unwrap();
    settings.solver.time_limit_s = 1.0;
    let mut c = Controller::with_input_delays(&p.model, &p.input_delays_s, &settings).unwrap();
    c.reset(&nalgebra::DVector::zeros(p.model.nstates()), &vec![0.0; p.model.input_names.len()]);
    let mut plant = mpc::DrivePlant::new(model, settings.dt_s, &p.model.output_names).unwrap();
    let picked = measured(&p, &settings);
    let record = close_loop(&mut c, &mut plant, &picked, 0.0, reference);
    replay_in_c(&dir, &path, &record, names);
    record
}

/// A drive model through the same API: the gear bench example (motor – shaft – hub – 3:1 gear –
/// load, its `[mpc]` section bounding the motor torque at 2 N·m), the load speed's reference
/// stepping to 10 rad/s at 50 ms.
#[test]
fn c_program_controls_a_drive_model_as_the_rust_loop_does() {
    let record = drive_model_in_c(
        "examples/gear_bench/bench.toml",
        "bench",
        "measured: w_motor w_hub w_load | references: w_load | commands: M_motor",
        |k| vec![if k >= 50 { 10.0 } else { 0.0 }],
    );
    // the motor pushes the load towards its new speed, within its 2 N·m bound
    let peak = record.commands.iter().map(|u| u[0]).fold(0.0f64, f64::max);
    assert!(peak > 0.5 && peak <= 2.0 + 1e-9, "motor torque peak {peak} N m");
}

/// The branched gearbox drawn with its gears (`rigs/branched_gearbox.toml`: a pinion meshing two
/// wheels, the meshes' modes at 1.4 and 2.5 kHz left out of the prediction), two inputs: load
/// a's speed steps to 10 rad/s at 50 ms while load b's brake follows a 5 N·m torque reference.
#[test]
fn c_program_controls_a_branched_gearbox_as_the_rust_loop_does() {
    let record = drive_model_in_c(
        "rigs/branched_gearbox.toml",
        "gearbox",
        "measured: w_motor w_pinion w_wheel_a w_load_a w_wheel_b w_load_b | references: w_load_a M_load_b | commands: M_motor M_load_b",
        |k| vec![if k >= 50 { 10.0 } else { 0.0 }, 5.0],
    );
    let last = record.commands.last().unwrap();
    assert!((last[1] - 5.0).abs() < 0.5, "the brake follows its 5 N m reference: {last:?}");
    assert!(record.rows.last().unwrap().0[3] > 5.0, "load a follows its step");
}

/// The Rust side of the boundary: NULL, a bad file and a NaN are refused with statuses and
/// messages, never a panic.
#[test]
fn refusals_at_the_boundary() {
    use rigtwin_mpc::*;
    let mut err = vec![0 as std::ffi::c_char; 256];
    let path = std::ffi::CString::new("/nonexistent/rig.toml").unwrap();
    // SAFETY: valid pointers and lengths
    let c = unsafe { rigtwin_mpc_create(path.as_ptr(), std::ptr::null(), err.as_mut_ptr(), err.len()) };
    assert!(c.is_null());
    // SAFETY: NUL-terminated by rigtwin_mpc_create
    let msg = unsafe { std::ffi::CStr::from_ptr(err.as_ptr()) }.to_string_lossy().into_owned();
    assert!(msg.contains("/nonexistent/rig.toml"), "{msg}");
    let bad = Options { horizon: 0, ..Options::default() };
    // SAFETY: valid pointers
    let c = unsafe { rigtwin_mpc_create(std::ptr::null(), &bad, err.as_mut_ptr(), err.len()) };
    assert!(c.is_null());
    // SAFETY: as above
    let msg = unsafe { std::ffi::CStr::from_ptr(err.as_ptr()) }.to_string_lossy().into_owned();
    assert!(msg.contains("horizon"), "{msg}");
    // SAFETY: NULL is allowed
    let c = unsafe { rigtwin_mpc_create(std::ptr::null(), std::ptr::null(), std::ptr::null_mut(), 0) };
    assert!(!c.is_null());
    let (m, r, mut t) = ([10.0, 10.0, 10.0], [10.0, 10.0, f64::INFINITY], [0.0; 3]);
    // SAFETY: live controller
    unsafe {
        assert_eq!(rigtwin_mpc_count(c, Signals::Measured as i32), 3);
        let name = std::ffi::CStr::from_ptr(rigtwin_mpc_name(c, Signals::Commands as i32, 1));
        assert_eq!(name.to_str().unwrap(), "M_drive");
        assert!(rigtwin_mpc_name(c, Signals::Commands as i32, 3).is_null());
    }
    // SAFETY: live controller, arrays of 3
    unsafe {
        assert_eq!(rigtwin_mpc_reset(c, 10.0), Status::Ok);
        assert_eq!(rigtwin_mpc_reset(c, f64::NAN), Status::BadInput);
        assert_eq!(rigtwin_mpc_step(c, m.as_ptr(), r.as_ptr(), t.as_mut_ptr()), Status::BadInput);
        assert!(t.iter().all(|v| v.is_finite()));
        assert_eq!(rigtwin_mpc_step(c, m.as_ptr(), std::ptr::null(), t.as_mut_ptr()), Status::Invalid);
        rigtwin_mpc_free(c);
    }
}

/// The example program users start from (capi/examples/minimal.c) builds with the lines it gives
/// and runs: a drive-torque step commands a drive torque towards the 40 N·m reference.
#[test]
fn the_minimal_c_example_builds_and_runs() {
    let dir = std::env::temp_dir().join(format!("rigtwin-capi-minimal-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lib = library_dir();
    let exe = dir.join("minimal");
    compile_source(
        "examples/minimal.c",
        &exe,
        &[lib.join("librigtwin_mpc.a").to_str().unwrap(), "-lm", "-lpthread", "-ldl"],
    );
    let out = Command::new(&exe).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    let drive: f64 = text
        .split("M_drive = ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no drive torque in {text}"));
    assert!(drive > 0.0 && drive.is_finite(), "the drive torque moves towards its reference: {text}");
}

/// Operating points of a geared line: `rigtwin_mpc_reset(c, 10)` on the gear bench (3:1 between
/// hub and load) starts the motor and hub at 10 rad/s and the load at 10/3 rad/s, held by the
/// motor against the drags — 0.0002·10 + 0.004·(10/3)/3 = 0.006444 N·m, worked out by hand from
/// the file's drags — so the first step at that state and reference commands it (to the QP's
/// tolerance); a line held by a spring to ground has no free motion: only 0 is an operating
/// speed.
#[test]
fn a_geared_line_starts_from_its_free_motion() {
    use rigtwin_mpc::*;
    let bench = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/gear_bench/bench.toml");
    let path = std::ffi::CString::new(bench.to_str().unwrap()).unwrap();
    let mut err = vec![0 as std::ffi::c_char; 512];
    // SAFETY: valid pointers and lengths
    let c = unsafe { rigtwin_mpc_create(path.as_ptr(), std::ptr::null(), err.as_mut_ptr(), err.len()) };
    assert!(!c.is_null());
    let (m, r, mut u) = ([10.0, 10.0, 10.0 / 3.0], [10.0 / 3.0], [0.0]);
    // SAFETY: a live controller, arrays of its counts (3 measured, 1 reference, 1 command)
    unsafe {
        assert_eq!(rigtwin_mpc_reset(c, 10.0), Status::Ok);
        for _ in 0..5 {
            assert_eq!(rigtwin_mpc_step(c, m.as_ptr(), r.as_ptr(), u.as_mut_ptr()), Status::Ok);
            assert!((u[0] - (0.0002 * 10.0 + 0.004 * (10.0 / 3.0) / 3.0)).abs() < 1e-6, "{u:?}");
        }
        rigtwin_mpc_free(c);
    }
    let dir = std::env::temp_dir().join(format!("rigtwin-capi-ground-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let grounded = dir.join("grounded.toml");
    let text = std::fs::read_to_string(&bench).unwrap().replace(
        "  { stiffness = 15000.0, damping = 0.4, ratio = 3.0 },\n",
        "  { stiffness = 15000.0, damping = 0.4, ratio = 3.0 },\n  { between = [\"load\"], stiffness = 50.0 },\n",
    );
    // a constant torque on a grounded line only deflects it: the ground spring's force is
    // measured, so that the input disturbance can be estimated, and tracked (a speed has no
    // steady state other than 0)
    let text = text.replace(
        "[mpc]\n",
        "[mpc]\nmeasured = [\"w_motor\", \"w_load\", \"T_coupling_3\"]\ntracked = [\"T_coupling_3\"]\n",
    );
    assert!(text.contains("between") && text.contains("T_coupling_3"));
    std::fs::write(&grounded, text).unwrap();
    let path = std::ffi::CString::new(grounded.to_str().unwrap()).unwrap();
    // SAFETY: as above
    unsafe {
        let c = rigtwin_mpc_create(path.as_ptr(), std::ptr::null(), err.as_mut_ptr(), err.len());
        assert!(!c.is_null(), "{}", std::ffi::CStr::from_ptr(err.as_ptr()).to_string_lossy());
        assert_eq!(rigtwin_mpc_reset(c, 0.0), Status::Ok);
        assert_eq!(rigtwin_mpc_reset(c, 5.0), Status::BadInput);
        rigtwin_mpc_free(c);
    }
}
