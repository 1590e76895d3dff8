//! Times the whole `drive_test` diagnosis of the real-sized record of
//! `examples/common/line_record.rs` (8 bodies, two gear stages, 2 inputs, 7 outputs, 13 s at
//! 1 kHz) and prints its answer: `cargo run --release -p ident --example diagnose_line`.

#[path = "common/line_record.rs"]
mod common;
#[path = "common/memory.rs"]
mod memory;

use ident::diagnose::drive::{diagnose, DriveRecord};

fn main() {
    let model = common::declared();
    let (inputs, y) = common::record();
    let rec = DriveRecord { model: &model, inputs: &inputs, outputs: &common::OUTPUTS, measured: &y, dt_s: 1e-3 };
    let rss_before = memory::status_kb("VmRSS");
    let start = std::time::Instant::now();
    let d = diagnose(rec, &|c| eprintln!("  {c} at {:.2} s", start.elapsed().as_secs_f64())).expect("diagnosed");
    println!(
        "{:.2} s: {} {:?} error {:.4} -> {:.4}",
        start.elapsed().as_secs_f64(),
        d.effect,
        d.at,
        d.error_before,
        d.error_after
    );
    println!("  {:?}", d.parameters);
    for (k, (m, a)) in d.traces.measured.iter().zip(&d.traces.after).enumerate() {
        let e =
            (m.iter().zip(a).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / m.iter().map(|x| x * x).sum::<f64>()).sqrt();
        println!("  output {k}: error {e:.4}");
    }
    for c in &d.candidates {
        println!("  {} {:?} {:.4}", c.effect, c.at, c.error_after);
    }
    // memory: the process's peak above its size once the record was made (Linux), per sample
    // and channel (2 inputs, 7 outputs)
    memory::print_peak_above(rss_before, inputs[0].len(), inputs.len() + y.len());
}
