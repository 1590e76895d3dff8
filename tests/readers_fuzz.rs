//! Property test of the input readers: random and mutated rig files and bundles (TOML and CSV)
//! give a clean error or a valid model and finite data — never a panic. The cases start from
//! the example bundles and the shipped rig file and mutate them: bytes flipped, lines dropped
//! or repeated, numbers replaced by NaN, inf, 1e308, -1, 0 or text, delimiters changed,
//! files truncated. A fixed number of cases per property (see CASES) runs in CI.

mod common;

use std::path::Path;

use proptest::prelude::*;

/// Cases per property: 8 properties × 500 cases = 4000 inputs per run (`.ci/run` prints the
/// count from this line and the list of properties).
const CASES: u32 = 500;

fn shared(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(name)).unwrap()
}

fn scratch() -> common::Scratch {
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    common::scratch("fuzz", &n.to_string())
}

/// One mutation of a text.
#[derive(Debug, Clone)]
enum Mutation {
    FlipByte(usize, u8),
    DropLine(usize),
    RepeatLine(usize),
    Number(usize, &'static str),
    Delimiter(&'static str),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::FlipByte(i, b)),
        any::<usize>().prop_map(Mutation::DropLine),
        any::<usize>().prop_map(Mutation::RepeatLine),
        (
            any::<usize>(),
            prop::sample::select(vec!["NaN", "inf", "-inf", "1e308", "-1", "0", "", "x", "1e-320", "2e200"])
        )
            .prop_map(|(i, v)| Mutation::Number(i, v)),
        prop::sample::select(vec![";", "\t", " ", ",,"]).prop_map(Mutation::Delimiter),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn apply(text: &str, m: &Mutation) -> Vec<u8> {
    let lines: Vec<&str> = text.lines().collect();
    let pick = |i: usize| i % lines.len().max(1);
    match m {
        Mutation::FlipByte(i, b) => {
            let mut bytes = text.as_bytes().to_vec();
            if !bytes.is_empty() {
                let k = i % bytes.len();
                bytes[k] = *b;
            }
            bytes
        }
        Mutation::DropLine(i) => {
            let k = pick(*i);
            lines
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, l)| format!("{l}\n"))
                .collect::<String>()
                .into_bytes()
        }
        Mutation::RepeatLine(i) => {
            let k = pick(*i);
            let mut v: Vec<&str> = lines.clone();
            if !v.is_empty() {
                v.insert(k, lines[k]);
            }
            (v.join("\n") + "\n").into_bytes()
        }
        Mutation::Number(i, value) => {
            // the i-th number-looking token of the text
            let tokens: Vec<(usize, usize)> = {
                let b = text.as_bytes();
                let mut out = Vec::new();
                let mut k = 0;
                while k < b.len() {
                    if b[k].is_ascii_digit() {
                        let s = k;
                        while k < b.len() && (b[k].is_ascii_digit() || b".eE-+".contains(&b[k])) {
                            k += 1;
                        }
                        out.push((s, k));
                    } else {
                        k += 1;
                    }
                }
                out
            };
            if tokens.is_empty() {
                return text.as_bytes().to_vec();
            }
            let (s, e) = tokens[i % tokens.len()];
            format!("{}{value}{}", &text[..s], &text[e..]).into_bytes()
        }
        Mutation::Delimiter(d) => text.replace(',', d).into_bytes(),
        Mutation::Truncate(i) => {
            let bytes = text.as_bytes();
            bytes[..i % (bytes.len() + 1)].to_vec()
        }
    }
}

/// The first `rows` data rows of a CSV (keeps a case fast; the readers still see a full header).
fn head(csv: &str, rows: usize) -> String {
    csv.lines().take(rows + 1).map(|l| format!("{l}\n")).collect()
}

/// The bytes of an MDF 4 file of two channel groups at different rates (falcon_mdf's writer):
/// `n` (rpm) at 1 kHz for 0.3 s, `m` (N·m) at 500 Hz.
fn mdf_base(dir: &Path) -> Vec<u8> {
    let t1: Vec<f64> = (0..300).map(|k| k as f64 * 1e-3).collect();
    let t2: Vec<f64> = (0..150).map(|k| k as f64 * 2e-3).collect();
    let mut w = falcon_mdf::Mf4Writer::new();
    w.add_group(&t1)
        .unwrap()
        .add_channel("n", "rpm", &t1.iter().map(|t| (t * 50.0).sin()).collect::<Vec<f64>>())
        .unwrap();
    w.add_group(&t2)
        .unwrap()
        .add_channel("m", "Nm", &t2.iter().map(|t| (t * 20.0).cos()).collect::<Vec<f64>>())
        .unwrap();
    w.write_to_file(dir.join("base.mf4")).unwrap();
    std::fs::read(dir.join("base.mf4")).unwrap()
}

/// A single-body drive_test reading `m.mf4`: input `m`, output `n` as a speed.
const MDF_BUNDLE: &str = "kind = \"drive_test\"\ndata = \"m.mf4\"\ndomain = \"rotational\"\n[model]\nbodies = [{ name = \"a\", inertia = 1.0 }]\n[[inputs]]\ncolumn = \"m\"\nbody = 1\n[[outputs]]\ncolumn = \"n\"\nbody = 1\nquantity = \"speed\"\n";

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: CASES, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn rig_files_parse_or_are_refused(ms in prop::collection::vec(mutation(), 1..4)) {
        let mut text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs/paper.toml")).unwrap();
        for m in &ms {
            text = String::from_utf8_lossy(&apply(&text, m)).into_owned();
        }
        if let Ok(rig) = modelfile::rig::parse_rig(&text, Path::new("rig.toml")) {
            prop_assert!(rig.model.validate("model").is_ok());
        }
    }

