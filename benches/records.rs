//! Reading a long MDF 4 record: 200 s of 8 channels at 10 kHz (16 M samples, written here with
//! falcon_mdf's writer into one channel group), three of them selected by a drive_test bundle —
//! the whole load: decoding, unit conversion, the uniform-time, glitch and sampling checks.

use criterion::{criterion_group, criterion_main, Criterion};

fn record(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("rigtwin-bench-records-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = 2_000_000;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
    let mut w = falcon_mdf::Mf4Writer::new();
    let g = w.add_group(&t).unwrap();
    for ch in 0..8 {
        let v: Vec<f64> = t.iter().map(|t| (t * (3.0 + ch as f64)).sin() + 0.01 * ch as f64).collect();
        g.add_channel(&format!("ch{ch}"), if ch == 1 { "rpm" } else { "Nm" }, &v).unwrap();
    }
    w.write_to_file(dir.join("long.mf4")).unwrap();
    let bundle = "kind = \"drive_test\"\ndata = \"long.mf4\"\ndomain = \"rotational\"\n[model]\nbodies = [{ name = \"a\", inertia = 1.0 }]\n[[inputs]]\ncolumn = \"ch0\"\nbody = 1\n[[outputs]]\ncolumn = \"ch1\"\nbody = 1\nquantity = \"speed\"\n[[outputs]]\ncolumn = \"ch5\"\nbody = 1\nquantity = \"speed\"\nunit = \"rad/s\"\n";
    std::fs::write(dir.join("b.toml"), bundle).unwrap();
    let mut group = c.benchmark_group("records");
    group.sample_size(10);
    group.bench_function("MDF4 200 s x 8 channels at 10 kHz, 3 selected", |b| {
        b.iter(|| rigtwin::bundle::load_drive_test(&dir.join("b.toml")).unwrap())
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, record);
criterion_main!(benches);
