//! Memory of reading an MDF 4 record (issue 17: "≤ a small multiple of the channels actually
//! used"). A 50 s, 8-channel, 10 kHz file (one channel group, 36 MB of records) is written with
//! falcon_mdf's writer; `rigtwin check` selects 3 channels of it in a child process whose peak
//! resident memory is read from `wait4`. The selected data are 3 channels + the master time ×
//! 500 000 samples × 8 bytes = 16 MB; a reader that assembles the group's records whole holds
//! at least the 36 MB file on top of that. Alone in this test binary so no other child's peak
//! is mixed in.

mod common;

use std::process::Command;

#[test]
fn an_mdf_record_is_read_in_memory_proportional_to_the_selected_channels() {
    let dir = common::scratch("memory", "mdf");
    let n = 500_000;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
    let mut w = falcon_mdf::Mf4Writer::new();
    let g = w.add_group(&t).unwrap();
    for ch in 0..8 {
        let v: Vec<f64> = t.iter().map(|t| (t * (3.0 + ch as f64)).sin()).collect();
        g.add_channel(&format!("ch{ch}"), if ch == 1 { "rpm" } else { "Nm" }, &v).unwrap();
    }
    w.write_to_file(dir.join("long.mf4")).unwrap();
    let file_mb = std::fs::metadata(dir.join("long.mf4")).unwrap().len() as f64 / 1e6;
    std::fs::write(
        dir.join("b.toml"),
        "kind = \"drive_test\"\ndata = \"long.mf4\"\ndomain = \"rotational\"\n[model]\n\
         bodies = [{ name = \"a\", inertia = 1.0 }]\n[[inputs]]\ncolumn = \"ch0\"\nbody = 1\n\
         [[outputs]]\ncolumn = \"ch1\"\nbody = 1\nquantity = \"speed\"\n\
         [[outputs]]\ncolumn = \"ch5\"\nbody = 1\nquantity = \"speed\"\nunit = \"rad/s\"\n",
    )
    .unwrap();

    // the child's data segment and private mappings (RLIMIT_DATA: the heap, large vectors)
    // are capped at 3× the selected data: the values, one decoded window, the checks'
    // temporaries; an allocation beyond the cap fails and the run exits non-zero
    let selected = 4 * n * 8;
    let cap = 3 * selected as u64;
    let run = |limit: u64| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_rigtwin"));
        cmd.args(["check", dir.join("b.toml").to_str().unwrap()]).stderr(std::process::Stdio::null());
        common::limit_data(&mut cmd, limit);
        cmd.status().unwrap().success()
    };
    let within = run(cap);
    // the cap is not so loose that anything passes: with the file's size as the cap (less than
    // the group's records plus the selected values) the read must fail
    let below = run((file_mb * 1e6 * 0.5) as u64);
    let _ = std::fs::remove_dir_all(&dir);
    println!("file {file_mb:.1} MB, selected {:.1} MB, cap {:.1} MB", selected as f64 / 1e6, cap as f64 / 1e6);
    assert!(within, "rigtwin check did not read 3 of 8 channels within {cap} bytes of data segment");
    assert!(!below, "rigtwin check read the record within half the file's size: the cap test is void");
}
