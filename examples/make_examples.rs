//! Writes the example bundles of `examples/` (`cargo run --release --example make_examples
//! [DIR]`, into DIR instead when given; `tests/examples.rs` checks the shipped files are what it
//! writes):
//! one of each kind a rig hands over, made by rigtwin's own simulator with a known truth, so
//! the README's journeys and the tests run from a clone alone. Seeded: the same files every run.
//!
//! - `sweep/`: a V1 sine sweep of the paper rig whose drive acts 4.0 ms late (a dead time the
//!   declared model lacks), as a MATLAB `.mat` file with the speeds in rpm;
//! - `variants/`: sweeps of V1–V4 at 40 rad/s of a rig whose j_drive is 0.550 kg m² and c_short
//!   1400 N m/rad (the declared model says 0.529 and 1479): what `parametrise` finds;
//! - `bearing/`: two multisine shake tests (5–85 Hz) of an element with K, C and an added mass
//!   of 6 kg; the bundle declares a K–C element;
//! - `gear_bench/`: motor – shaft – hub – 3:1 gear – load with 0.30 N m of Coulomb friction at
//!   the load (not declared), as an MDF 4 file;
//! - `linear_axis/`: a linear-motor axis (12 kg carriage) with 20 N of Coulomb friction (not
//!   declared), as CSV.
//!
//! Every record carries sensor noise from a seeded generator.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::Path;

use plant::rig::DriveEffects;
use plant::{CoulombFriction, Coupling, Domain, DriveModel, Effect, Line, LineBody, Quantity, Variant};

/// A small seeded generator (xorshift) and its normal draws (Box–Muller).
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn normal(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (TAU * self.uniform()).cos()
    }
}

/// A sine sweep from `f0` to `f1` Hz over `n` samples of `dt` s around `offset`, amplitude `a`.
fn sweep(n: usize, dt: f64, f0: f64, f1: f64, offset: f64, a: f64) -> Vec<f64> {
    let t_end = n as f64 * dt;
    (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            offset + a * (TAU * (f0 * t + 0.5 * (f1 - f0) / t_end * t * t)).sin()
        })
        .collect()
}

/// The CSV of `columns` (name, samples), values with 7 significant digits.
fn csv(columns: &[(&str, &[f64])]) -> String {
    let mut s = columns.iter().map(|c| c.0).collect::<Vec<_>>().join(",") + "\n";
    for k in 0..columns[0].1.len() {
        let row: Vec<String> = columns.iter().map(|c| format!("{:.7e}", c.1[k])).collect();
        let _ = writeln!(s, "{}", row.join(","));
    }
    s
}