    #[test]
    fn torsional_bundles_load_or_are_refused(
        toml_ms in prop::collection::vec(mutation(), 0..3),
        csv_ms in prop::collection::vec(mutation(), 0..3),
    ) {
        let d = scratch();
        let mut toml = shared("v1_sweep_b.toml");
        for m in &toml_ms {
            toml = String::from_utf8_lossy(&apply(&toml, m)).into_owned();
        }
        let mut csv = head(&shared("v1_sweep_b.csv"), 3000).into_bytes();
        for m in &csv_ms {
            csv = apply(&String::from_utf8_lossy(&csv), m);
        }
        std::fs::write(d.join("v1_sweep_b.toml"), toml).unwrap();
        std::fs::write(d.join("v1_sweep_b.csv"), csv).unwrap();
        if let Ok(b) = rigtwin::bundle::load_torsional(&d.join("v1_sweep_b.toml")) {
            prop_assert!(b.model.validate("model").is_ok());
            prop_assert!(b.sweep.dt_s > 0.0 && b.sweep.dt_s.is_finite());
            prop_assert!(finite(&b.sweep.torque_nm) && finite(&b.sweep.speed_m2_radps) && finite(&b.sweep.speed_m3_radps));
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn bearing_bundles_load_or_are_refused(
        toml_ms in prop::collection::vec(mutation(), 0..3),
        csv_ms in prop::collection::vec(mutation(), 0..2),
    ) {
        let d = scratch();
        let mut toml = shared("sfd_shake.toml");
        for m in &toml_ms {
            toml = String::from_utf8_lossy(&apply(&toml, m)).into_owned();
        }
        let mut x = shared("sfd_shake_x.csv").into_bytes();
        for m in &csv_ms {
            x = apply(&String::from_utf8_lossy(&x), m);
        }
        std::fs::write(d.join("sfd_shake.toml"), toml).unwrap();
        std::fs::write(d.join("sfd_shake_x.csv"), x).unwrap();
        std::fs::write(d.join("sfd_shake_y.csv"), shared("sfd_shake_y.csv")).unwrap();
        if let Ok(b) = rigtwin::bundle::load_bearing(&d.join("sfd_shake.toml")) {
            for t in &b.tests {
                prop_assert!(finite(&t.force_x_n) && finite(&t.force_y_n) && finite(&t.disp_x_m) && finite(&t.disp_y_m));
            }
            prop_assert!(b.band_hz.1 > b.band_hz.0);
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn mat_files_read_or_are_refused(flips in prop::collection::vec((any::<usize>(), any::<u8>()), 1..6), cut in any::<usize>(), compress in any::<bool>()) {
        // a .mat file written by matrw (v7, compressed or not), then damaged
        let d = scratch();
        let base = d.join("base.mat");
        let n = 200;
        let mut mat = matrw::MatFile::new();
        mat.insert("t", matrw::matvar!((0..n).map(|k| k as f64 * 1e-3).collect::<Vec<f64>>()));
        mat.insert("x", matrw::matvar!((0..n).map(|k| (k as f64).sin()).collect::<Vec<f64>>()));
        matrw::save_matfile_v7(base.to_str().unwrap(), mat, compress).unwrap();
        let mut bytes = std::fs::read(&base).unwrap();
        for (i, b) in &flips {
            let k = 128 + i % (bytes.len() - 128);
            bytes[k] = *b;
        }
        bytes.truncate(128 + cut % (bytes.len() - 127));
        std::fs::write(d.join("m.mat"), &bytes).unwrap();
        if let Ok(cols) = rigtwin::bundle::read_mat(&d.join("m.mat"), &["t", "x"]) {
            prop_assert_eq!(cols[0].len(), cols[1].len());
            prop_assert!(finite(&cols[0]) && finite(&cols[1]));
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn mdf_files_read_or_are_refused(flips in prop::collection::vec((any::<usize>(), any::<u8>()), 1..6), cut in any::<usize>()) {
        // an MDF 4 file of two channel groups at different rates (falcon_mdf's writer), damaged
        let d = scratch();
        let mut bytes = mdf_base(&d);
        for (i, b) in &flips {
            let k = 64 + i % (bytes.len() - 64);
            bytes[k] = *b;
        }
        bytes.truncate(64 + cut % (bytes.len() - 63));
        std::fs::write(d.join("m.mf4"), &bytes).unwrap();
        let bundle = MDF_BUNDLE;
        std::fs::write(d.join("b.toml"), bundle).unwrap();
        if let Ok(b) = rigtwin::bundle::load_drive_test(&d.join("b.toml")) {
            prop_assert!(finite(&b.input_data[0]) && finite(&b.output_data[0]));
            prop_assert!(b.dt_s > 0.0);
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn drive_models_and_tests_load_or_are_refused(
        toml_ms in prop::collection::vec(mutation(), 0..4),
        as_model in any::<bool>(),
    ) {
        let d = scratch();
        let mut toml = shared("bench_gear.toml");
        if as_model {
            toml = toml.replace("kind = \"drive_test\"", "kind = \"drive_model\"").replace("data = \"bench_gear.csv\"\n", "");
        }
        for m in &toml_ms {
            toml = String::from_utf8_lossy(&apply(&toml, m)).into_owned();
        }
        std::fs::write(d.join("b.toml"), toml).unwrap();
        std::fs::write(d.join("bench_gear.csv"), head(&shared("bench_gear.csv"), 2000)).unwrap();
        if let Ok(m) = modelfile::drive::load_drive_model(&d.join("b.toml")) {
            prop_assert!(m.validate().is_ok());
            prop_assert!(m.line.bodies.len() <= plant::MAX_BODIES);
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn fmu_state_bytes_deserialise_or_are_refused(
        flips in prop::collection::vec((any::<usize>(), any::<u8>()), 1..6),
        cut in any::<usize>(),
    ) {
        let bytes = state_bytes();
        let mut b = bytes.to_vec();
        for (i, v) in &flips {
            let n = b.len();
            b[i % n] = *v;
        }
        if cut % 4 == 0 {
            b.truncate(cut % (bytes.len() + 1));
        }
        // a state is either refused or of the declared shape with every value finite: set on
        // an instance of the FMU it claims to be from, it gives finite outputs or is refused
        if let Ok(s) = rigtwin_fmu::instance::Snapshot::from_bytes(&b) {
            let mut i = state_instance();
            if i.restore(&s).is_ok() {
                let t = i.table().clone();
                for v in t.variables.iter().filter(|v| v.name.starts_with("w_")) {
                    let mut out = [0.0];
                    if i.get_f64(&[v.vr], &mut out).is_ok() {
                        prop_assert!(out[0].is_finite());
                    }
                }
            }
        }
    }

    #[test]
    fn random_bytes_are_refused_cleanly(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let d = scratch();
        std::fs::write(d.join("b.toml"), &bytes).unwrap();
        prop_assert!(rigtwin::bundle::load_torsional(&d.join("b.toml")).is_err());
        prop_assert!(rigtwin::bundle::load_bearing(&d.join("b.toml")).is_err());
        let text = String::from_utf8_lossy(&bytes);
        let _ = modelfile::rig::parse_rig(&text, Path::new("b.toml"));
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// A default FMU instance for the state property.
fn state_instance() -> rigtwin_fmu::instance::Instance {
    struct Quiet;
    impl rigtwin_fmu::instance::Logger for Quiet {
        fn log(&self, _: rigtwin_fmu::instance::Status, _: &str, _: &str) {}
    }
    let p = rigtwin_fmu::FmuParams::default();
    rigtwin_fmu::instance::Instance::new(
        "fuzz",
        rigtwin_fmu::instance::Interface::CoSimulation,
        Box::new(Quiet),
        false,
        &p,
    )
}

/// The serialized state of a default instance after initialisation and a few driven steps.
fn state_bytes() -> &'static [u8] {
    static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    BYTES.get_or_init(|| {
        let mut i = state_instance();
        i.enter_initialization_mode(0.0, None).unwrap();
        i.exit_initialization_mode().unwrap();
        let drive = i.table().variables.iter().find(|v| v.name == "M_drive").unwrap().vr;
        for k in 0..10 {
            i.set_f64(&[drive], &[20.0 * (k as f64 * 0.4).sin()]).unwrap();
            i.do_step(k as f64 * 1e-3, 1e-3).unwrap();
        }
        i.snapshot().to_bytes()
    })
}

/// The undamaged base file of `mdf_files_read_or_are_refused` loads, resampled onto 1 kHz: the
/// property's cases start from a file the reader accepts.
#[test]
fn the_fuzzed_mdf_base_file_loads() {
    let d = scratch();
    std::fs::write(d.join("m.mf4"), mdf_base(&d)).unwrap();
    let bundle = MDF_BUNDLE;
    std::fs::write(d.join("b.toml"), bundle).unwrap();
    let b = rigtwin::bundle::load_drive_test(&d.join("b.toml")).unwrap();
    assert!((b.dt_s - 1e-3).abs() < 1e-12);
    // the common interval 0 … 0.298 s at 1 kHz
    assert_eq!(b.output_data[0].len(), 299);
    // rpm → rad/s, and the torque interpolated between its 2 ms samples
    assert!((b.output_data[0][100] - (0.1f64 * 50.0).sin() * 2.0 * std::f64::consts::PI / 60.0).abs() < 1e-12);
    let mid = 0.5 * ((0.100f64 * 20.0).cos() + (0.102f64 * 20.0).cos());
    assert!((b.input_data[0][101] - mid).abs() < 1e-12, "{} vs {mid}", b.input_data[0][101]);
}

/// Offsets of every block of `id` ("##DG", …) in an MDF 4 file's bytes.
fn blocks(bytes: &[u8], id: &[u8; 4]) -> Vec<usize> {
    bytes.windows(4).enumerate().filter(|(_, w)| *w == id).map(|(k, _)| k).collect()
}

fn put_u64(bytes: &mut [u8], at: usize, v: u64) {
    bytes[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

/// Hostile MDF 4 files made from the base file by hand — data groups linking in a loop, a link
/// far outside the file, a data block claiming 200 GB — are refused with an error naming the
/// file, within 10 s, without allocating what they claim (the test process would be killed
/// long before 200 GB); a channel group claiming 10¹² records is read as the records its data
/// block holds (falcon_mdf takes the data's size as the authority over the claimed count).
#[test]
fn hostile_mdf_files_are_refused_in_bounded_time() {
    let d = scratch();
    let base = mdf_base(&d);
    let dg = blocks(&base, b"##DG");
    let cg = blocks(&base, b"##CG");
    let dt = blocks(&base, b"##DT");
    assert!(!dg.is_empty() && !cg.is_empty() && !dt.is_empty(), "the base file has DG, CG and DT blocks");
    let mut cases: Vec<(&str, Vec<u8>)> = Vec::new();
    // DG: header (24 bytes), then dg_dg_next as its first link
    let mut b = base.clone();
    put_u64(&mut b, dg[0] + 24, dg[0] as u64);
    cases.push(("a data group linking to itself", b));
    let mut b = base.clone();
    if dg.len() > 1 {
        put_u64(&mut b, dg[1] + 24, dg[0] as u64);
    }
    cases.push(("two data groups linking to each other", b));
    // HD at 64: its first link is the first data group
    let mut b = base.clone();
    put_u64(&mut b, 64 + 24, 1 << 50);
    cases.push(("a link far outside the file", b));
    // a block's length at +8
    let mut b = base.clone();
    put_u64(&mut b, dt[0] + 8, 200_000_000_000);
    cases.push(("a data block claiming 200 GB", b));
    // CG: after the header and its links, cg_record_id then cg_cycle_count
    let mut b = base.clone();
    let links = u64::from_le_bytes(base[cg[0] + 16..cg[0] + 24].try_into().unwrap()) as usize;
    put_u64(&mut b, cg[0] + 24 + 8 * links + 8, 1_000_000_000_000);
    cases.push(("a channel group claiming 10^12 records", b));
    for (what, bytes) in cases {
        let claims_records = what.contains("10^12");
        let dir = d.join(what.replace(' ', "_"));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("m.mf4"), &bytes).unwrap();
        std::fs::write(dir.join("b.toml"), MDF_BUNDLE).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let file = dir.join("b.toml");
        std::thread::spawn(move || {
            let _ = tx.send(rigtwin::bundle::load_drive_test(&file).map(|b| b.input_data[0].len()));
        });
        match rx.recv_timeout(std::time::Duration::from_secs(10)) {
            Ok(Ok(n)) if claims_records => assert_eq!(n, 299, "{what}: the records the data holds"),
            Ok(Ok(n)) => panic!("{what}: read as {n} samples"),
            Ok(Err(e)) => {
                let msg = e.to_string();
                assert!(msg.contains("m.mf4"), "{what}: the error names the file: {msg}");
                eprintln!("{what}: {msg}");
            }
            Err(_) => panic!("{what}: no answer within 10 s"),
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}
