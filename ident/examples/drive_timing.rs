//! One-shot timing of the `drive_test` diagnosis on a 60 s, 1 kHz record of a three-body line
//! with three outputs and the whole vocabulary (the criterion bench `cargo bench -p ident --features bench
//! --bench diagnose_drive` repeats it): `cargo run --release -p ident --example drive_timing`.

#[path = "common/drive_record.rs"]
mod common;
#[path = "common/memory.rs"]
mod memory;
use std::time::Instant;

use ident::diagnose::drive::{diagnose, DriveRecord};

fn main() {
    let model = common::declared();
    let (u, y) = common::record(0.3);
    let inputs = [u];
    let rec = DriveRecord { model: &model, inputs: &inputs, outputs: &common::OUTPUTS, measured: &y, dt_s: 1e-3 };
    let rss_before = memory::status_kb("VmRSS");
    let t0 = Instant::now();
    let d = diagnose(rec, &|_| {}).unwrap();
    println!(
        "three bodies, three outputs, friction 0.3 Nm at the load: {:.2} s, found {} at {:?} {:?}, error {:.4} → {:.4}",
        t0.elapsed().as_secs_f64(),
        d.effect,
        d.at,
        d.parameters,
        d.error_before,
        d.error_after
    );
    // memory: the process's peak above its size once the record was made (Linux), per sample
    // and channel (the input and the three outputs)
    memory::print_peak_above(rss_before, inputs[0].len(), inputs.len() + y.len());
}