fn write(path: &Path, text: impl AsRef<[u8]>) {
    std::fs::create_dir_all(path.parent().expect("a folder")).expect("create the folder");
    std::fs::write(path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// The declared [model] of the paper rig as a bundle writes it.
fn model_section(m: &plant::RigParams) -> String {
    format!(
        "[model]  # declared model, reduced to the output side, SI units\nj_m2 = {}\nj_drive = {}\nj_m3 = {}\n\
         c_short = {}\nc_long = {}\nc_delta = {}\nj_m2_delta = {}\nj_m3_delta = {}\nd_short = {}\nd_long = {}\nload_drag = {}\n",
        m.j_m2,
        m.j_drive,
        m.j_m3,
        m.c_short,
        m.c_long(),
        m.c_delta,
        m.j_m2_delta.unwrap_or(m.j_m2),
        m.j_m3_delta.unwrap_or(m.j_m3),
        m.d_short,
        m.d_long,
        m.load_drag
    )
}

fn main() {
    let root = match std::env::args_os().nth(1) {
        Some(dir) => std::path::PathBuf::from(dir),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("examples"),
    };
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let rpm = 60.0 / TAU;

    // --- sweep: V1, 1–30 Hz in 40 s at 1 kHz about 20 N m, a 4.0 ms dead time, speeds in rpm (.mat)
    let declared = plant::paper::rig().model;
    let (n, dt) = (40_000, 1e-3);
    let torque = sweep(n, dt, 1.0, 30.0, 20.0, 15.0);
    let truth = DriveEffects { time_delay_s: 4.0e-3, ..DriveEffects::default() };
    let (w2, w3) =
        plant::record_speeds(&declared, Variant::V1, &truth, &torque, dt, 10.0).expect("the sweep simulates");
    let mut mat = matrw::MatFile::new();
    let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    let speed =
        |w: &[f64], noise: &mut Noise| -> Vec<f64> { w.iter().map(|v| (v + 2e-3 * noise.normal()) * rpm).collect() };
    mat.insert("t", t.clone().into());
    mat.insert("M_drive", torque.iter().map(|v| v + 0.02 * noise.normal()).collect::<Vec<f64>>().into());
    mat.insert("n_M2", speed(&w2, &mut noise).into());
    mat.insert("n_M3", speed(&w3, &mut noise).into());
    std::fs::create_dir_all(root.join("sweep")).expect("folder");
    let mat_path = root.join("sweep/v1_sweep.mat");
    matrw::save_matfile_v7(mat_path.to_str().expect("a UTF-8 path"), mat, true).expect("write the .mat file");
    // the header's 116 bytes of text carry the time of writing: a fixed text instead, so the
    // file is the same every run
    let mut bytes = std::fs::read(&mat_path).expect("read the .mat file back");
    let text = b"MATLAB 5.0 MAT-file, Platform: GLNXA64, Created by rigtwin examples/make_examples.rs";
    bytes[..116].fill(b' ');
    bytes[..text.len()].copy_from_slice(text);
    write(&mat_path, bytes);
    write(
        &root.join("sweep/v1_sweep.toml"),
        format!(
            "# V1 sine sweep 1-30 Hz about 20 N m, recorded in MATLAB (speeds in rpm); made by\n\
             # examples/make_examples.rs with a 4.0 ms dead time of the drive the declared model lacks\n\
             kind = \"torsional_sweep\"\ndata = \"v1_sweep.mat\"\ntime = \"t\"\nvariant = \"V1\"\n\n\
             [columns]\ntorque_drive_Nm = {{ channel = \"M_drive\", unit = \"N.m\" }}\n\
             speed_m2_radps = {{ channel = \"n_M2\", unit = \"rpm\" }}\n\
             speed_m3_radps = {{ channel = \"n_M3\", unit = \"rpm\" }}\n\n{}",
            model_section(&declared)
        ),
    );

    // --- variants: V1–V4 of a rig with j_drive 0.550 and c_short 1400, 1–30 Hz in 30 s at 500 Hz
    let mut truth_rig = declared.clone();
    truth_rig.j_drive = 0.550;
    truth_rig.c_short = 1400.0;
    // the long shaft follows at the declared ratio (eq. 13), as the parametrisation assumes
    truth_rig.c_long = None;
    let (n, dt) = (15_000, 2e-3);
    for v in Variant::ALL {
        let torque = sweep(n, dt, 1.0, 30.0, 40.0, 25.0);
        let (w2, w3) = plant::record_speeds(&truth_rig, v, &DriveEffects::default(), &torque, dt, 40.0)
            .expect("the variant simulates");
        let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
        let m: Vec<f64> = torque.iter().map(|x| x + 0.02 * noise.normal()).collect();
        let s2: Vec<f64> = w2.iter().map(|x| x + 2e-3 * noise.normal()).collect();
        let s3: Vec<f64> = w3.iter().map(|x| x + 2e-3 * noise.normal()).collect();
        let name = format!("variant_{v}");
        write(
            &root.join(format!("variants/{name}.csv")),
            csv(&[("time_s", &t), ("torque_drive_Nm", &m), ("speed_m2_radps", &s2), ("speed_m3_radps", &s3)]),
        );
        write(
            &root.join(format!("variants/{name}.toml")),
            format!(
                "# {v} sine sweep 1-30 Hz about 40 N m for the indirect parametrisation; made by\n\
                 # examples/make_examples.rs with j_drive = 0.550 kg m^2 and c_short = 1400 N m/rad\n\
                 kind = \"torsional_sweep\"\ndata = \"{name}.csv\"\nvariant = \"{v}\"\n\n{}",
                model_section(&declared)
            ),
        );
    }

    // --- bearing: an element with K, C and an added mass on the paper's support, 4 periods of 1 s
    let support = plant::Support { k_x: 3.68e6, k_y: 3.85e6, c_x: 1226.0, c_y: 1313.0, m_x: 18.14, m_y: 18.14 };
    let element = plant::Coefficients {
        k_n_per_m: [[1.2e6, 0.0], [0.0, 1.5e6]],
        c_ns_per_m: [[2600.0, 0.0], [0.0, 2800.0]],
        m_kg: [[6.0, 0.0], [0.0, 6.0]],
    };
    let bearing = plant::BearingModel { element, support, table: None };
    let (fs, periods) = (1000.0, 4usize);
    let n = (fs * periods as f64) as usize;
    let lines: Vec<(f64, f64)> = (5..=85).map(|f| (f as f64, TAU * noise.uniform())).collect();
    for (test, along) in [("x", 0usize), ("y", 1usize)] {
        // mainly along `along`, a tenth across: two independent tests
        let gain = if along == 0 { [1.0, 0.1] } else { [0.1, 1.0] };
        let mut f = [vec![0.0; n], vec![0.0; n]];
        let mut x = [vec![0.0; n], vec![0.0; n]];
        for &(hz, phase) in &lines {
            let w = TAU * hz;
            let force = [
                num_complex::Complex64::from_polar(200.0 * gain[0], phase),
                num_complex::Complex64::from_polar(200.0 * gain[1], phase + 1.3),
            ];
            let g = bearing.flexibility(w).expect("the shaken system is not singular");
            let disp = [g[(0, 0)] * force[0] + g[(0, 1)] * force[1], g[(1, 0)] * force[0] + g[(1, 1)] * force[1]];
            for k in 0..n {
                let e = num_complex::Complex64::from_polar(1.0, w * k as f64 / fs);
                for d in 0..2 {
                    f[d][k] += (force[d] * e).re;
                    x[d][k] += (disp[d] * e).re;
                }
            }
        }
        let t: Vec<f64> = (0..n).map(|k| k as f64 / fs).collect();
        let fx: Vec<f64> = f[0].iter().map(|v| v + 0.5 * noise.normal()).collect();
        let fy: Vec<f64> = f[1].iter().map(|v| v + 0.5 * noise.normal()).collect();
        let dx: Vec<f64> = x[0].iter().map(|v| v + 2e-8 * noise.normal()).collect();
        let dy: Vec<f64> = x[1].iter().map(|v| v + 2e-8 * noise.normal()).collect();
        write(
            &root.join(format!("bearing/shake_{test}.csv")),
            csv(&[("time_s", &t), ("force_x_N", &fx), ("force_y_N", &fy), ("disp_x_m", &dx), ("disp_y_m", &dy)]),
        );
    }
    write(
        &root.join("bearing/shake.toml"),
        "# a bearing element on a soft support, two multisine shake tests 5-85 Hz (4 periods of 1 s);\n\
         # made by examples/make_examples.rs with K = 1.2/1.5 MN/m, C = 2600/2800 N s/m and an added\n\
         # mass of 6 kg, which the declared K-C element lacks\n\
         kind = \"bearing_shake\"\ntests = [\"shake_x.csv\", \"shake_y.csv\"]\nf_min_hz = 5.0\nf_max_hz = 85.0\n\n\
         [support]  # dry-system baseline, SI units\nk_x = 3.68e6\nk_y = 3.85e6\nc_x = 1226.0\nc_y = 1313.0\n\
         m_x = 18.14\nm_y = 18.14\n\n[model]\nstructure = \"KC\"\ncoupling = \"direct\"\n",
    );

    // --- gear bench: 20 s at 1 kHz, a multisine about standstill, friction at the load (MDF 4)
    let line = Line {
        domain: Domain::Rotational,
        bodies: vec![
            LineBody { name: "motor".into(), inertia: 0.004, drag: 2e-4 },
            LineBody { name: "hub".into(), inertia: 0.001, drag: 0.0 },
            LineBody { name: "load".into(), inertia: 0.06, drag: 0.004 },
        ],
        couplings: vec![Coupling::new(900.0, 0.03, 1.0), Coupling::new(15000.0, 0.4, 3.0)],
    };
    let friction = Effect::CoulombFriction(CoulombFriction { body: 2, friction: 0.30, smoothing_speed: 1e-3 });
    let bench = DriveModel { line: line.clone(), inputs: vec![0], effects: vec![friction] };
    let (n, dt) = (20_000, 1e-3);
    let tones: Vec<(f64, f64)> = (0..24).map(|i| (0.3 * 150f64.powf(i as f64 / 23.0), TAU * noise.uniform())).collect();
    let u: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            0.9 * (TAU * 0.15 * t).sin() + tones.iter().map(|(f, p)| 0.08 * (TAU * f * t + p).sin()).sum::<f64>()
        })
        .collect();
    let outputs = [(Quantity::Speed, 0), (Quantity::Speed, 2), (Quantity::CouplingForce, 1)];
    let y = bench.simulate(std::slice::from_ref(&u), dt, 0.0, &outputs).expect("the gear bench simulates");
    let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    // a fixed start time (2026-01-01), so the file is the same every run
    let mut w = falcon_mdf::Mf4Writer::with_start_time_ns(1_767_225_600_000_000_000);
    let g = w.add_group(&t).expect("a channel group");
    let measured =
        |v: &[f64], sd: f64, noise: &mut Noise| -> Vec<f64> { v.iter().map(|x| x + sd * noise.normal()).collect() };
    g.add_channel("Trq_Motor", "Nm", &measured(&u, 0.002, &mut noise)).expect("channel");
    g.add_channel("n_Motor", "rpm", &measured(&y[0], 0.01, &mut noise).iter().map(|v| v * rpm).collect::<Vec<_>>())
        .expect("channel");
    g.add_channel("n_Load", "rpm", &measured(&y[1], 0.003, &mut noise).iter().map(|v| v * rpm).collect::<Vec<_>>())
        .expect("channel");
    g.add_channel("Trq_Gear", "Nm", &measured(&y[2], 0.01, &mut noise)).expect("channel");
    std::fs::create_dir_all(root.join("gear_bench")).expect("folder");
    w.write_to_file(root.join("gear_bench/bench.mf4")).expect("write the MDF file");
    write(
        &root.join("gear_bench/bench.toml"),
        "# motor - shaft - hub - 3:1 gear - load, a multisine about standstill, recorded as MDF 4 (speeds\n\
         # in rpm, the units from the file); made by examples/make_examples.rs with 0.30 N m of Coulomb\n\
         # friction at the load that the declared model lacks\n\
         kind = \"drive_test\"\ndata = \"bench.mf4\"\ndomain = \"rotational\"\n\n[model]\nbodies = [\n\
         \x20 { name = \"motor\", inertia = 0.004, drag = 0.0002 },\n  { name = \"hub\", inertia = 0.001 },\n\
         \x20 { name = \"load\", inertia = 0.06, drag = 0.004 },\n]\ncouplings = [\n\
         \x20 { stiffness = 900.0, damping = 0.03 },\n  { stiffness = 15000.0, damping = 0.4, ratio = 3.0 },\n]\n\n\
         [[inputs]]\ncolumn = \"Trq_Motor\"\nbody = \"motor\"\n\n\
         [[outputs]]\ncolumn = \"n_Motor\"\nbody = \"motor\"\nquantity = \"speed\"\n\n\
         [[outputs]]\ncolumn = \"n_Load\"\nbody = \"load\"\nquantity = \"speed\"\n\n\
         [[outputs]]\ncolumn = \"Trq_Gear\"\ncoupling = 2\nquantity = \"coupling_torque\"\n\n\
         [mpc]\ninput_max = [2.0]  # N m, the motor's limit\n",
    );

    // --- linear axis: 10 s at 1 kHz, force steps and a sine, 20 N of friction (CSV)
    let axis = DriveModel {
        line: Line {
            domain: Domain::Translational,
            bodies: vec![LineBody { name: "carriage".into(), inertia: 12.0, drag: 40.0 }],
            couplings: vec![],
        },
        inputs: vec![0],
        effects: vec![Effect::CoulombFriction(CoulombFriction { body: 0, friction: 20.0, smoothing_speed: 1e-3 })],
    };
    let (n, dt) = (10_000, 1e-3);
    let force: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            let step = if (t % 2.0) < 1.0 { 60.0 } else { -60.0 };
            step + 40.0 * (TAU * 1.7 * t).sin() + 15.0 * (PI * 9.0 * t).sin()
        })
        .collect();
    let y = axis.simulate(std::slice::from_ref(&force), dt, 0.0, &[(Quantity::Speed, 0)]).expect("the axis simulates");
    let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    let f: Vec<f64> = force.iter().map(|v| v + 0.2 * noise.normal()).collect();
    let v: Vec<f64> = y[0].iter().map(|v| v + 5e-4 * noise.normal()).collect();
    write(&root.join("linear_axis/axis.csv"), csv(&[("time_s", &t), ("force_N", &f), ("velocity_mps", &v)]));
    write(
        &root.join("linear_axis/axis.toml"),
        "# a linear-motor axis, force steps and sines; made by examples/make_examples.rs with 20 N of\n\
         # Coulomb friction that the declared model lacks\n\
         kind = \"drive_test\"\ndata = \"axis.csv\"\ndomain = \"translational\"\n\n[model]\nbodies = [\n\
         \x20 { name = \"carriage\", inertia = 12.0, drag = 40.0 },\n]\n\n\
         [[inputs]]\ncolumn = \"force_N\"\nbody = \"carriage\"\n\n\
         [[outputs]]\ncolumn = \"velocity_mps\"\nbody = \"carriage\"\nquantity = \"speed\"\n\n\
         [mpc]\ninput_max = [150.0]  # N, the motor's limit\n",
    );
    println!("wrote the example bundles under {}", root.display());
}
